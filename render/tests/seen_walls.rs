//! The seen image on rendered scenes without a white (issue 34): a wall of one stone seen from
//! a square, with only paving and sky around it, keeps the stone's colour; a white card in
//! front of it does not change how the wall is seen; a white marble wall is still white.
//!
//! Each case is a path-traced render (absolute XYZ, the adapting white, the light masks and the
//! sky's coverage, as the farm's tiles carry them) passed through `restauro_spectral::seen`.
//! The wall's seen colour is compared with the stone's colour under D65, CIELAB against the
//! perfect white, as `restauro color` prints it.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, TileResult, render_tile};
use restauro_scene::load::{Limits, load_folder};
use restauro_spectral::appearance::d65_white;
use restauro_spectral::colorimetry::relative_xyz;
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::{SeenParams, seen};
use restauro_spectral::{Illuminant, Lab, Observer, Xyz};

const W: u32 = 120;
const H: u32 = 80;

/// The light of a case.
#[derive(Clone, Copy, Debug)]
enum Light {
    /// An afternoon sun (80 000 lux, D55, 40° up, from the south-south-west) and the CIE
    /// standard clear sky (type 12, 15 000 lux, 12 000 K).
    SunAndSky,
    /// The CIE standard overcast sky, 10 000 lux, D65.
    Overcast,
    /// A 3000 K floodlight of this many candela from 10 m in front of the wall, at night.
    Flood(f64),
}

/// A wall of `stone` (10 × 4 m, facing south) seen from 14 m across a square of sandstone
/// flagstones, under `light`, with a 1.2 m white card standing in front of its left half when
/// `card`. Returns the tile and the pixels well inside the wall's right half (away from the
/// card and its shadow).
fn render(stone: &str, light: Light, card: bool) -> (TileResult, Vec<usize>) {
    render_with(stone, light, card, 8)
}

/// [`render`] at `spp` samples per pixel.
fn render_with(stone: &str, light: Light, card: bool, spp: u32) -> (TileResult, Vec<usize>) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_meshes(d);
    std::fs::write(d.join("scene.toml"), scene_toml(stone, light, card, spp)).unwrap();
    let loaded = load_folder(&d.join("scene.toml"), &Limits::default()).unwrap();
    let prepared = PreparedScene::new(&loaded, None, Settings::from(&loaded.file.render)).unwrap();
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: W, height: H }, false);
    let wall = wall_pixels(&prepared);
    assert!(wall.len() > 300, "premise: the wall is in view ({} pixels)", wall.len());
    (tile, wall)
}

/// The square's paving, the wall and the card, one quad each, into folder `d`.
fn write_meshes(d: &std::path::Path) {
    let quad = |name: &str, v: [[f32; 3]; 4]| {
        let mut s = String::new();
        for p in v {
            s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        std::fs::write(d.join(name), s + "f 1 2 3 4\n").unwrap();
    };
    quad(
        "ground.obj",
        [[-40.0, -40.0, 0.0], [40.0, -40.0, 0.0], [40.0, 40.0, 0.0], [-40.0, 40.0, 0.0]],
    );
    quad("wall.obj", [[-5.0, 6.0, 0.0], [5.0, 6.0, 0.0], [5.0, 6.0, 4.0], [-5.0, 6.0, 4.0]]);
    quad("card.obj", [[-3.2, 5.0, 0.4], [-2.0, 5.0, 0.4], [-2.0, 5.0, 1.6], [-3.2, 5.0, 1.6]]);
}

/// The `[[lights]]` of `light`.
fn lights_toml(light: Light) -> String {
    match light {
        Light::SunAndSky => r#"[[lights]]
kind = "sun"
illuminance_lux = 80000.0
azimuth_deg = 200.0
elevation_deg = 40.0
spectrum = "sunlight"
[[lights]]
kind = "sky"
illuminance_lux = 15000.0
model = "cie-general"
cie_type = 12
spectrum = "skylight"
"#
        .to_owned(),
        Light::Overcast => r#"[[lights]]
kind = "sky"
preset = "overcast"
spectrum = "daylight"
"#
        .to_owned(),
        Light::Flood(cd) => format!(
            r#"[[lights]]
kind = "spot"
position = [2.5, -4.0, 0.5]
aim = [2.5, 6.0, 2.0]
intensity_cd = {cd}
cone_deg = 25.0
falloff_deg = 10.0
spectrum = "flood"
"#
        ),
    }
}

/// The scene file of a case: the camera, the path tracer at `spp`, the spectra and materials,
/// the ground, the wall of `stone`, the card when `card`, and the lights.
fn scene_toml(stone: &str, light: Light, card: bool, spp: u32) -> String {
    let card = if card {
        "[[objects]]\nname = \"card\"\nmesh = \"card.obj\"\nmaterial = \"card\"\n"
    } else {
        ""
    };
    let lights = lights_toml(light);
    format!(
        r#"format = 1
[camera]
position = [0.0, -8.0, 1.6]
target = [0.0, 6.0, 2.2]
vertical_fov_deg = 40.0
width = {W}
height = {H}
[render]
integrator = "path"
samples_per_pixel = {spp}
max_depth = 3
seed = 34
[spectra]
stone = "{stone}"
paving = "sandstone_flagstone_solid__eco_ward61"
card = {{ constant = 0.9 }}
sunlight = {{ illuminant = "D55" }}
skylight = {{ illuminant = "daylight:12000" }}
daylight = {{ illuminant = "D65" }}
flood = {{ illuminant = "blackbody:3000" }}
[materials.stone]
model = "lambert"
reflectance = "stone"
[materials.paving]
model = "lambert"
reflectance = "paving"
[materials.card]
model = "lambert"
reflectance = "card"
[[objects]]
name = "ground"
mesh = "ground.obj"
material = "paving"
[[objects]]
name = "wall"
mesh = "wall.obj"
material = "stone"
{card}{lights}"#
    )
}

/// The wall's right half, 0.5 m in from its edges, by where each pixel's centre ray meets
/// the plane y = 6.
fn wall_pixels(prepared: &PreparedScene) -> Vec<usize> {
    let o = prepared.camera.origin;
    (0..(W * H) as usize)
        .filter(|&p| {
            let (dir, _) =
                restauro_render::tile::camera_ray(prepared, p as u32 % W, p as u32 / W, 0);
            let t = (6.0 - o.y) / dir.y;
            let at = o + dir * t;
            t > 0.0 && (0.5..4.5).contains(&at.x) && (0.5..3.5).contains(&at.z)
        })
        .collect()
}

/// The seen image of a tile, as the farm makes it.
fn seen_of(tile: &TileResult) -> Vec<[f32; 3]> {
    let emitters = tile.sky.as_ref().map(|s| s.iter().map(|&f| f >= 0.1).collect());
    let params = SeenParams {
        retinex: RetinexParams {
            seed: 1,
            emitters,
            frameworks: tile.lit_by.clone(),
            ..RetinexParams::default()
        },
        ..SeenParams::default()
    };
    let white = tile.white.as_ref().expect("an image carries its white");
    seen(&tile.xyz, white, (W as usize, H as usize), &params, &|_, _| {}).unwrap().0
}

fn mean_lab(img: &[[f32; 3]], pixels: &[usize]) -> Lab {
    let n = pixels.len() as f64;
    let s = pixels.iter().fold([0.0; 3], |s, &p| {
        [s[0] + f64::from(img[p][0]), s[1] + f64::from(img[p][1]), s[2] + f64::from(img[p][2])]
    });
    Lab::from_xyz(Xyz::new(s[0] / n, s[1] / n, s[2] / n), d65_white())
}

/// The stone's colour under D65, CIELAB against the perfect white (`restauro color`).
fn under_d65(stone: &str) -> Lab {
    let rho = restauro_spectral::library::load_reflectance(stone).unwrap().spectrum;
    let d65 = "D65".parse::<Illuminant>().unwrap().spd().unwrap();
    Lab::from_xyz(relative_xyz(&rho, &d65, Observer::Cie1931TwoDegree).scale(0.01), d65_white())
}

fn hue_difference(a: f64, b: f64) -> f64 {
    ((a - b + 540.0) % 360.0 - 180.0).abs()
}

fn show(label: &str, lab: Lab) -> String {
    format!("{label:<22} L* {:5.1} C* {:5.1} h {:6.1}°", lab.l, lab.chroma(), lab.hue_deg())
}

const STONES: [&str; 5] = [
    "brick_red_smooth__eco_0097uuubrk",
    "travertine_tufa_solid__eco_ward73",
    "sandstone_red_potsdam_solid__eco_ward59",
    "lichen_xanthoria_orange_on_rock__usgs_Xanthoria-1",
    "granite_biotite_grey_solid__eco_ward10",
];

/// Without a white in view, each wall is seen in its own hue (within 10°), chroma (within
/// 20 %) and lightness (within 10 L*); with the card, within ΔE00 3 of that.
#[test]
fn a_wall_keeps_its_colour_without_a_white_in_view() {
    let mut failures = Vec::new();
    for light in [Light::SunAndSky, Light::Overcast] {
        for stone in STONES {
            let truth = under_d65(stone);
            let (tile, wall) = render(stone, light, false);
            let alone = mean_lab(&seen_of(&tile), &wall);
            let (tile, wall) = render(stone, light, true);
            let with_card = mean_lab(&seen_of(&tile), &wall);
            let de = restauro_spectral::ciede2000::ciede2000(alone, with_card);
            eprintln!("{light:?}, {stone}");
            eprintln!("  {}", show("under D65", truth));
            eprintln!("  {}", show("seen, no white", alone));
            eprintln!("  {}   ΔE00 {de:.2}", show("seen, white card", with_card));
            let chroma = alone.chroma() / truth.chroma() - 1.0;
            if hue_difference(alone.hue_deg(), truth.hue_deg()) > 10.0
                || chroma.abs() > 0.2
                || (alone.l - truth.l).abs() > 10.0
                || de > 3.0
            {
                failures.push(format!("{light:?} {stone}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// A white marble wall is still seen white: L* ≥ 85 in the sun and under an overcast sky.
#[test]
fn a_white_marble_wall_is_seen_white() {
    let stone = "marble_white_solid__eco_ward95";
    let truth = under_d65(stone);
    for light in [Light::SunAndSky, Light::Overcast] {
        let (tile, wall) = render(stone, light, false);
        let lab = mean_lab(&seen_of(&tile), &wall);
        eprintln!("{light:?}: {}   ({})", show("seen", lab), show("under D65", truth));
        assert!(lab.l >= 85.0, "{light:?}: L* {:.1}", lab.l);
    }
}

/// The mean luminance (cd/m²) of `pixels` of a render.
fn luminance(tile: &TileResult, pixels: &[usize]) -> f64 {
    pixels.iter().map(|&p| f64::from(tile.xyz[p][1])).sum::<f64>() / pixels.len() as f64
}

/// A warm floodlight (3000 K) on pale stone at night, the lit stone at about 0.5 cd/m² (as the
/// demo's floodlit facade): seen warm — its hue within 25° of the stone's own under D65 and
/// redder (a* higher), not blue — and less saturated than the same light at a daylight level
/// (1000 times brighter), where the eye adapts more and the rods take no part.
#[test]
fn a_warm_flood_at_night_is_seen_warm_and_weaker_not_blue() {
    let stone = "travertine_tufa_solid__eco_ward73";
    let truth = under_d65(stone);
    let (night, wall) = render(stone, Light::Flood(520.0), false);
    let (day, _) = render(stone, Light::Flood(520_000.0), false);
    let lit = luminance(&night, &wall);
    assert!((0.3..0.8).contains(&lit), "premise: the lit stone at {lit:.2} cd/m²");
    let (at_night, by_day) = (mean_lab(&seen_of(&night), &wall), mean_lab(&seen_of(&day), &wall));
    eprintln!("{}", show("under D65", truth));
    eprintln!("{}   at {lit:.2} cd/m²", show("seen at night", at_night));
    eprintln!("{}", show("seen at 1000 ×", by_day));
    let hue = at_night.hue_deg();
    assert!(
        hue_difference(hue, truth.hue_deg()) < 25.0 && at_night.a > truth.a,
        "not warm: {hue:.1}°"
    );
    assert!(at_night.b > 0.0 && at_night.chroma() > 0.5 * truth.chroma(), "{at_night:?}");
    assert!(
        at_night.chroma() < by_day.chroma(),
        "{:.1} against {:.1}",
        at_night.chroma(),
        by_day.chroma()
    );
}

/// The spread of CIE u′v′ over `pixels` (RMS distance from their mean), of pixels not black.
fn chromatic_noise(img: &[[f32; 3]], pixels: &[usize]) -> f64 {
    let uv: Vec<(f64, f64)> = pixels
        .iter()
        .filter_map(|&p| {
            let [x, y, z] = img[p].map(f64::from);
            restauro_spectral::seen::degree::uv(Xyz::new(x, y, z))
        })
        .collect();
    let n = uv.len() as f64;
    let (mu, mv) = uv.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0 / n, a.1 + b.1 / n));
    (uv.iter().map(|(u, v)| (u - mu).powi(2) + (v - mv).powi(2)).sum::<f64>() / n).sqrt()
}

/// The relative spread of luminance over `pixels` (standard deviation over mean).
fn luminance_noise(img: &[[f32; 3]], pixels: &[usize]) -> f64 {
    let y: Vec<f64> = pixels.iter().map(|&p| f64::from(img[p][1])).collect();
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64).sqrt() / mean
}

/// Monte Carlo noise in the dark is not made into a speckle: on the night scene rendered at 2
/// samples per pixel, where the surfaces outside the flood are lit only by light bounced off
/// the wall (noisy), the seen image's chromatic noise (u′v′ spread) is no larger than the
/// render's, and its luminance noise (relative spread) no larger than the render's either: the
/// seen image scales each pixel by smooth factors (its light, the paths' change), so it shows
/// the render's own noise and adds none.
#[test]
fn noise_in_the_dark_is_not_amplified() {
    let stone = "travertine_tufa_solid__eco_ward73";
    let (night, _) = render_with(stone, Light::Flood(520.0), false, 2);
    // The surfaces the flood does not reach.
    let lit_by = night.lit_by.as_ref().unwrap();
    let dark: Vec<usize> =
        (0..(W * H) as usize).filter(|&p| lit_by[p] == 0 && night.xyz[p][1] > 0.0).collect();
    assert!(dark.len() > 200, "premise: a dark corner ({} pixels)", dark.len());
    let rendered = chromatic_noise(&night.xyz, &dark);
    let seen_noise = chromatic_noise(&seen_of(&night), &dark);
    // What the Retinex alone made of it (the speckle of issue 34), for the record.
    let emitters = night.sky.as_ref().map(|s| s.iter().map(|&f| f >= 0.1).collect());
    let params =
        RetinexParams { seed: 1, emitters, frameworks: night.lit_by.clone(), ..Default::default() };
    let space = restauro_spectral::appearance::ChannelSpace::default();
    let (retinex, _) = restauro_spectral::appearance::retinex_xyz(
        &night.xyz,
        W as usize,
        H as usize,
        &params,
        space,
        &|_, _| {},
    )
    .unwrap();
    eprintln!(
        "u′v′ spread where the flood does not reach (mean {:.4} cd/m²): rendered {rendered:.4}, \
         seen {seen_noise:.4}, the Retinex alone {:.4}",
        luminance(&night, &dark),
        chromatic_noise(&retinex, &dark)
    );
    assert!(rendered > 0.002, "premise: the render is noisy there ({rendered})");
    assert!(seen_noise <= rendered, "seen {seen_noise:.4} against rendered {rendered:.4}");
    let (rendered_y, seen_y) =
        (luminance_noise(&night.xyz, &dark), luminance_noise(&seen_of(&night), &dark));
    eprintln!(
        "relative luminance spread there: rendered {rendered_y:.3}, seen {seen_y:.3}, the Retinex \
         alone {:.3}",
        luminance_noise(&retinex, &dark)
    );
    assert!(seen_y <= 1.05 * rendered_y, "seen {seen_y:.3} against rendered {rendered_y:.3}");
}
