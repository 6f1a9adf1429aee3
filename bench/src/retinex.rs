//! `restauro bench retinex`: the seen image of a synthetic Mondrian, timed (adapted to the
//! light, and by the Retinex alone).

use crate::args::BenchArgs;
use crate::error::BenchError;
use restauro_spectral::keyed_random::KeyedRng;
use restauro_spectral::retinex::{PhaseSeconds, RetinexParams, RetinexStats};
use restauro_spectral::seen::{Adaptation, SeenParams, seen_image};
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
pub(crate) struct RetinexBench {
    benchmark: &'static str,
    /// What the seen image adapts to: `light` (the farm's seen image: the known light, the
    /// paths for lightness) or `retinex` (the paths alone, in CAT02 cones).
    adaptation: String,
    width: usize,
    height: usize,
    threads: usize,
    paths: u32,
    length: u32,
    threshold: f32,
    repeats: u32,
    /// Wall-clock seconds of each run.
    seconds: Vec<f64>,
    best_seconds: f64,
    megapixels_per_second: f64,
    /// Path steps (pixel visits) per second in the best run, phase 1 and phase 2 together.
    million_steps_per_second: f64,
    shared_paths: u64,
    top_up_paths: u64,
    min_samples: u32,
    max_samples: u32,
    /// The phases of the best run.
    best_phase_seconds: PhaseSeconds,
}

/// The smooth illumination over [`mondrian`]'s pixel `i`: 0.4 to 1.
fn shade(i: usize, width: usize, height: usize) -> f32 {
    let (x, y) = ((i % width) as f32 / width as f32, (i / width) as f32 / height as f32);
    0.4 + 0.6 * (1.0 - 0.5 * (x * x + y))
}

/// The light on [`mondrian`]'s pixel `i`, as a render's adapting white: a D65 white of
/// 100 cd/m² times the card's shading (scotopic: D65's S/P ratio, 2.47).
fn lit(i: usize, width: usize, height: usize) -> [f32; 4] {
    let y = 100.0 * shade(i, width, height);
    [0.9504 * y, y, 1.0888 * y, 2.47 * y]
}

/// A deterministic test card: rectangles of random colours over a smooth illumination gradient,
/// like the Mondrians Land used.
pub fn mondrian(width: usize, height: usize, seed: u64) -> Vec<[f32; 3]> {
    let mut img = vec![[0.0f32; 3]; width * height];
    let mut rng = KeyedRng::from_parts(&[seed, 0x6d6f6e64]);
    for _ in 0..200 {
        let (x0, y0) = (rng.below(width as u32) as usize, rng.below(height as u32) as usize);
        let (dx, dy) =
            (1 + rng.below(width as u32 / 4) as usize, 1 + rng.below(height as u32 / 4) as usize);
        let colour =
            [0.05 + 0.9 * rng.next_f32(), 0.05 + 0.9 * rng.next_f32(), 0.05 + 0.9 * rng.next_f32()];
        for y in y0..(y0 + dy).min(height) {
            for x in x0..(x0 + dx).min(width) {
                img[y * width + x] = colour;
            }
        }
    }
    for (i, px) in img.iter_mut().enumerate() {
        let shade = shade(i, width, height);
        for v in px.iter_mut() {
            *v = (*v).max(0.02) * shade * 100.0;
        }
    }
    img
}

/// Times the seen image of a test card by `adaptation` (`restauro bench retinex`).
pub(crate) fn seen_bench(
    args: &BenchArgs,
    adaptation: Adaptation,
) -> Result<RetinexBench, BenchError> {
    let (w, h) = (args.width, args.height);
    let img = mondrian(w, h, 1);
    let white: Vec<[f32; 4]> = (0..w * h).map(|i| lit(i, w, h)).collect();
    let params = SeenParams {
        retinex: RetinexParams { paths: args.paths, ..Default::default() },
        ..Default::default()
    };
    let mut seconds = Vec::new();
    let mut stats: Option<RetinexStats> = None;
    for _ in 0..args.repeats.max(1) {
        let t = Instant::now();
        let (_, report) = seen_image(&img, Some(&white), (w, h), &params, adaptation, &|_, _| {})?;
        let run = t.elapsed().as_secs_f64();
        if seconds.iter().all(|&best| run < best) {
            stats = Some(report.retinex);
        }
        seconds.push(run);
    }
    let stats = stats.expect("at least one run");
    let best = seconds.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(RetinexBench {
        benchmark: "retinex",
        adaptation: match adaptation {
            Adaptation::Light => "light".into(),
            Adaptation::Retinex(_) => "retinex".into(),
        },
        width: w,
        height: h,
        threads: rayon::current_num_threads(),
        paths: params.retinex.paths,
        length: stats.length,
        threshold: params.retinex.threshold,
        repeats: args.repeats.max(1),
        best_seconds: best,
        megapixels_per_second: (w * h) as f64 / best / 1e6,
        million_steps_per_second: stats.steps as f64 / best / 1e6,
        seconds,
        shared_paths: stats.shared_paths,
        top_up_paths: stats.top_up_paths,
        min_samples: stats.min_samples,
        max_samples: stats.max_samples,
        best_phase_seconds: stats.seconds,
    })
}
