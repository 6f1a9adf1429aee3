//! Lighting design on the model, in a real browser against a real coordinator and worker: a
//! calculation grid placed on the paving by two clicks in the view (bad spacings refused in the
//! server's words, in the grids' form), computed on the farm, its figures in the page equal to
//! those `restauro illuminance` prints for the revision downloaded from the studio, and its
//! false-colour map drawn on the model where the grid is, as the command line draws it.
//! Screenshots in `<target>/tmp/studio/`.

use restauro_tests::browser::{Browser, available, png_rgb};
use restauro_tests::{CLIENT_TOKEN, Coordinator, StudioFarm, download_shown, submit, text};
use serde_json::json;
use std::path::{Path, PathBuf};

/// Screenshots go to `<target>/tmp/studio/`.
fn shots() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("studio")
}

/// The studio with the Aosta scene (160 × 90 px) rendered once, open in a browser signed in.
fn opened(d: &Path) -> (StudioFarm, Browser) {
    let farm = Coordinator::studio_farm(d, 160, 90);
    submit(&farm.scene, &["--spp", "1", "--tile", "32"], &farm.coordinator.url, &farm.token);
    let mut b = Browser::launch(1280, 900);
    b.goto(&format!("{}#token={CLIENT_TOKEN}", farm.page));
    b.wait_for("the model", "document.getElementById('view').dataset.revision === '0'");
    (farm, b)
}

fn set_value(b: &mut Browser, id: &str, value: &str) {
    b.eval(&format!(
        "(() => {{ const e = document.getElementById('{id}'); e.value = {value:?}; \
         e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change')); }})()"
    ));
}

/// A click of the mouse at the fraction (`fx`, `fy`) of the view's width and height.
fn click_view_at(b: &mut Browser, fx: f64, fy: f64) {
    let [x, y, w, h] = b.rect("#view");
    let (x, y) = (x + fx * w, y + fy * h);
    for kind in ["mousePressed", "mouseReleased"] {
        b.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1 }),
        );
    }
}

/// Where the scene's point `p` (m, the scene's frame) is drawn: its index in a screenshot
/// `width` device pixels wide, at `ratio` device pixels a CSS pixel.
fn screen_pixel(b: &mut Browser, p: [f64; 3], ratio: f64, width: usize) -> usize {
    let at = b.eval(&format!(
        "(() => {{ const v = window.studioViewer, o = v.view.offset_m; \
         const q = v.camera.position.clone().set({} - o[0], {} - o[2], -({} - o[1])); \
         return v.onScreen(q); }})()",
        p[0], p[2], p[1]
    ));
    let (x, y) = (at[0].as_f64().unwrap() * ratio, at[1].as_f64().unwrap() * ratio);
    y as usize * width + x as usize
}

/// The grids' form shows a refusal naming `field`; the scene stays at `revision`.
fn refused(b: &mut Browser, button: &str, field: &str, revision: &str) {
    b.eval("document.getElementById('grid-error').textContent = ''");
    b.click(button);
    b.wait_for("the refusal", "document.getElementById('grid-error').textContent.length > 0");
    let said = b.eval("document.getElementById('grid-error').textContent");
    assert!(said.as_str().unwrap().contains(field), "{said}");
    assert_eq!(b.eval("document.getElementById('view').dataset.revision"), revision);
}

fn grid_rows(b: &mut Browser) -> Vec<Vec<String>> {
    let rows = b.eval(
        "[...document.querySelectorAll('#grids tbody tr')].map(r => [...r.cells].slice(0, 6).map(c => c.textContent))",
    );
    serde_json::from_value(rows).unwrap()
}

#[test]
fn a_grid_placed_by_clicking_is_computed_as_the_command_line_computes_it() {
    if !available("studio_grids") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b) = opened(d);
    let c = &farm.coordinator;

    // Looking straight down at the paving in front of the facade (y = −7 m, north up).
    b.eval(
        "(() => { const v = window.studioViewer, o = v.view.offset_m; \
         const glb = (x, y, z) => [x - o[0], z - o[2], -(y - o[1])]; \
         v.fly({ position: glb(0, -7, 12), target: glb(0, -7, 0), up: [0, 0, -1], vertical_fov_deg: 40 }); })()",
    );
    b.eval("document.getElementById('view').scrollIntoView({ block: 'nearest' })");
    // Two opposite corners clicked on the paving; the grid 0.85 m above it.
    click_view_at(&mut b, 0.35, 0.3);
    b.wait_for("the first click", "window.studioViewer.picked !== undefined");
    b.click("#grid-first");
    b.wait_for(
        "the first corner",
        "document.getElementById('grid-corners').textContent.startsWith('First corner')",
    );
    click_view_at(&mut b, 0.65, 0.7);
    set_value(&mut b, "grid-name", "work-plane");
    set_value(&mut b, "grid-lift", "0.85");
    // Bad spacings are refused, naming the field, where the grid was placed.
    set_value(&mut b, "grid-spacing", "0");
    refused(&mut b, "#grid-save", "spacing_m", "0");
    set_value(&mut b, "grid-spacing", "NaN");
    refused(&mut b, "#grid-save", "spacing_m", "0");
    set_value(&mut b, "grid-spacing", "0.5");
    b.click("#grid-save");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    let rows = grid_rows(&mut b);
    assert_eq!(rows.len(), 1, "{rows:?}");
    assert_eq!(rows[0][0], "work-plane");
    assert_eq!(b.eval("document.getElementById('grid-error').textContent"), "");
    let before = b.screenshot(&shots().join("50-grid-placed.png"));

    // Computed on the farm, 4 samples a point.
    set_value(&mut b, "grid-spp", "4");
    b.click("#grid-compute");
    b.wait_for(
        "the grids computed",
        "document.getElementById('grid-status').textContent.startsWith('computed')",
    );
    b.wait_for("the map drawn", "document.querySelector('#grid-maps img')?.complete === true");
    let rows = grid_rows(&mut b);
    let caption = b.eval("document.querySelector('#grid-maps figcaption').textContent");

    // The revision downloaded, computed by the command line in its own process.
    let scene = download_shown(&mut b, c, d);
    let out = d.join("cli-illuminance");
    let o = restauro_tests::restauro(&[
        "illuminance",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--spp",
        "4",
        "--in-process",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8(o.stdout).unwrap();
    let line = stdout.lines().find(|l| l.starts_with("work-plane: ")).expect("the grid's line");
    // `work-plane: N points, min A lx, mean B lx, max C lx, uniformity U`.
    let figure = |after: &str| {
        let rest = &line[line.find(after).unwrap() + after.len()..];
        rest.split([' ', ',']).next().unwrap().to_owned()
    };
    let points = line["work-plane: ".len()..].split(' ').next().unwrap().to_owned();
    let cli = [points, figure("min "), figure("mean "), figure("max "), figure("uniformity ")];
    assert_eq!(rows[0][1..], cli, "the page's row, and the command line's: {line}");
    let expected = format!(
        "work-plane: min {} lx, mean {} lx, max {} lx, U0 {}",
        cli[1], cli[2], cli[3], cli[4]
    );
    assert_eq!(caption, expected.as_str(), "{line}");
    let cells: usize = cli[0].parse().unwrap();
    assert!(cells >= 4, "{cells} points");
    assert!(cli[1].parse::<f64>().unwrap() > 0.0, "the sun and sky light the paving: {line}");

    the_map_is_drawn_where_the_grid_is(&mut b, &before, &scene, &out.join("work-plane.png"));
    b.docs_picture(&shots(), "studio-grids.png");

    // Renamed, then deleted.
    set_value(&mut b, "grid-name", "paving");
    b.click("#grids tbody button[aria-label='Rename grid work-plane to the name in the form']");
    b.wait_for("revision 2", "document.getElementById('view').dataset.revision === '2'");
    assert_eq!(grid_rows(&mut b)[0][0], "paving");
    b.click("#grids tbody button[aria-label='Delete grid paving']");
    b.wait_for("revision 3", "document.getElementById('view').dataset.revision === '3'");
    assert!(grid_rows(&mut b).is_empty());
}

/// The view shows the command line's map (`png`, its lux scale below it cut off) over the
/// rectangle the downloaded `scene` places: at points across the rectangle, projected with the
/// view's camera, the screenshot's colour is the map's colour there, and the model's colour
/// (in `before`, the grid not yet computed) is not. Colours agree within 8 of 255 per channel.
fn the_map_is_drawn_where_the_grid_is(b: &mut Browser, before: &[u8], scene: &Path, png: &Path) {
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(scene).unwrap()).unwrap();
    let grid = &toml["grids"].as_array().unwrap()[0];
    let vec3 = |k: &str| -> [f64; 3] {
        let a = grid[k].as_array().unwrap();
        std::array::from_fn(|i| a[i].as_float().or(a[i].as_integer().map(|v| v as f64)).unwrap())
    };
    let (origin, u, v) = (vec3("origin"), vec3("u"), vec3("v"));
    let (map, map_width) = png_rgb(&std::fs::read(png).unwrap());
    let map_height = map.len() / map_width - 36;
    let after = b.screenshot(&shots().join("51-grid-computed.png"));
    let (shot, width) = png_rgb(&after);
    let (old, _) = png_rgb(before);
    let ratio = b.eval("window.devicePixelRatio").as_f64().unwrap();
    let (mut close, mut changed, mut total) = (0, 0, 0);
    for j in 0..10 {
        for i in 0..10 {
            let (s, t) = ((f64::from(i) + 0.5) / 10.0, (f64::from(j) + 0.5) / 10.0);
            let p: [f64; 3] = std::array::from_fn(|k| origin[k] + s * u[k] + t * v[k]);
            let at = screen_pixel(b, p, ratio, width);
            let seen = shot[at];
            let (mx, my) =
                ((s * map_width as f64) as usize, ((1.0 - t) * map_height as f64) as usize);
            let want = map[my * map_width + mx];
            let was = old[at];
            let far = |a: [u8; 3], b: [u8; 3]| {
                (0..3).map(|k| (i32::from(a[k]) - i32::from(b[k])).abs()).max().unwrap()
            };
            total += 1;
            close += usize::from(far(seen, want) <= 8);
            changed += usize::from(far(seen, was) > 16);
        }
    }
    // Drawn upside down or mirrored, fewer than half would (37 and 40 of 100 when this was
    // written); the rest differ by the texture's filtering across an isoline.
    assert!(close >= 85, "{close} of {total} points of the grid show the map's colour there");
    assert!(changed >= 50, "only {changed} of {total} points changed when the map was drawn");
}

/// An area luminaire placed on the facade from the page: a size left out is refused in the
/// server's words, naming the edge; the one saved is in the downloaded `scene.toml` centred
/// 5 cm out of the wall from the point clicked, facing the square, with the width and height
/// given, and it is drawn where it is, as light, over most of its rectangle.
#[test]
fn an_area_luminaire_placed_from_the_page_is_kept_with_its_sizes_and_drawn() {
    if !available("studio_grids") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (farm, mut b) = opened(d);
    b.eval(
        "(() => { const v = window.studioViewer, o = v.view.offset_m; \
         const glb = (x, y, z) => [x - o[0], z - o[2], -(y - o[1])]; \
         v.fly({ position: glb(0, -12, 4), target: glb(0, 0, 4), up: [0, 1, 0], vertical_fov_deg: 50 }); })()",
    );
    click_view_at(&mut b, 0.5, 0.5);
    b.wait_for("the material panel", "!document.getElementById('material').hidden");
    let clicked = b.eval(
        "(() => { const v = window.studioViewer, p = v.picked, o = v.view.offset_m; \
         return [p.x + o[0], -p.z + o[1], p.y + o[2]]; })()",
    );
    let clicked: [f64; 3] = std::array::from_fn(|k| clicked[k].as_f64().unwrap());
    set_value(&mut b, "lum-kind", "area");
    set_value(&mut b, "lum-lift", "0.05");
    b.click("#lum-place");
    set_value(&mut b, "lum-spectrum", "cie:A");
    set_value(&mut b, "lum-luminance", "3000");
    set_value(&mut b, "lum-width", "");
    b.click("#lum-save");
    let problem = b.refusal_beside("#lum-save");
    assert!(problem.contains(".u: an edge of length 0"), "{problem}");
    set_value(&mut b, "lum-width", "1.2");
    set_value(&mut b, "lum-height", "0.6");
    b.click("#lum-save");
    b.wait_for("revision 1", "document.getElementById('view').dataset.revision === '1'");
    let kind = b.eval("document.querySelector('#luminaires tbody tr').cells[1].textContent");
    assert_eq!(kind, "area 1.20 × 0.60 m");

    let scene = download_shown(&mut b, &farm.coordinator, d);
    let toml: toml::Table = toml::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    let area = toml["lights"]
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["kind"].as_str() == Some("area"))
        .expect("the area light in the downloaded scene");
    let vec3 = |k: &str| -> [f64; 3] {
        let a = area[k].as_array().unwrap();
        std::array::from_fn(|i| a[i].as_float().or(a[i].as_integer().map(|v| v as f64)).unwrap())
    };
    let (corner, u, v) = (vec3("corner"), vec3("u"), vec3("v"));
    let length = |e: [f64; 3]| e.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((length(u) - 1.2).abs() < 1e-9 && (length(v) - 0.6).abs() < 1e-9, "{area}");
    assert!((0..3).map(|k| u[k] * v[k]).sum::<f64>().abs() < 1e-9, "u ⟂ v: {area}");
    let centre: [f64; 3] = std::array::from_fn(|k| corner[k] + (u[k] + v[k]) / 2.0);
    // It faces the square (−y), whence the facade was clicked: u × v points south; its centre
    // is 5 cm out of the wall from the point clicked.
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    assert!(-n[1] / length(n) > 0.9, "it emits towards {n:?}: {area}");
    let out: [f64; 3] = std::array::from_fn(|k| clicked[k] + 0.05 * n[k] / length(n));
    assert!((0..3).all(|k| (centre[k] - out[k]).abs() < 1e-6), "{centre:?} {out:?}");
    let luminance = &area["luminance_cd_m2"];
    assert_eq!(luminance.as_float().or(luminance.as_integer().map(|v| v as f64)), Some(3000.0));

    // Drawn: points across the panel, projected with the view's camera, are its pale yellow.
    b.eval("document.getElementById('view').scrollIntoView({ block: 'nearest' })");
    let (shot, width) = png_rgb(&b.screenshot(&shots().join("52-area-light.png")));
    let ratio = b.eval("window.devicePixelRatio").as_f64().unwrap();
    let pale = [0xff, 0xf4, 0xc0];
    let mut lit = 0;
    for j in 0..5 {
        for i in 0..5 {
            let (s, t) = ((f64::from(i) + 0.5) / 5.0, (f64::from(j) + 0.5) / 5.0);
            let p: [f64; 3] = std::array::from_fn(|k| corner[k] + s * u[k] + t * v[k]);
            let seen = shot[screen_pixel(&mut b, p, ratio, width)];
            lit += usize::from((0..3).all(|k| (i32::from(seen[k]) - pale[k]).abs() <= 3));
        }
    }
    assert!(lit >= 23, "only {lit} of 25 points of the panel show its colour");
}
