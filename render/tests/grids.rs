//! Calculation grids band by band: CIE 171:2006 cases 5.2 and 5.8 under CIE illuminant A with
//! a measured, far from flat reflectance (a dark red building brick, USGS splib07a GDS350).
//! Each of the 81 bands must give the case's relative result on its own, to 1 %.

use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use restauro_spectral::grid::BANDS;
use std::fmt::Write as _;
use std::path::Path;

fn load(dir: &Path, mesh: &str, body: &str) -> LoadedScene {
    std::fs::write(dir.join("mesh.obj"), mesh).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [2.0, 0.2, 1.5]\ntarget = [2.0, 4.0, 1.5]\nwidth = 8\n\
         height = 6\n[spectra]\nlamp = {{ illuminant = \"A\" }}\n\
         brick = \"brick_building_darkred__usgs_GDS350\"\n\
         [materials.brick]\nmodel = \"lambert\"\nreflectance = \"brick\"\n\
         [[objects]]\nname = \"mesh\"\nmesh = \"mesh.obj\"\nmaterial = \"brick\"\n{body}"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

/// Every sensor's mean direct and indirect spectral irradiance, in the grids' order.
fn irradiance(scene: &LoadedScene, samples: u32) -> (Vec<Spectrum>, Vec<Spectrum>) {
    let settings = Settings {
        integrator: Integrator::Path,
        samples_per_pixel: samples,
        max_depth: 0,
        seed: 3,
        grids: true,
        noise_target: 0.0,
    };
    let prepared = PreparedScene::new(scene, None, settings).unwrap();
    let n = prepared.sensors.len() as u32;
    let tile = render_tile(&prepared, Rect { x: 0, y: 0, width: n, height: 2 }, true);
    let spectra = tile.spectral.unwrap();
    let (direct, indirect) = spectra.split_at(n as usize);
    (direct.to_vec(), indirect.to_vec())
}

/// 5.2 under illuminant A: the source I(θ) = 1000 cos θ (isotropic light shaped by a cone
/// would not do: written as a measured distribution), 3 m above the plane. In every band,
/// E(x, y)/E(0, 0) = (h/d)⁴ and the plane, whatever its colour, sends no light back to it.
#[test]
fn case_5_2_holds_in_every_band() {
    let dir = tempfile::tempdir().unwrap();
    let angles: Vec<String> = (0..=90).map(|a| a.to_string()).collect();
    let cd: Vec<String> =
        (0..=90).map(|a| format!("{:.6}", 1000.0 * f64::from(a).to_radians().cos())).collect();
    let ies = format!(
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 91 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
        angles.join(" "),
        cd.join(" ")
    );
    std::fs::write(dir.path().join("cos.ies"), ies).unwrap();
    let offsets = [(0.0, 0.0), (1.0, 0.0), (1.5, 0.5), (1.5, 1.5)];
    let points: Vec<String> = offsets.iter().map(|(x, y)| format!("[{x}, {y}, 0.0]")).collect();
    let body = format!(
        "[[lights]]\nkind = \"point\"\nposition = [0.0, 0.0, 3.0]\nspectrum = \"lamp\"\n\
         ies = \"cos.ies\"\n[[grids]]\nname = \"g\"\npoints = [{}]\nnormal = [0, 0, 1]\n",
        points.join(", ")
    );
    let plane = "v -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\nf 1 2 3 4\n";
    let scene = load(dir.path(), plane, &body);
    let (direct, indirect) = irradiance(&scene, 4);
    for (k, (x, y)) in offsets.iter().enumerate() {
        let expected = (9.0 / (x * x + y * y + 9.0) as f32).powi(2);
        for band in 0..BANDS {
            let ratio = direct[k].0[band] / direct[0].0[band];
            assert!(
                (ratio / expected - 1.0).abs() < 0.001,
                "({x}, {y}), band {band}: {ratio} against {expected}"
            );
            assert_eq!(indirect[k].0[band], 0.0);
        }
    }
}

/// 5.8 with the brick on every face: in each band λ, the area-weighted means over the six faces
/// of the indirect and the direct irradiance stand in the ratio ρ(λ)/(1 − ρ(λ)).
#[test]
fn case_5_8_holds_in_every_band() {
    let dir = tempfile::tempdir().unwrap();
    let cube = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 4\nv 4 0 4\nv 4 4 4\nv 0 4 4\n\
                f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
    let mut body = String::from(
        "[[lights]]\nkind = \"point\"\nposition = [2.0, 2.0, 2.0]\nflux_lm = 10000.0\n\
         spectrum = \"lamp\"\n",
    );
    // The faces, 16 × 16 cells each (all the same area), facing in.
    for (o, u, v, n) in [
        ("[0, 0, 0]", "[4, 0, 0]", "[0, 4, 0]", "[0, 0, 1]"),
        ("[0, 0, 4]", "[4, 0, 0]", "[0, 4, 0]", "[0, 0, -1]"),
        ("[0, 0, 0]", "[4, 0, 0]", "[0, 0, 4]", "[0, 1, 0]"),
        ("[0, 4, 0]", "[4, 0, 0]", "[0, 0, 4]", "[0, -1, 0]"),
        ("[0, 0, 0]", "[0, 4, 0]", "[0, 0, 4]", "[1, 0, 0]"),
        ("[4, 0, 0]", "[0, 4, 0]", "[0, 0, 4]", "[-1, 0, 0]"),
    ] {
        let name = format!("f{}", body.len());
        let _ = write!(
            body,
            "[[grids]]\nname = \"{name}\"\norigin = {o}\nu = {u}\nv = {v}\ndivisions = [16, 16]\n\
             normal = {n}\n"
        );
    }
    let scene = load(dir.path(), cube, &body);
    let rho = scene.spectra["brick"];
    let (direct, indirect) = irradiance(&scene, 64);
    let mean = |s: &[Spectrum], band: usize| {
        s.iter().map(|e| f64::from(e.0[band])).sum::<f64>() / s.len() as f64
    };
    let (lo, hi) =
        (rho.0.iter().cloned().fold(1.0, f32::min), rho.0.iter().cloned().fold(0.0, f32::max));
    assert!(hi > 2.0 * lo, "the brick is far from grey: ρ from {lo} to {hi}");
    for band in 0..BANDS {
        let r = f64::from(rho.0[band]);
        let ratio = mean(&indirect, band) / mean(&direct, band);
        let expected = r / (1.0 - r);
        assert!(
            (ratio / expected - 1.0).abs() < 0.01,
            "band {band} (ρ = {r:.3}): indirect/direct {ratio:.4} against {expected:.4}"
        );
    }
}

/// A point 5 cm below the centre of a 1 × 1 m panel of 1000 cd/m², where the panel fills most
/// of its sky: sampled by solid angle, 256 samples give E = 4 · L · ½ [X/√(1 + X²)
/// atan(Y/√(1 + X²)) + (X ↔ Y)], X = Y = 10 (the rectangle's configuration factor, four
/// quarters), to 0.5 %.
#[test]
fn a_point_close_to_an_area_luminaire_is_sampled_by_solid_angle() {
    let dir = tempfile::tempdir().unwrap();
    let body = "[[lights]]\nkind = \"area\"\ncorner = [-0.5, -0.5, 0.05]\nu = [1.0, 0.0, 0.0]\n\
                v = [0.0, 1.0, 0.0]\nnormal = [0.0, 0.0, -1.0]\nluminance_cd_m2 = 1000.0\n\
                spectrum = \"lamp\"\n[[grids]]\nname = \"g\"\npoints = [[0.0, 0.0, 0.0]]\n\
                normal = [0.0, 0.0, 1.0]\n";
    let speck = "v 9 9 -1\nv 10 9 -1\nv 9 10 -1\nf 1 2 3\n";
    let scene = load(dir.path(), speck, body);
    let (direct, _) = irradiance(&scene, 256);
    let e = f64::from(restauro_render::tile::film_xyz(&direct[0])[1]);
    let x: f64 = 10.0;
    let quarter = 0.5 * 2.0 * x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
    let expected = 4.0 * 1000.0 * quarter;
    assert!((e / expected - 1.0).abs() < 0.005, "{e} lx against {expected}");
}
