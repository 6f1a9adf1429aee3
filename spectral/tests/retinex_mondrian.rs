//! What the paper claims for its Retinex, and the seen image that adapts to the known light,
//! measured on a spectral Mondrian rendered for the test:
//! patches of the 24 published ColorChecker reflectances (Ohta) and of 16 shipped stone
//! spectra, under a smooth, uneven illumination, rendered with CIE A, B and D65.
//!
//! Differences are mean CIEDE2000 over all pixels after one global exposure factor (the ratio of
//! mean luminances), with CIELAB relative to the D65 white. Run with `--nocapture` to see the
//! figures, including those of the white-patch baseline.

use restauro_spectral::adaptation::ConeSpace;
use restauro_spectral::appearance::{ChannelSpace, d65_white, retinex_xyz, white_patch_xyz};
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::{Observer, relative_xyz};
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::{SeenParams, seen};
use restauro_spectral::{Illuminant, Lab, Spectrum, Xyz, library};

const W: usize = 240;
const H: usize = 160;
const COLS: usize = 8;
const ROWS: usize = 5;

const STONES: [&str; 16] = [
    "travertine_tufa_solid__eco_ward73",
    "travertine_particulate_coarse__eco_travertine1",
    "conglomerate_quartz_solid__eco_ward48",
    "conglomerate_quartz_solid__eco_ward49",
    "conglomerate_limestone_breccia_solid__eco_ward50",
    "limestone_weathered_surface__usgs_CU02-11A",
    "limestone_oolitic_indiana_solid__eco_ward72",
    "marble_pink_solid__eco_ward96",
    "marble_white_solid__eco_ward95",
    "sandstone_red_potsdam_solid__eco_ward59",
    "sandstone_brownstone_portland_solid__eco_ward60",
    "brick_building_medred__usgs_GDS353",
    "brick_paving_tan__usgs_GDS347",
    "terracotta_roof_tile_weathered__eco_0484uuupot",
    "granite_biotite_grey_solid__eco_ward10",
    "lichen_xanthoria_orange_on_rock__usgs_Xanthoria-1",
];

/// The 24 ColorChecker reflectances from `data/colorchecker/`.
fn colorchecker() -> Vec<Spectrum> {
    let text = include_str!("../../data/colorchecker/colorchecker_ohta_5nm_380-780.csv");
    let mut rows = text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let columns = rows.next().unwrap().split(',').count() - 1;
    let mut patches = vec![Spectrum::ZERO; columns];
    for (band, row) in rows.enumerate() {
        for (i, v) in row.split(',').skip(1).enumerate() {
            patches[i][band] = v.trim().parse().unwrap();
        }
    }
    assert_eq!(patches.len(), 24);
    patches
}

/// The patch of each pixel and the illumination falling on it (0.55–1, smooth: a change of at
/// most 0.4 % between neighbours, so below the Retinex threshold).
fn layout() -> (Vec<usize>, Vec<f32>) {
    let mut patch = Vec::with_capacity(W * H);
    let mut light = Vec::with_capacity(W * H);
    for y in 0..H {
        for x in 0..W {
            // Columns of uneven widths so that patch edges do not line up in a regular grid.
            let col = (((x as f32 / W as f32).powf(1.15)) * COLS as f32) as usize;
            let row = y * ROWS / H;
            patch.push((row * COLS + col.min(COLS - 1) + 7 * row) % (COLS * ROWS));
            let (u, v) = (x as f32 / W as f32, y as f32 / H as f32);
            light.push(0.55 + 0.45 * (1.0 - 0.6 * u * u - 0.4 * v));
        }
    }
    (patch, light)
}

/// The Mondrian under `illuminant`, in XYZ with Y = 1 for a perfect white in full light.
fn render(illuminant: &str, patches: &[Spectrum]) -> Vec<[f32; 3]> {
    render_lit(illuminant, patches, true)
}

/// The Mondrian with the uneven light, or with every patch in full light.
fn render_lit(illuminant: &str, patches: &[Spectrum], uneven: bool) -> Vec<[f32; 3]> {
    let spd = illuminant.parse::<Illuminant>().unwrap().spd().unwrap();
    let colours: Vec<Xyz> = patches
        .iter()
        .map(|r| relative_xyz(r, &spd, Observer::Cie1931TwoDegree).scale(0.01))
        .collect();
    let (patch, light) = layout();
    patch
        .iter()
        .zip(&light)
        .map(|(&p, &g)| {
            let g = if uneven { g } else { 1.0 };
            let c = colours[p];
            [c.x as f32 * g, c.y as f32 * g, c.z as f32 * g]
        })
        .collect()
}

fn mean_y(img: &[[f32; 3]]) -> f64 {
    img.iter().map(|p| f64::from(p[1])).sum::<f64>() / img.len() as f64
}

fn lab(p: [f32; 3], k: f64) -> Lab {
    let white = d65_white();
    Lab::from_xyz(Xyz::new(f64::from(p[0]) * k, f64::from(p[1]) * k, f64::from(p[2]) * k), white)
}

/// Mean ΔE00 of `test` against `reference`, after scaling `test` by one exposure factor.
/// With `chroma_only`, the lightness difference is left out (the reference's L* is used for
/// both).
fn mean_delta_e(test: &[[f32; 3]], reference: &[[f32; 3]], chroma_only: bool) -> f64 {
    let k = mean_y(reference) / mean_y(test);
    let total: f64 = test
        .iter()
        .zip(reference)
        .map(|(&t, &r)| {
            let (lt, lr) = (lab(t, k), lab(r, 1.0));
            let lt = if chroma_only { Lab::new(lr.l, lt.a, lt.b) } else { lt };
            ciede2000(lr, lt)
        })
        .sum();
    total / test.len() as f64
}

fn all_patches() -> Vec<Spectrum> {
    let mut patches = colorchecker();
    for stem in STONES {
        patches.push(library::load_reflectance(stem).unwrap().spectrum);
    }
    patches
}

#[test]
fn retinex_makes_the_mondrian_illuminant_invariant() {
    let patches = all_patches();
    let space = ChannelSpace::default();
    let params = RetinexParams { seed: 2004, ..Default::default() };
    let run = |img: &[[f32; 3]]| retinex_xyz(img, W, H, &params, space, &|_, _| {}).unwrap().0;
    let d65 = render("D65", &patches);
    let retinex_d65 = run(&d65);
    let white_patch_d65 = white_patch_xyz(&d65, space);
    for light in ["A", "B"] {
        let img = render(light, &patches);
        let uncorrected = mean_delta_e(&img, &d65, false);
        let retinex = mean_delta_e(&run(&img), &retinex_d65, false);
        let baseline = mean_delta_e(&white_patch_xyz(&img, space), &white_patch_d65, false);
        eprintln!(
            "{light} against D65, mean ΔE00: uncorrected {uncorrected:.2}, Retinex {retinex:.2} \
             ({:.0} % lower), white-patch baseline {baseline:.2} ({:.0} % lower)",
            100.0 * (1.0 - retinex / uncorrected),
            100.0 * (1.0 - baseline / uncorrected)
        );
        assert!(
            retinex <= 0.3 * uncorrected,
            "{light}: Retinex {retinex} vs uncorrected {uncorrected}"
        );
    }
}

#[test]
fn retinex_leaves_a_d65_scene_nearly_unchanged_in_chroma() {
    let patches = all_patches();
    let space = ChannelSpace::default();
    let params = RetinexParams { seed: 2004, ..Default::default() };
    let d65 = render("D65", &patches);
    let (out, stats) = retinex_xyz(&d65, W, H, &params, space, &|_, _| {}).unwrap();
    let chroma = mean_delta_e(&out, &d65, true);
    let baseline = mean_delta_e(&white_patch_xyz(&d65, space), &d65, true);
    eprintln!(
        "D65: Retinex against the D65 image, chroma only, mean ΔE00 {chroma:.2} (white-patch \
         baseline {baseline:.2}); {stats:?}"
    );
    assert!(chroma < 1.0, "{chroma}");
}

#[test]
fn the_white_patch_stays_white_and_threads_do_not_matter() {
    let patches = all_patches();
    let params = RetinexParams { seed: 7, paths: 10, ..Default::default() };
    let space = ChannelSpace::Lms(ConeSpace::Cat02);
    // In even light the white patch (ColorChecker white 9.5, patch 18) is the brightest area in
    // every channel; it must stay white, i.e. come out as the D65 white.
    let img = render_lit("A", &patches, false);
    let (patch, _) = layout();
    let channels = space.from_xyz(&img);
    let white_pixel = patch.iter().position(|&p| p == 18).unwrap();
    for c in 0..3 {
        let max = channels.iter().map(|p| p[c]).fold(0.0f32, f32::max);
        assert_eq!(channels[white_pixel][c], max, "premise: white is brightest in channel {c}");
    }
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    let one = pool(1).install(|| retinex_xyz(&img, W, H, &params, space, &|_, _| {}).unwrap().0);
    let two = pool(2).install(|| retinex_xyz(&img, W, H, &params, space, &|_, _| {}).unwrap().0);
    assert!(one == two, "the output depends on the number of threads");
    let white = d65_white();
    for (i, p) in one.iter().enumerate().filter(|(i, _)| patch[*i] == 18) {
        assert!((f64::from(p[1]) - 1.0).abs() < 1e-4, "pixel {i}: {p:?}");
        assert!((f64::from(p[0]) - white.x).abs() < 1e-4, "pixel {i}: {p:?}");
        assert!((f64::from(p[2]) - white.z).abs() < 1e-4, "pixel {i}: {p:?}");
    }
}

/// The Mondrian at a white of `level_cd_m2`, with its adapting white (the light on each
/// pixel: the illuminant's white times the uneven illumination), as a render carries it.
fn lit_at(
    illuminant: &str,
    patches: &[Spectrum],
    uneven: bool,
    level_cd_m2: f32,
) -> (Vec<[f32; 3]>, Vec<[f32; 4]>) {
    let spd = illuminant.parse::<Illuminant>().unwrap().spd().unwrap();
    let white = relative_xyz(&Spectrum::ONE, &spd, Observer::Cie1931TwoDegree).scale(0.01);
    let (_, light) = layout();
    let img = render_lit(illuminant, patches, uneven)
        .into_iter()
        .map(|p| p.map(|v| v * level_cd_m2))
        .collect();
    let whites = light
        .iter()
        .map(|&g| {
            let g = if uneven { g } else { 1.0 } * level_cd_m2;
            // The scotopic part only matters below 5 cd/m².
            [white.x as f32 * g, white.y as f32 * g, white.z as f32 * g, 2.0 * g]
        })
        .collect();
    (img, whites)
}

fn seen_of(img: &[[f32; 3]], white: &[[f32; 4]], seed: u64) -> Vec<[f32; 3]> {
    let params =
        SeenParams { retinex: RetinexParams { seed, ..Default::default() }, ..Default::default() };
    seen(img, white, (W, H), &params, &|_, _| {}).unwrap().0
}

/// Adapted to the known light, the Mondrian under B is seen as under D65 (a fifth of the
/// camera's difference at most, as the Retinex), and under A with the warmth a person keeps
/// under a tungsten light in a bright room (the blue bias: D ≈ 0.78 at 1000 cd/m²) — a third
/// of the camera's difference at most, and warmer (b*) than under D65.
#[test]
fn the_seen_image_makes_the_mondrian_nearly_illuminant_invariant() {
    let patches = all_patches();
    let level = 1000.0;
    let (d65, d65_white) = lit_at("D65", &patches, true, level);
    let seen_d65 = seen_of(&d65, &d65_white, 2004);
    let d65_relative = render("D65", &patches);
    for (light, bound) in [("B", 0.2), ("A", 0.35)] {
        let (img, white) = lit_at(light, &patches, true, level);
        let uncorrected = mean_delta_e(&render(light, &patches), &d65_relative, false);
        let seen_img = seen_of(&img, &white, 2004);
        let adapted = mean_delta_e(&seen_img, &seen_d65, false);
        let mean_b =
            |img: &[[f32; 3]]| img.iter().map(|&p| lab(p, 1.0).b).sum::<f64>() / img.len() as f64;
        eprintln!(
            "{light} against D65, mean ΔE00: uncorrected {uncorrected:.2}, seen {adapted:.2} \
             ({:.0} % lower); mean b* {:.2} against {:.2} under D65",
            100.0 * (1.0 - adapted / uncorrected),
            mean_b(&seen_img),
            mean_b(&seen_d65),
        );
        assert!(adapted <= bound * uncorrected, "{light}: {adapted:.2} vs {uncorrected:.2}");
        if light == "A" {
            assert!(mean_b(&seen_img) > mean_b(&seen_d65) + 1.0, "a tungsten light stays warm");
        }
    }
}

/// Under D65 the seen image is the image, relative to its white: chroma within ΔE00 1 (what
/// differs is lightness, where the uneven light is partly discounted, and CIELAB's chroma
/// follows lightness), and the same whatever the number of threads.
#[test]
fn the_seen_image_leaves_a_d65_scene_unchanged_and_threads_do_not_matter() {
    let patches = all_patches();
    let (d65, white) = lit_at("D65", &patches, true, 1000.0);
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    let one = pool(1).install(|| seen_of(&d65, &white, 7));
    let two = pool(2).install(|| seen_of(&d65, &white, 7));
    assert!(one == two, "the output depends on the number of threads");
    let chroma = mean_delta_e(&one, &d65, true);
    eprintln!("D65: the seen image against the D65 image, chroma only, mean ΔE00 {chroma:.3}");
    assert!(chroma < 1.0, "{chroma}");
}
