//! The Marini–Rizzi Brownian-path Retinex (Marini & Rizzi, "A computational approach to color
//! adaptation effects", Image and Vision Computing 18, 2000; Rossi, Marini & Rizzi 2004, §2.5),
//! which simulates the lightness and chromatic adaptation of the human visual system.
//!
//! For each channel separately, the lightness of a pixel is the mean, over random paths ending
//! there, of the path's accumulated log ratio
//!
//! ```text
//!   s = Σₖ δₖ · log(I_{k+1} / I_k),   δₖ = 0 where |log(I_{k+1}/I_k)| ≤ threshold, else 1,
//!   and whenever s > 0, s ← 0        (the reset),
//! ```
//!
//! so that s at the end of a path is the log of the pixel's value relative to the brightest area
//! the path has crossed (Land & McCann's ratio–product–reset; the threshold discards the small
//! steps of smooth illumination gradients). The output lightness is exp(mean s): 1 for the
//! reference white, less elsewhere.
//!
//! **Paths.** A path is a walk on the pixel grid, one step to one of the 8 neighbours at a time,
//! with a persistent direction: at each step it turns 45° left or right with probability q each,
//! else goes straight; at the border it reflects as in a mirror on the border's outer edge. Its
//! large-scale limit is Brownian motion; the persistence length is a quarter of the image
//! diagonal, so the paths have the same shape relative to the image at any resolution. With no
//! length given, L is eight image diagonals: long enough that a path crosses the image several
//! times and meets its brightest areas, which is what lets the Retinex take the scene's white as
//! the white (measured on the test Mondrian, whose white is one patch in forty: with paths of
//! half a diagonal each cone class found a different local maximum and the colours of a D65
//! scene shifted by 9 ΔE00; with eight diagonals, by 0.8).
//!
//! **Shared paths.** A path's running value at every pixel it crosses is itself a sample for a
//! path ending there, so one path serves every pixel it visits once it is past a burn-in of L/4
//! steps: the samples are paths of L/4 to L steps, uniformly. Phase 1 starts enough paths at
//! uniformly random pixels to give each pixel about 2N samples (the counts are Poisson-like, so
//! fewer would leave many pixels short); phase 2 gives every pixel still short of N samples its
//! own paths ending exactly there, with lengths drawn from the same L/4..L, so every pixel has at
//! least N samples.
//!
//! **Exactness and determinism.** Logs are held in fixed point, 1/1024 of a natural-log unit
//! (a 0.1 % step in value, far below what a display shows), and the whole path function runs in
//! integers. Every random number is a function of (seed, phase, path) — phase-1 paths are
//! numbered, phase-2 paths are keyed by (pixel, index) — and samples are summed as integers,
//! whose addition is associative. The output is therefore bit-identical for any number of
//! threads and any order of work.

use crate::error::{Error, Result};
use crate::keyed_random::KeyedRng;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Where the reference white comes from.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum WhiteReference {
    /// The paper's behaviour: the brightest area a path crosses is white, whatever it is.
    #[default]
    Paper,
    /// Values above this percentile (per channel, 50–100) are clipped to it first, so light
    /// sources and sky in view do not become the white and darken everything else.
    Percentile(f64),
    /// Pixels marked as emitters (`true`) are clipped, per channel, to the brightest value of the
    /// pixels that are not, so they cannot become the white.
    ExcludeEmitters(Vec<bool>),
}

/// The parameters of the filter. They are part of a job: the same parameters and seed give
/// the same image.
#[derive(Clone, Debug, PartialEq)]
pub struct RetinexParams {
    /// N: the least number of path samples per pixel (1–4096).
    pub paths: u32,
    /// L: steps per path; `None` for eight image diagonals.
    pub length: Option<u32>,
    /// The threshold on |log ratio| below which a step counts as zero (natural-log units).
    pub threshold: f32,
    pub seed: u64,
    pub white: WhiteReference,
}

impl Default for RetinexParams {
    fn default() -> Self {
        Self { paths: 20, length: None, threshold: 0.01, seed: 0, white: WhiteReference::Paper }
    }
}

/// What a run did, for reports and tests.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RetinexStats {
    /// The path length L used.
    pub length: u32,
    /// Paths started in phase 1.
    pub shared_paths: u64,
    /// Paths added in phase 2 for pixels with fewer than N samples.
    pub top_up_paths: u64,
    /// Path steps taken in both phases.
    pub steps: u64,
    /// The smallest and largest number of samples of any pixel.
    pub min_samples: u32,
    pub max_samples: u32,
}

/// Fixed-point units per natural-log unit.
const LOG_SCALE: f32 = 1024.0;
/// Logs are stored relative to each channel's maximum and floored at e⁻²⁰ of it, so they lie in
/// −20 480..0 and fit an i16.
const LOG_FLOOR: f32 = -20.0;
/// A sample is clamped at s = −16 (a lightness of 1e-7 of white) so it fits in 15 bits; a
/// 32-bit sum then holds 2¹⁸ samples, and `paths` ≤ 4096 keeps every pixel far below that.
const S_MIN: i32 = -16 * 1024;
pub const MAX_PATHS: u32 = 4096;

/// The 8 neighbour steps in circular order, so that ±1 turns by 45°.
const STEPS: [(i32, i32); 8] =
    [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)];

/// The samples of one pixel: the sums of −s of the three channels in fixed point, and the
/// count. Each field stays below 2³² (see [`S_MIN`]); four lanes so that adding a sample is one
/// vector addition.
type Sums = [u32; 4];

#[inline]
fn add(sums: &mut Sums, s: [i32; 4]) {
    let q = [
        s[0].max(S_MIN).unsigned_abs(),
        s[1].max(S_MIN).unsigned_abs(),
        s[2].max(S_MIN).unsigned_abs(),
        1,
    ];
    for c in 0..4 {
        sums[c] += q[c];
    }
}

fn count(sums: &Sums) -> u32 {
    sums[3]
}

fn lightness(sums: &Sums) -> [f32; 3] {
    let n = f64::from(count(sums));
    std::array::from_fn(|c| (-f64::from(sums[c]) / (f64::from(LOG_SCALE) * n)).exp() as f32)
}

/// Phase 1 keeps one accumulator image per task; more than this many would cost more memory
/// than the parallelism is worth.
const MAX_ACCUMULATOR_IMAGES: usize = 8;

/// A walker on the pixel grid.
struct Walk<'a> {
    width: i32,
    height: i32,
    x: i32,
    y: i32,
    index: i32,
    direction: usize,
    /// Turn thresholds on 16-bit draws: below `left` turn left, below `right` turn right.
    left: u32,
    right: u32,
    rng: &'a mut KeyedRng,
    bits: u64,
    bits_left: u32,
}

impl Walk<'_> {
    #[inline]
    fn draw16(&mut self) -> u32 {
        if self.bits_left == 0 {
            self.bits = self.rng.next_u64();
            self.bits_left = 4;
        }
        self.bits_left -= 1;
        let v = (self.bits & 0xffff) as u32;
        self.bits >>= 16;
        v
    }

    /// One step; returns the new pixel index (the same pixel at a border reflection).
    #[inline]
    fn step(&mut self) -> usize {
        let r = self.draw16();
        if r < self.left {
            self.direction = (self.direction + 1) & 7;
        } else if r < self.right {
            self.direction = (self.direction + 7) & 7;
        }
        let (mut dx, mut dy) = STEPS[self.direction];
        // Reflect at the border as in a mirror placed on the border's outer edge: the step that
        // would leave the image lands on the border pixel again and the direction flips. This
        // is the walk on the unfolded plane folded back, so every pixel, the border included,
        // is visited equally often (mirroring the step instead would visit border pixels half
        // as often, like the ends of a path graph).
        let (out_x, out_y) =
            (!(0..self.width).contains(&(self.x + dx)), !(0..self.height).contains(&(self.y + dy)));
        if out_x || out_y {
            let (fx, fy) = (if out_x { -dx } else { dx }, if out_y { -dy } else { dy });
            self.direction = STEPS.iter().position(|&s| s == (fx, fy)).unwrap_or(self.direction);
            if out_x {
                dx = 0;
            }
            if out_y {
                dy = 0;
            }
        }
        self.x += dx;
        self.y += dy;
        self.index += dy * self.width + dx;
        self.index as usize
    }
}

/// Everything a path needs to know about the image.
struct Walker<'a> {
    /// Per pixel, the fixed-point log of each channel relative to the channel's maximum.
    logs: &'a [[i16; 4]],
    width: usize,
    height: usize,
    left: u32,
    right: u32,
    threshold: i32,
}

impl Walker<'_> {
    /// One step of the path function: the thresholded log ratio is added and the value reset
    /// to 0 when it would exceed it (the path has met an area brighter than all before).
    #[inline]
    fn accumulate(&self, s: &mut [i32; 4], from: [i16; 4], to: [i16; 4]) {
        // Four lanes (the fourth log is always 0, so its lane stays 0) so that the compiler
        // can do the three channels in one vector operation.
        for c in 0..4 {
            let r = i32::from(to[c]) - i32::from(from[c]);
            // A select, not a branch: whether a step crosses an edge is unpredictable.
            let delta = if r.abs() > self.threshold { r } else { 0 };
            s[c] = (s[c] + delta).min(0);
        }
    }

    /// Walks `steps` steps from `start` in a random initial direction and calls
    /// `visit(pixel, s)` with the running value after each step k = `from`..=steps.
    #[inline]
    fn run(
        &self,
        rng: &mut KeyedRng,
        start: usize,
        steps: u32,
        from: u32,
        mut visit: impl FnMut(usize, [i32; 4]),
    ) {
        let direction = rng.below(8) as usize;
        let mut walk = Walk {
            width: self.width as i32,
            height: self.height as i32,
            x: (start % self.width) as i32,
            y: (start / self.width) as i32,
            index: start as i32,
            direction,
            left: self.left,
            right: self.right,
            rng,
            bits: 0,
            bits_left: 0,
        };
        let mut prev = self.logs[start];
        let mut s = [0i32; 4];
        for k in 1..=steps {
            let pixel = walk.step();
            let cur = self.logs[pixel];
            self.accumulate(&mut s, prev, cur);
            prev = cur;
            if k >= from {
                visit(pixel, s);
            }
        }
    }
}

/// The image diagonal in pixels.
fn diagonal(width: usize, height: usize) -> f64 {
    ((width * width + height * height) as f64).sqrt()
}

/// Validate the image and parameters; returns the path length.
fn check(width: usize, height: usize, len: usize, params: &RetinexParams) -> Result<u32> {
    if width == 0 || height == 0 || width.checked_mul(height) != Some(len) {
        return Err(Error::Image {
            problem: format!("{width}×{height} does not match the {len} pixels given"),
        });
    }
    if len > i32::MAX as usize {
        return Err(Error::Image {
            problem: format!("{width}×{height} is more than 2³¹ pixels; split the image"),
        });
    }
    if !(1..=MAX_PATHS).contains(&params.paths) {
        return Err(Error::OutOfRange {
            quantity: "Retinex paths",
            value: f64::from(params.paths),
            expected: "1 to 4096 samples per pixel",
        });
    }
    if !(params.threshold.is_finite() && (0.0..=10.0).contains(&params.threshold)) {
        return Err(Error::OutOfRange {
            quantity: "Retinex threshold",
            value: f64::from(params.threshold),
            expected: "a log-ratio threshold from 0 to 10",
        });
    }
    if let WhiteReference::Percentile(p) = params.white
        && !(p.is_finite() && (50.0..=100.0).contains(&p))
    {
        return Err(Error::OutOfRange {
            quantity: "Retinex white percentile",
            value: p,
            expected: "a percentile from 50 to 100",
        });
    }
    if let WhiteReference::ExcludeEmitters(mask) = &params.white
        && mask.len() != len
    {
        return Err(Error::Image {
            problem: format!("the emitter mask has {} pixels, the image {len}", mask.len()),
        });
    }
    match params.length {
        Some(l) if (4..=1_000_000).contains(&l) => Ok(l),
        Some(l) => Err(Error::OutOfRange {
            quantity: "Retinex path length",
            value: f64::from(l),
            expected: "4 to 1 000 000 steps",
        }),
        None => Ok((8.0 * diagonal(width, height)).round().clamp(16.0, 1_000_000.0) as u32),
    }
}

/// The fixed-point log of every channel relative to the channel's maximum, with the white
/// reference applied; black pixels are floored at e⁻²⁰ of the maximum.
fn log_image(pixels: &[[f32; 3]], white: &WhiteReference) -> Result<Vec<[i16; 4]>> {
    if let Some(i) = pixels.iter().position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0)) {
        return Err(Error::Image {
            problem: format!(
                "pixel {i} is {:?}; the Retinex needs finite values ≥ 0 (map out-of-gamut \
                 colours before it)",
                pixels[i]
            ),
        });
    }
    let mut ceiling = [f32::INFINITY; 3];
    match white {
        WhiteReference::Paper => {}
        WhiteReference::Percentile(p) => {
            for (c, ceil) in ceiling.iter_mut().enumerate() {
                let mut values: Vec<f32> = pixels.iter().map(|px| px[c]).collect();
                let rank = ((p / 100.0) * (values.len() - 1) as f64).round() as usize;
                let (_, v, _) = values.select_nth_unstable_by(rank, f32::total_cmp);
                *ceil = *v;
            }
        }
        WhiteReference::ExcludeEmitters(mask) => {
            for (c, ceil) in ceiling.iter_mut().enumerate() {
                let max = pixels
                    .iter()
                    .zip(mask)
                    .filter(|(_, emitter)| !**emitter)
                    .map(|(px, _)| px[c])
                    .fold(f32::NEG_INFINITY, f32::max);
                if max.is_finite() {
                    *ceil = max;
                }
            }
        }
    }
    let max: [f32; 3] =
        std::array::from_fn(|c| pixels.iter().map(|p| p[c]).fold(0.0f32, f32::max).min(ceiling[c]));
    Ok(pixels
        .par_iter()
        .map(|p| {
            let mut out = [0i16; 4];
            for c in 0..3 {
                // A black channel (max 0) is uniformly at the floor: no ratios, lightness 1.
                let relative = if max[c] > 0.0 { (p[c].min(max[c]) / max[c]).ln() } else { 0.0 };
                out[c] = (relative.max(LOG_FLOOR) * LOG_SCALE).round() as i16;
            }
            out
        })
        .collect())
}

/// The Retinex lightness of each channel of `pixels` (row-major, `width` × `height`, any
/// non-negative linear values): 1 for the reference white. `progress(done, total)` is called
/// from worker threads as phase-1 paths finish.
pub fn retinex(
    pixels: &[[f32; 3]],
    width: usize,
    height: usize,
    params: &RetinexParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Vec<[f32; 3]>, RetinexStats)> {
    let length = check(width, height, pixels.len(), params)?;
    let logs = log_image(pixels, &params.white)?;
    let n = pixels.len();
    let steps = length - 1;
    let burn_in = length / 4;
    let samples_per_path = u64::from(steps - burn_in + 1);
    let persistence = (diagonal(width, height) / 4.0).max(4.0);
    // For a turn of ±45° with probability q each, the direction correlation per step is
    // 1 − 2q(1 − cos 45°); its persistence length is the reciprocal of one minus that.
    let q = (1.0 / (2.0 * (1.0 - std::f64::consts::FRAC_1_SQRT_2) * persistence)).min(1.0 / 3.0);
    let left = (q * 65536.0).round() as u32;
    let walker = Walker {
        logs: &logs,
        width,
        height,
        left,
        right: 2 * left,
        threshold: (params.threshold * LOG_SCALE).round() as i32,
    };

    // Phase 1: shared paths from uniformly random starts, about 2N samples per pixel. The paths
    // are split into contiguous ranges, one accumulator image each, summed at the end.
    let shared_paths = (2 * u64::from(params.paths) * n as u64).div_ceil(samples_per_path);
    let tasks = rayon::current_num_threads().clamp(1, MAX_ACCUMULATOR_IMAGES) as u64;
    let done = AtomicU64::new(0);
    const CHUNK: u64 = 256;
    let partials: Vec<Vec<Sums>> = (0..tasks)
        .into_par_iter()
        .map(|task| {
            let mut sums = vec![[0u32; 4]; n];
            let (first, end) = (shared_paths * task / tasks, shared_paths * (task + 1) / tasks);
            for path in first..end {
                let mut rng = KeyedRng::from_parts(&[params.seed, 1, path]);
                let start = rng.below(n as u32) as usize;
                walker.run(&mut rng, start, steps, burn_in, |pixel, s| add(&mut sums[pixel], s));
                if (path - first + 1) % CHUNK == 0 || path + 1 == end {
                    let step = (path - first) % CHUNK + 1;
                    progress(done.fetch_add(step, Ordering::Relaxed) + step, shared_paths);
                }
            }
            sums
        })
        .collect();
    let mut partials = partials.into_iter();
    let mut sums = partials.next().unwrap_or_else(|| vec![[0u32; 4]; n]);
    for partial in partials {
        sums.par_iter_mut().zip(partial.par_iter()).for_each(|(a, b)| {
            for c in 0..4 {
                a[c] += b[c];
            }
        });
    }

    // Phase 2: every pixel short of N samples gets its own paths ending there. A path ending at
    // p is walked from p outwards and read backwards (the walk is reversible), so its value at
    // p is that of a path from the far end to p.
    let short: Vec<(usize, u32)> = sums
        .par_iter()
        .enumerate()
        .filter_map(|(p, s)| (count(s) < params.paths).then(|| (p, params.paths - count(s))))
        .collect();
    let top_up_paths: u64 = short.iter().map(|&(_, d)| u64::from(d)).sum();
    let top_ups: Vec<(usize, Sums, u64)> = short
        .par_iter()
        .map_init(
            || Vec::with_capacity(length as usize),
            |trail, &(pixel, deficit)| {
                let mut total = [0u32; 4];
                let mut walked = 0;
                for j in 0..deficit {
                    let mut rng =
                        KeyedRng::from_parts(&[params.seed, 2, pixel as u64, u64::from(j)]);
                    let k = burn_in + rng.below(steps - burn_in + 1);
                    trail.clear();
                    trail.push(pixel);
                    walker.run(&mut rng, pixel, k, 1, |p, _| trail.push(p));
                    let mut s = [0i32; 4];
                    for pair in trail.windows(2).rev() {
                        walker.accumulate(&mut s, logs[pair[1]], logs[pair[0]]);
                    }
                    add(&mut total, s);
                    walked += u64::from(k);
                }
                (pixel, total, walked)
            },
        )
        .collect();
    let mut top_up_steps = 0;
    for (pixel, extra, walked) in top_ups {
        for c in 0..4 {
            sums[pixel][c] += extra[c];
        }
        top_up_steps += walked;
    }

    let min_samples = sums.iter().map(count).min().unwrap_or(0);
    let max_samples = sums.iter().map(count).max().unwrap_or(0);
    let out = sums.par_iter().map(lightness).collect();
    let stats = RetinexStats {
        length,
        shared_paths,
        top_up_paths,
        steps: shared_paths * u64::from(steps) + top_up_steps,
        min_samples,
        max_samples,
    };
    Ok((out, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(pixels: &[[f32; 3]], w: usize, h: usize, params: &RetinexParams) -> Vec<[f32; 3]> {
        retinex(pixels, w, h, params, &|_, _| {}).unwrap().0
    }

    #[test]
    fn a_uniform_image_stays_uniform_and_white() {
        let pixels = vec![[0.3f32, 0.5, 0.2]; 40 * 30];
        for p in run(&pixels, 40, 30, &RetinexParams::default()) {
            assert_eq!(p, [1.0, 1.0, 1.0]);
        }
    }

    #[test]
    fn every_pixel_gets_at_least_n_samples() {
        let pixels: Vec<[f32; 3]> =
            (0..64 * 48).map(|i| [(i % 7) as f32 + 1.0, (i % 5) as f32 + 1.0, 1.0]).collect();
        for paths in [1, 5, 20] {
            let params = RetinexParams { paths, ..Default::default() };
            let (_, stats) = retinex(&pixels, 64, 48, &params, &|_, _| {}).unwrap();
            assert!(stats.min_samples >= paths, "{stats:?}");
        }
    }

    /// Two halves, the left twice as bright in every channel: the bright half is white, the
    /// dark half has lightness ½ wherever paths have crossed the edge (all of them do here).
    #[test]
    fn a_step_edge_gives_the_ratio_to_the_brightest_area() {
        let (w, h) = (32, 16);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| if i % w < w / 2 { [2.0, 4.0, 8.0] } else { [1.0, 2.0, 4.0] })
            .collect();
        let params = RetinexParams { paths: 50, length: Some(800), ..Default::default() };
        let out = run(&pixels, w, h, &params);
        for (i, p) in out.iter().enumerate() {
            let expect = if i % w < w / 2 { 1.0 } else { 0.5 };
            for v in p {
                assert!((v - expect).abs() < 0.01, "pixel {i}: {p:?}");
            }
        }
    }

    #[test]
    fn the_threshold_discards_smooth_gradients() {
        // A ramp of 0.2 % per pixel: with a threshold of 0.01 every step is ignored and the
        // whole image reads as white; without one, the ramp shows: paths long enough to cross
        // the image find the bright end 1.002⁶³ = 1.134 times brighter than pixel 0.
        let (w, h) = (64, 8);
        let pixels: Vec<[f32; 3]> =
            (0..w * h).map(|i| [1.002f32.powi((i % w) as i32); 3]).collect();
        let flat = run(&pixels, w, h, &RetinexParams { threshold: 0.01, ..Default::default() });
        assert!(flat.iter().all(|p| *p == [1.0, 1.0, 1.0]));
        let long = RetinexParams { threshold: 0.0, length: Some(1000), ..Default::default() };
        let ramp = run(&pixels, w, h, &long);
        assert!((ramp[0][0] - 1.0 / 1.134).abs() < 0.01, "{:?}", ramp[0]);
        assert_eq!(ramp[w - 1], [1.0; 3]);
    }

    #[test]
    fn the_output_is_the_same_for_any_thread_count() {
        let (w, h) = (50, 37);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let x = (i % w) as f32;
                let y = (i / w) as f32;
                [1.0 + (x * 0.3).sin().abs(), 1.0 + (y * 0.2).cos().abs(), 0.5 + (x / 50.0)]
            })
            .collect();
        let params = RetinexParams { paths: 8, seed: 77, ..Default::default() };
        let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
        let one = pool(1).install(|| run(&pixels, w, h, &params));
        let two = pool(2).install(|| run(&pixels, w, h, &params));
        let three = pool(3).install(|| run(&pixels, w, h, &params));
        assert_eq!(one, two);
        assert_eq!(one, three);
        // Another seed gives another (noisy) estimate.
        let other = run(&pixels, w, h, &RetinexParams { seed: 78, ..params });
        assert_ne!(one, other);
    }

    #[test]
    fn a_light_source_in_view_does_not_darken_the_scene_when_excluded() {
        let (w, h) = (40, 20);
        let mut pixels = vec![[0.5f32, 0.5, 0.5]; w * h];
        // A white patch (the scene's white) and a lamp 100 times brighter.
        for y in 0..6 {
            for x in 0..6 {
                pixels[y * w + x] = [1.0; 3];
                pixels[y * w + x + 30] = [100.0; 3];
            }
        }
        let mask: Vec<bool> = pixels.iter().map(|p| p[0] > 10.0).collect();
        let base = RetinexParams { paths: 40, length: Some(400), ..Default::default() };
        let paper = run(&pixels, w, h, &base);
        let excluded = run(
            &pixels,
            w,
            h,
            &RetinexParams { white: WhiteReference::ExcludeEmitters(mask), ..base.clone() },
        );
        let percentile =
            run(&pixels, w, h, &RetinexParams { white: WhiteReference::Percentile(90.0), ..base });
        let grey = 10 * w + 20;
        assert!(paper[grey][0] < 0.1, "paper: the lamp is the white: {:?}", paper[grey]);
        assert!((excluded[grey][0] - 0.5).abs() < 0.05, "{:?}", excluded[grey]);
        assert!(percentile[grey][0] > 0.9, "{:?}", percentile[grey]);
    }

    #[test]
    fn bad_input_is_refused() {
        let ok = vec![[1.0f32; 3]; 4];
        let p = RetinexParams::default();
        assert!(retinex(&ok, 3, 2, &p, &|_, _| {}).is_err());
        let nan = vec![[1.0, f32::NAN, 1.0]; 4];
        assert!(retinex(&nan, 2, 2, &p, &|_, _| {}).is_err());
        for bad in [
            RetinexParams { paths: 0, ..Default::default() },
            RetinexParams { paths: 5000, ..Default::default() },
            RetinexParams { threshold: -1.0, ..Default::default() },
            RetinexParams { length: Some(2), ..Default::default() },
            RetinexParams { white: WhiteReference::Percentile(120.0), ..Default::default() },
            RetinexParams {
                white: WhiteReference::ExcludeEmitters(vec![false]),
                ..Default::default()
            },
        ] {
            assert!(retinex(&ok, 2, 2, &bad, &|_, _| {}).is_err(), "{bad:?}");
        }
        // A one-pixel-wide image is valid.
        assert!(retinex(&[[1.0f32; 3]; 5], 1, 5, &p, &|_, _| {}).is_ok());
    }
}
