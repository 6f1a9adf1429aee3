//! The Retinex and the seen image on rendered images: a single firefly (or a glint) is not the
//! white; under a sun and a sky a neutral is seen neutral in both lights.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, load_folder};
use restauro_spectral::appearance::{ChannelSpace, retinex_xyz};
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::{SeenParams, seen};

const W: u32 = 96;
const H: u32 = 64;

/// The scene `toml` written into `dir` (beside its files), loaded and prepared with its own
/// render settings.
fn prepare(dir: &std::path::Path, toml: &str) -> PreparedScene {
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let loaded = load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap();
    PreparedScene::new(&loaded, None, Settings::from(&loaded.file.render)).unwrap()
}

/// A grey ground, a white tile and a wall under a summer sun and a clear sky, path traced at 4
/// samples per pixel (so with Monte Carlo noise), in absolute XYZ, and its adapting white.
fn render() -> (Vec<[f32; 3]>, Vec<[f32; 4]>) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("grey.csv"), "380,0.3\n780,0.3\n").unwrap();
    std::fs::write(d.join("white.csv"), "380,0.8\n780,0.8\n").unwrap();
    std::fs::write(
        d.join("ground.obj"),
        "v -20 -20 0\nv 20 -20 0\nv 20 20 0\nv -20 20 0\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        d.join("tile.obj"),
        "v -1 -1 0.01\nv 1 -1 0.01\nv 1 1 0.01\nv -1 1 0.01\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(d.join("wall.obj"), "v -6 3 0\nv 6 3 0\nv 6 3 3\nv -6 3 3\nf 1 2 3 4\n")
        .unwrap();
    let toml = format!(
        r#"format = 1
[camera]
position = [0.0, -9.0, 5.0]
target = [0.0, 0.0, 0.5]
width = {W}
height = {H}
[render]
integrator = "path"
samples_per_pixel = 4
max_depth = 4
seed = 5
[spectra]
grey = {{ file = "grey.csv" }}
white = {{ file = "white.csv" }}
daylight = {{ illuminant = "D65" }}
[materials.grey]
model = "lambert"
reflectance = "grey"
[materials.white]
model = "lambert"
reflectance = "white"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "grey"
[[objects]]
name = "tile"
mesh = "tile.obj"
material = "white"
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "grey"
[[lights]]
kind = "sun"
illuminance_lux = 80000.0
azimuth_deg = 200.0
elevation_deg = 50.0
spectrum = "daylight"
[[lights]]
kind = "sky"
illuminance_lux = 15000.0
model = "uniform"
spectrum = "daylight"
"#
    );
    let prepared = prepare(d, &toml);
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: W, height: H }, false);
    (tile.xyz, tile.white.expect("an image carries its white"))
}

/// The largest relative change, away from pixel `except`, between two images.
fn largest_change(before: &[[f32; 3]], after: &[[f32; 3]], except: usize) -> f64 {
    let mut worst = 0.0f64;
    for (i, (a, b)) in before.iter().zip(after).enumerate() {
        for c in 0..3 {
            if i != except && a[c] > 0.0 {
                worst = worst.max((f64::from(b[c]) / f64::from(a[c]) - 1.0).abs());
            }
        }
    }
    worst
}

/// A firefly 10⁴ times the brightest pixel, put into a rendered image, changes the Retinex
/// output nowhere else by as much as 1 % (relative, in every channel).
#[test]
fn a_firefly_does_not_become_the_white() {
    let (image, white) = render();
    let brightest = image.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    let firefly = (H as usize / 2) * W as usize + W as usize / 3;
    let mut with_firefly = image.clone();
    with_firefly[firefly] = [1e4 * brightest; 3];
    let params = RetinexParams { seed: 8, ..Default::default() };
    let run = |img: &[[f32; 3]]| {
        retinex_xyz(img, W as usize, H as usize, &params, ChannelSpace::default(), &|_, _| {})
            .unwrap()
            .0
    };
    let (before, after) = (run(&image), run(&with_firefly));
    let worst = largest_change(&before, &after, firefly);
    eprintln!("largest relative change away from the firefly: {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
    // The seen image, adapted to the known light (the firefly's white is its surface's).
    let seen_params = SeenParams { retinex: params.clone(), ..SeenParams::default() };
    let see = |img: &[[f32; 3]]| {
        seen(img, &white, (W as usize, H as usize), &seen_params, &|_, _| {}).unwrap().0
    };
    let worst = largest_change(&see(&image), &see(&with_firefly), firefly);
    eprintln!("seen: largest relative change away from the firefly: {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
    // The paper's rule takes the firefly as the white: the same image darkens by orders of
    // magnitude (the premise of the test).
    let paper =
        RetinexParams { white: restauro_spectral::retinex::WhiteReference::Paper, ..params };
    let darkened = retinex_xyz(
        &with_firefly,
        W as usize,
        H as usize,
        &paper,
        ChannelSpace::default(),
        &|_, _| {},
    )
    .unwrap()
    .0;
    let mean =
        |img: &[[f32; 3]]| img.iter().map(|p| f64::from(p[1])).sum::<f64>() / img.len() as f64;
    assert!(mean(&darkened) < 0.1 * mean(&before), "{} vs {}", mean(&darkened), mean(&before));
}

/// A neutral tile (reflectance 0.8) and a travertine tile on grey ground, one pair in the sun
/// and one in the sky-lit shadow of a long wall, seen from above: absolute XYZ, and for each
/// tile the pixels well inside it, in the order neutral-sun, travertine-sun, neutral-shadow,
/// travertine-shadow; and which lights light each pixel.
struct TwoLights {
    xyz: Vec<[f32; 3]>,
    white: Vec<[f32; 4]>,
    lit_by: Vec<u32>,
    width: usize,
    height: usize,
    tiles: Vec<Vec<usize>>,
}

fn two_lights() -> TwoLights {
    let (w, h) = (120u32, 120u32);
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("neutral.csv"), "380,0.8\n780,0.8\n").unwrap();
    std::fs::write(d.join("grey.csv"), "380,0.3\n780,0.3\n").unwrap();
    let quad = |x0: f32, y0: f32, x1: f32, y1: f32, z: f32| {
        format!("v {x0} {y0} {z}\nv {x1} {y0} {z}\nv {x1} {y1} {z}\nv {x0} {y1} {z}\nf 1 2 3 4\n")
    };
    std::fs::write(d.join("ground.obj"), quad(-30.0, -30.0, 30.0, 30.0, 0.0)).unwrap();
    std::fs::write(d.join("wall.obj"), "v -30 0 0\nv 30 0 0\nv 30 0 4\nv -30 0 4\nf 1 2 3 4\n")
        .unwrap();
    // Tiles 1.6 m square centred at x = ∓1.3, y = ∓2.6 (y < 0 in the sun, y > 0 in shadow).
    let tiles = [(-1.3f32, -2.6f32), (1.3, -2.6), (-1.3, 2.6), (1.3, 2.6)];
    for (i, (x, y)) in tiles.iter().enumerate() {
        std::fs::write(
            d.join(format!("tile{i}.obj")),
            quad(x - 0.8, y - 0.8, x + 0.8, y + 0.8, 0.005),
        )
        .unwrap();
    }
    let objects: String = (0..4)
        .map(|i| {
            let material = if i % 2 == 0 { "neutral" } else { "travertine" };
            format!("[[objects]]\nname = \"tile{i}\"\nmesh = \"tile{i}.obj\"\nmaterial = \"{material}\"\n")
        })
        .collect();
    let toml = format!(
        r#"format = 1
[camera]
position = [0.0, 0.0, 14.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vertical_fov_deg = 46.0
width = {w}
height = {h}
[render]
integrator = "path"
samples_per_pixel = 16
max_depth = 4
seed = 3
[spectra]
neutral = {{ file = "neutral.csv" }}
grey = {{ file = "grey.csv" }}
travertine = "travertine_tufa_solid__eco_ward73"
sunlight = {{ illuminant = "D55" }}
skylight = {{ illuminant = "daylight:12000" }}
[materials.neutral]
model = "lambert"
reflectance = "neutral"
[materials.travertine]
model = "lambert"
reflectance = "travertine"
[materials.grey]
model = "lambert"
reflectance = "grey"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "grey"
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "grey"
{objects}
[[lights]]
kind = "sun"
illuminance_lux = 80000.0
azimuth_deg = 180.0
elevation_deg = 35.0
spectrum = "sunlight"
[[lights]]
kind = "sky"
illuminance_lux = 15000.0
model = "uniform"
spectrum = "skylight"
"#
    );
    let prepared = prepare(d, &toml);
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: w, height: h }, false);
    let (xyz, lit_by) = (tile.xyz, tile.lit_by.expect("the scene has a sun"));
    let white = tile.white.expect("an image carries its white");
    // Each pixel's point on the ground, from its centre ray.
    let inside: Vec<Vec<usize>> = tiles
        .iter()
        .map(|&(tx, ty)| {
            (0..(w * h) as usize)
                .filter(|&p| {
                    let (dir, _) =
                        restauro_render::tile::camera_ray(&prepared, p as u32 % w, p as u32 / w, 0);
                    let o = prepared.camera.origin;
                    let g = o + dir * (-o.z / dir.z);
                    (g.x - tx).abs() < 0.55 && (g.y - ty).abs() < 0.55
                })
                .collect()
        })
        .collect();
    TwoLights { xyz, white, lit_by, width: w as usize, height: h as usize, tiles: inside }
}

fn mean_lab(img: &[[f32; 3]], pixels: &[usize]) -> restauro_spectral::Lab {
    let n = pixels.len() as f64;
    let s = pixels.iter().fold([0.0; 3], |s, &p| {
        [s[0] + f64::from(img[p][0]), s[1] + f64::from(img[p][1]), s[2] + f64::from(img[p][2])]
    });
    let white = restauro_spectral::appearance::d65_white();
    restauro_spectral::Lab::from_xyz(
        restauro_spectral::Xyz::new(s[0] / n, s[1] / n, s[2] / n),
        white,
    )
}

/// The four tiles of [`two_lights`] (Lab, D65 white) as the Retinex alone sees them and as the
/// seen image adapted to the known light sees them, and the travertine's colour under D65.
type Labs = Vec<restauro_spectral::Lab>;
fn seen_tiles() -> (Labs, Labs, restauro_spectral::Lab) {
    let TwoLights { xyz: img, white: light, lit_by, width: w, height: h, tiles } = two_lights();
    assert!(tiles.iter().all(|t| t.len() > 100), "premise: every tile is in view");
    let luminance =
        |t: &[usize]| t.iter().map(|&p| f64::from(img[p][1])).sum::<f64>() / t.len() as f64;
    assert!(luminance(&tiles[0]) > 4.0 * luminance(&tiles[2]), "premise: the shadow is a shadow");
    // The renderer says which light lights each pixel: the sun (light 0) the first pair, nothing
    // but the sky the second.
    for (i, tile) in tiles.iter().enumerate() {
        let expect = u32::from(i < 2);
        assert!(tile.iter().all(|&p| lit_by[p] == expect), "tile {i}: lit by {expect}");
    }
    let travertine =
        restauro_spectral::library::load_reflectance("travertine_tufa_solid__eco_ward73")
            .unwrap()
            .spectrum;
    let d65 = "D65".parse::<restauro_spectral::Illuminant>().unwrap().spd().unwrap();
    let white = restauro_spectral::appearance::d65_white();
    let under_d65 = restauro_spectral::Lab::from_xyz(
        restauro_spectral::colorimetry::relative_xyz(
            &travertine,
            &d65,
            restauro_spectral::Observer::Cie1931TwoDegree,
        )
        .scale(0.01),
        white,
    );
    let params = RetinexParams { seed: 4, frameworks: Some(lit_by), ..Default::default() };
    let (retinex, stats) =
        retinex_xyz(&img, w, h, &params, ChannelSpace::default(), &|_, _| {}).unwrap();
    assert_eq!(stats.frameworks, 2, "premise: the sunlit and the shadowed ground are told apart");
    let labs: Vec<_> = tiles.iter().map(|t| mean_lab(&retinex, t)).collect();
    let seen_params = SeenParams { retinex: params, ..SeenParams::default() };
    let (adapted, _) = seen(&img, &light, (w, h), &seen_params, &|_, _| {}).unwrap();
    let seen_labs: Vec<_> = tiles.iter().map(|t| mean_lab(&adapted, t)).collect();
    eprintln!(
        "travertine under D65: L* {:.1} C* {:.1} h {:.1}°",
        under_d65.l,
        under_d65.chroma(),
        under_d65.hue_deg()
    );
    let names = ["neutral, sun", "travertine, sun", "neutral, shadow", "travertine, shadow"];
    for (i, label) in names.iter().enumerate() {
        let (r, s) = (labs[i], seen_labs[i]);
        eprintln!(
            "{label:<20} Retinex L* {:5.1} C* {:5.1} h {:6.1}°   light L* {:5.1} C* {:5.1} h {:6.1}°",
            r.l,
            r.chroma(),
            r.hue_deg(),
            s.l,
            s.chroma(),
            s.hue_deg()
        );
    }
    (labs, seen_labs, under_d65)
}

fn hue_difference(a: f64, b: f64) -> f64 {
    ((a - b + 540.0) % 360.0 - 180.0).abs()
}

/// The tiles of one half (0: sun, 2: shadow): the neutral has C* < 3 and the travertine's hue
/// is within 10° of its hue under D65.
fn check_half(labs: &[restauro_spectral::Lab], under_d65: restauro_spectral::Lab, i: usize) {
    let half = if i == 0 { "sun" } else { "shadow" };
    assert!(labs[i].chroma() < 3.0, "the neutral in the {half}: C* {:.1}", labs[i].chroma());
    let dh = hue_difference(labs[i + 1].hue_deg(), under_d65.hue_deg());
    assert!(
        dh < 10.0,
        "the travertine in the {half}: hue {:.1}° against {:.1}°",
        labs[i + 1].hue_deg(),
        under_d65.hue_deg()
    );
}

/// Under sun and sky, in the sunlit half the Retinex (and the seen image adapted to the known
/// light: the same measures) sees the neutral tile as neutral
/// (C* < 3) and the travertine with its hue under D65 (within 10°), though the noise of the
/// render (7 %) is as large as the travertine's step against the grey ground in the S cones.
/// Measured: neutral C* 0.5, travertine 84.9° against 79.9° (with the bilateral's cut at 3σ_n
/// instead of 2σ_n, 93°).
#[test]
fn two_lights_in_the_sun_a_neutral_is_neutral_and_a_travertine_keeps_its_hue() {
    let (retinex, adapted, under_d65) = seen_tiles();
    check_half(&retinex, under_d65, 0);
    check_half(&adapted, under_d65, 0);
}

/// The same in the sky-lit shadow of the wall, adapted to its own framework of illumination
/// (the pixels the sun does not light), whose light the Retinex finds from the ratio across the
/// shadow's edge. Measured: neutral C* 0.3, travertine 88.2° against 79.9°. With one white for the whole image (no frameworks) the neutral in the shadow is seen
/// relative to the sunlit white: C* 18.6, blue; with a local reach instead (0.3) a D65
/// Mondrian shifts by 6.5 ΔE00 (see `DEFAULT_REACH`).
#[test]
fn two_lights_in_the_shadow_a_neutral_is_neutral_and_a_travertine_keeps_its_hue() {
    let (retinex, adapted, under_d65) = seen_tiles();
    check_half(&retinex, under_d65, 2);
    check_half(&adapted, under_d65, 2);
}
