//! `restauro bench adaptive`: the CPU time to reach a given per-pixel error, adaptive sampling
//! against a fixed count (`restauro_render::adaptive`), on the demo's facade under the summer
//! sun (or `--scene-file`), path traced.
//!
//! Each render's error is measured against a reference of 8 × `--spp` samples per pixel with
//! another seed, so that its samples are independent of the renders': per pixel the relative
//! luminance error |Y − Y_ref| / (Y_ref + 0.005 cd/m²), summarised by its root mean square and
//! its 95th percentile over the image. (The reference's own noise is in the figures too: about
//! 1/√8 of that of the fixed render at `--spp`.) The fixed renders take `--spp`/4, `--spp`/2 and
//! `--spp` samples; the adaptive ones stop each pixel at noise targets of 20, 15, 10 and 5 % with
//! `--spp` as the cap. For each adaptive render the CPU time a fixed count needs for the same RMS
//! error is read off the fixed renders' own error, which falls as 1/√samples.

use crate::BenchArgs;
use crate::cpu::timed;
use crate::error::BenchError;
use restauro_assets::load_scene;
use restauro_render::adaptive::FLOOR_CD_M2;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::{Limits, LoadedScene};
use restauro_scene::scene_file::Integrator;
use serde::Serialize;

#[derive(Serialize)]
struct AdaptiveBench {
    benchmark: &'static str,
    scene: String,
    width: u32,
    height: u32,
    reference_spp: u32,
    reference_cpu_s: f64,
    runs: Vec<Measured>,
}

#[derive(Serialize)]
struct Measured {
    /// "fixed" or "adaptive".
    sampling: &'static str,
    /// The samples per pixel (fixed) or the cap (adaptive).
    spp: u32,
    /// The noise target, a fraction of each pixel's luminance (adaptive only).
    noise_target: Option<f32>,
    mean_samples_per_pixel: f64,
    cpu_s: f64,
    wall_s: f64,
    rms_relative_error: f64,
    p95_relative_error: f64,
    /// Adaptive only: the CPU seconds a fixed count needs for the same RMS error, and how many
    /// times this render's time that is.
    fixed_cpu_s_at_same_error: Option<f64>,
    speed_up: Option<f64>,
}

/// One render of the whole image: its luminance, its samples per pixel, the CPU and wall time.
struct Render {
    luminance: Vec<f32>,
    mean_samples: f64,
    cpu_s: f64,
    wall_s: f64,
}

fn render(scene: &LoadedScene, settings: Settings) -> Result<Render, BenchError> {
    let prepared = PreparedScene::new(scene, None, settings)?;
    let full = Rect { x: 0, y: 0, width: prepared.camera.width, height: prepared.camera.height };
    let tile = std::sync::Mutex::new(None);
    let (_, _, wall_s, cpu_s) = timed(2, || {
        let t = render_tile(&prepared, full, false);
        let rays = t.rays;
        *tile.lock().unwrap_or_else(|p| p.into_inner()) = Some(t);
        rays
    })?;
    let tile = tile.into_inner().unwrap_or_else(|p| p.into_inner()).expect("rendered once");
    let pixels = tile.xyz.len() as f64;
    let mean_samples = match &tile.samples {
        Some(n) => n.iter().map(|&n| f64::from(n)).sum::<f64>() / pixels,
        None => f64::from(settings.samples_per_pixel),
    };
    let luminance = tile.xyz.iter().map(|p| p[1]).collect();
    Ok(Render { luminance, mean_samples, cpu_s, wall_s })
}

/// The RMS and the 95th percentile of the per-pixel relative luminance error.
fn errors(image: &[f32], reference: &[f32]) -> (f64, f64) {
    let mut e: Vec<f64> = image
        .iter()
        .zip(reference)
        .map(|(&y, &r)| (f64::from(y) - f64::from(r)).abs() / (f64::from(r) + FLOOR_CD_M2))
        .collect();
    let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
    e.sort_by(f64::total_cmp);
    (rms, e[(e.len() * 95 / 100).min(e.len() - 1)])
}

pub fn bench(args: &BenchArgs) -> Result<String, BenchError> {
    let say = |what: String| restauro_cluster::progress::say(&format!("bench adaptive: {what}"));
    let (_dir, path) = match &args.scene_file {
        Some(p) => (None, p.clone()),
        None => {
            let (dir, p) = crate::aosta_scene("restauro-bench-adaptive-", args)?;
            (Some(dir), p)
        }
    };
    let mut scene = load_scene(&path, &Limits::default())
        .map_err(|source| BenchError::SceneNamed { what: path.display().to_string(), source })?;
    (scene.camera.width, scene.camera.height) = (args.width as u32, args.height as u32);
    let cap = args.spp.max(4);
    let base = Settings {
        integrator: Integrator::Path,
        samples_per_pixel: cap,
        max_depth: scene.file.render.max_depth,
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    let reference_spp = 8 * cap;
    say(format!("the reference, {reference_spp} samples per pixel"));
    let reference =
        render(&scene, Settings { samples_per_pixel: reference_spp, seed: 1_000_003, ..base })?;
    let mut runs = Vec::new();
    for spp in [cap / 4, cap / 2, cap] {
        say(format!("fixed, {spp} samples per pixel"));
        let r = render(&scene, Settings { samples_per_pixel: spp, ..base })?;
        runs.push(measured("fixed", spp, None, &r, &reference.luminance));
    }
    // The fixed render at the cap: its error and time, to which a fixed count's scale.
    let (fixed_error, fixed_cpu) = (runs[2].rms_relative_error, runs[2].cpu_s);
    for target in [0.2f32, 0.15, 0.1, 0.05] {
        say(format!("adaptive, noise target {target}, at most {cap} samples per pixel"));
        let r = render(&scene, Settings { noise_target: target, ..base })?;
        let mut m = measured("adaptive", cap, Some(target), &r, &reference.luminance);
        // Error ∝ 1/√samples, time ∝ samples: time at error e = t · (e_fixed / e)².
        let same = fixed_cpu * (fixed_error / m.rms_relative_error).powi(2);
        m.fixed_cpu_s_at_same_error = Some(same);
        m.speed_up = Some(same / m.cpu_s);
        runs.push(m);
    }
    let report = AdaptiveBench {
        benchmark: "adaptive",
        scene: path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
        width: scene.camera.width,
        height: scene.camera.height,
        reference_spp,
        reference_cpu_s: reference.cpu_s,
        runs,
    };
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}

fn measured(
    sampling: &'static str,
    spp: u32,
    noise_target: Option<f32>,
    r: &Render,
    reference: &[f32],
) -> Measured {
    let (rms, p95) = errors(&r.luminance, reference);
    Measured {
        sampling,
        spp,
        noise_target,
        mean_samples_per_pixel: r.mean_samples,
        cpu_s: r.cpu_s,
        wall_s: r.wall_s,
        rms_relative_error: rms,
        p95_relative_error: p95,
        fixed_cpu_s_at_same_error: None,
        speed_up: None,
    }
}
