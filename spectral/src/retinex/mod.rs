//! The Marini–Rizzi Brownian-path Retinex (Marini & Rizzi, "A computational approach to color
//! adaptation effects", Image and Vision Computing 18, 2000; Rossi, Marini & Rizzi 2004, §2.5),
//! which simulates the lightness and chromatic adaptation of the human visual system.
//!
//! For each channel separately, a pixel's lightness is its value relative to the white its
//! paths have found: each random path ending there carries, by the ratio–product–reset with
//! threshold, the brightest area it has crossed (`paths`), and the pixel's white is the
//! geometric mean of those, so
//!
//! ```text
//!   lightness(p) = I(p) / exp(mean over paths of log w),   1 for the reference white.
//! ```
//!
//! The parts, each in its own module:
//!
//! * [`walk`] — the paths: isotropic persistent random walks in the continuous plane, Brownian
//!   on large scales, with no preferred direction (the old lattice walk drew a cross-hatch);
//! * [`white`] — what the paths read: a cleaned image in which the white must be an *area*
//!   (a 3×3 median, then a bilateral mean that averages the image's own noise), so a firefly,
//!   a glint or Monte Carlo noise cannot be the white, and light sources in view are passed
//!   over, so the sky is neither the building's white nor a wall across its ratios;
//! * [`frameworks`] — the regions lit by the same light (the sun, the sky in the shadows);
//! * [`grid`] — what the paths walk on: the pixels, or on a large image cells of 2×2 (4×4, …)
//!   pixels, each with its brightest pixel's value, whose pixels share their samples;
//! * [`paths`] — the path function and the two phases that give every pixel ≥ N samples;
//! * [`tiling`] — the order in which the paths' images are kept: tiles, for the caches.
//!
//! **Reach: how local the adaptation is.** The paths' extent is the adaptation field: a
//! pixel's white is found among the areas its paths reach. `reach` is the RMS distance from a
//! path's start to the points where it samples, as a fraction of the image diagonal (in the
//! unfolded plane: beyond about half a diagonal the reflected paths cover the whole image);
//! the walk's persistence length is a tenth of it, and the path length L is chosen so that the
//! samples (steps L/4..L) lie at that RMS distance. See [`DEFAULT_REACH`] for the default and
//! why. Distances and lengths are in steps of the walk's grid: a pixel, or on an image with a
//! diagonal over [`grid::WALK_DIAGONAL_PX`] a cell (see [`grid`] for why and what it changes:
//! at 1920×1080 the seen image moved by less than the paths' own noise, and the paths took 4.5
//! times fewer steps).
//!
//! **Frameworks: mixed light.** Under a warm sun and a blue sky, one white for the whole image
//! makes the sky-lit shadows blue, and a smaller reach cannot help (a neighbourhood's brightest
//! area in each channel is its white, and a uniform scene takes casts). With the frameworks of
//! illumination given (`RetinexParams::frameworks`: for a render, which lights light each
//! pixel), the paths still find the white of the whole image, and each framework is then
//! adapted to its own light, as anchoring theory has it (Gilchrist et al. 1999): the ratio r of
//! the brightest framework's light to its own, per channel, is read across the edges between
//! them (see [`frameworks`]), and
//!
//! ```text
//!   log ℓ = log ℓ_image + (r − r̄) + w · r̄,     r̄ the mean of r over the channels,
//! ```
//!
//! so the colour of a framework's light is discounted whole (a white card in the shadow is
//! white) and its level with the framework's weight w ([`DEFAULT_FRAMEWORK_WEIGHT`]): the
//! anchoring changes lightness, not chromaticity. (Letting each framework's paths find a white
//! of their own, per channel, was tried first: in the noisy, partly bounce-lit shadows of the
//! demo's facade each channel's white was a different surface, and the shadows turned olive.)
//!
//! The output is a lightness per channel; where a pixel is brighter than its white (a light
//! source, a highlight smaller than the white's least area) it is above 1.

mod frameworks;
mod grid;
mod paths;
mod tiling;
mod walk;
mod white;

pub(crate) use frameworks::{Frameworks, counted, frameworks as frameworks_of};
pub use frameworks::{MAX_FRAMEWORKS, MIN_SHARE as MIN_FRAMEWORK_SHARE};

use crate::error::{Error, Result};
use paths::{Walker, count};
use rayon::prelude::*;
use walk::{Turning, mean_square_distance};
use white::{LOG_SCALE, white_image};

/// Where a path's chain of ratios starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Anchor {
    /// The paper's: a path takes the pixel it starts from as white until it crosses something
    /// brighter, so each pixel's white is the brightest area its paths found.
    #[default]
    Brightest,
    /// The image is already relative to a known white (1 is white; the seen image divides the
    /// render by the light that falls there, `crate::seen`): a path starts with its start's own
    /// value as its lightness, s₀ = min(0, log I_start), and only an area brighter than white
    /// resets it. Without thresholds or resets a pixel's lightness is then its value; the paths
    /// still discount smooth gradients (below the threshold) and make an area above white the
    /// white of what they cross after it.
    Known,
}

/// What may be the white.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WhiteReference {
    /// An area: the paths read the cleaned image (3×3 median and noise-adaptive bilateral
    /// mean; see `white`), so a single pixel — a firefly, a glint, noise — is not the white.
    #[default]
    Area,
    /// The paper's: the brightest pixel a path crosses, whatever it is.
    Paper,
}

/// The parameters of the filter. They are part of a job: the same parameters and seed give
/// the same image.
#[derive(Clone, Debug, PartialEq)]
pub struct RetinexParams {
    /// N: the least number of path samples per pixel (1–4096); on a grid of cells, per cell,
    /// whose samples all its pixels take.
    pub paths: u32,
    /// The RMS distance from a path's start to its samples, as a fraction of the image
    /// diagonal (0.01–4): the extent of the adaptation field.
    pub reach: f64,
    /// L: the length of a path in pixels (steps of one pixel; on a large image's grid of
    /// cells, L / cell steps of a cell); `None` for the length that gives `reach`.
    pub length: Option<u32>,
    /// The threshold on |log ratio| below which a step counts as zero (natural-log units).
    pub threshold: f32,
    pub seed: u64,
    pub white: WhiteReference,
    pub anchor: Anchor,
    /// Pixels that show a light source (the sky, an emitter), `true`; the paths pass over them.
    pub emitters: Option<Vec<bool>>,
    /// Per pixel, a key of its framework of illumination: pixels with the same key are lit
    /// by the same light (a render's mask of the lights that light each pixel). `None`: one.
    pub frameworks: Option<Vec<u32>>,
    /// w, the weight (0–1) of a surface's own framework in its lightness; 1 − w is the whole
    /// image's. Chromatic adaptation is to the framework's light whatever w.
    pub framework_weight: f32,
}

/// The default weight of a surface's own framework in its lightness: the midpoint. In
/// Gilchrist et al.'s account (1999, "co-determination") the weight of a local framework grows
/// with its size and articulation and is rarely all or nothing; we do not model that, and take
/// the midpoint: a shadow is seen half-way between its own light and the sun's, darker than the
/// sunlit stone, as people see it, and with its detail. The neutrality of colours does not
/// depend on it.
pub const DEFAULT_FRAMEWORK_WEIGHT: f32 = 0.5;

/// The default reach, in image diagonals: global adaptation. Measured on the test Mondrian
/// (`tests/retinex_mondrian.rs`, one white patch in forty, D65, chroma-only mean ΔE00 of the
/// Retinex output against the image, in Hunt–Pointer–Estévez channels): reach 0.3 → 6.5,
/// 0.5 → 3.3–5.0, 1 → 1.0–2.9, 2 and 3 → 0.63 (the old lattice walk, eight diagonals long:
/// 0.8); at 3 in the CAT02 channels now used, 0.54. A longer path covers more of the image,
/// which matters for a small white: 3 finds a white card of 3 % of the image from 96 % of the
/// paths. With a reach below the image, each neighbourhood's brightest area in each channel is
/// its white, and where those are different surfaces (a yellow's L and M, a blue's S) a D65
/// scene takes a cast no observer sees; the paths must reach the scene's white.
pub const DEFAULT_REACH: f64 = 3.0;
/// The walk's persistence length as a share of the reach: short, so that a path covers the
/// area it reaches (a straighter walk of the same reach crosses fewer areas: at persistence
/// 0.5 reach the D65 Mondrian above shifts by 2.9 instead of 1.5 at reach 1).
const PERSISTENCE_OF_REACH: f64 = 0.1;

impl Default for RetinexParams {
    fn default() -> Self {
        Self {
            paths: 20,
            reach: DEFAULT_REACH,
            length: None,
            threshold: 0.01,
            seed: 0,
            white: WhiteReference::Area,
            anchor: Anchor::Brightest,
            emitters: None,
            frameworks: None,
            framework_weight: DEFAULT_FRAMEWORK_WEIGHT,
        }
    }
}

/// What a run did, for reports and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct RetinexStats {
    /// The path length L used, in steps of the walk's grid.
    pub length: u32,
    /// The side of the walk's grid's cells, in pixels (1: the paths walk on the pixels).
    pub cell_px: u32,
    /// The walk's persistence length, in pixels.
    pub persistence_px: f64,
    /// Paths started in phase 1.
    pub shared_paths: u64,
    /// Paths added in phase 2 for pixels with fewer than N samples.
    pub top_up_paths: u64,
    /// Path steps taken in both phases.
    pub steps: u64,
    /// The smallest and largest number of samples of any cell of the walk's grid (each of its
    /// pixels has them).
    pub min_samples: u32,
    pub max_samples: u32,
    /// The noise σ of each channel (natural-log units) the cleaned image was made for, in each
    /// framework (the largest first).
    pub noise: Vec<[f32; 3]>,
    /// The frameworks of illumination told apart (1 when none were given or one covers all).
    pub frameworks: usize,
    /// Where the time went (wall clock), for `restauro bench retinex`.
    pub seconds: PhaseSeconds,
}

/// The wall-clock seconds of each phase of a run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhaseSeconds {
    /// The frameworks and the cleaned image the paths read (median, opening, bilateral).
    pub cleaning: f64,
    /// Phase 1: the shared paths.
    pub shared_paths: f64,
    /// Phase 2: the paths of the pixels short of N samples.
    pub top_up: f64,
    /// Each pixel's lightness from its samples.
    pub lightness: f64,
}

pub const MAX_PATHS: u32 = 4096;
const MAX_LENGTH: u32 = 1_000_000;

/// The image diagonal in pixels.
fn diagonal(width: usize, height: usize) -> f64 {
    ((width * width + height * height) as f64).sqrt()
}

/// The walk of a reach: its persistence length (px) and the path length L whose samples
/// (steps L/4..L, uniformly) lie at RMS distance `reach_px` from the start.
fn walk_for_reach(reach_px: f64) -> (f64, u32) {
    let persistence = (reach_px * PERSISTENCE_OF_REACH).max(1.0);
    let mean_square = |l: f64| {
        // The mean of the worm-like chain's ⟨r²⟩ over k = L/4..L (Simpson's rule is exact
        // enough: the integrand is smooth).
        let (a, b) = (l / 4.0, l);
        let m = 0.5 * (a + b);
        (mean_square_distance(a, persistence)
            + 4.0 * mean_square_distance(m, persistence)
            + mean_square_distance(b, persistence))
            / 6.0
    };
    let target = reach_px * reach_px;
    let (mut lo, mut hi) = (4.0f64, f64::from(MAX_LENGTH));
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mean_square(mid) < target { lo = mid } else { hi = mid }
    }
    (persistence, hi.round().clamp(16.0, f64::from(MAX_LENGTH)) as u32)
}

fn out_of_range(quantity: &'static str, value: f64, expected: &'static str) -> Error {
    Error::OutOfRange { quantity, value, expected }
}

/// Validate the image and parameters.
pub(crate) fn check(
    pixels: &[[f32; 3]],
    width: usize,
    height: usize,
    params: &RetinexParams,
) -> Result<()> {
    let len = pixels.len();
    if width == 0 || height == 0 || width.checked_mul(height) != Some(len) {
        return Err(Error::Image {
            problem: format!("{width}×{height} does not match the {len} pixels given"),
        });
    }
    if width >= 1 << 19 || height >= 1 << 19 || len > i32::MAX as usize {
        return Err(Error::Image {
            problem: format!("{width}×{height} is too large for the Retinex; split the image"),
        });
    }
    if !(1..=MAX_PATHS).contains(&params.paths) {
        return Err(out_of_range(
            "Retinex paths",
            f64::from(params.paths),
            "1 to 4096 samples per pixel",
        ));
    }
    if !(params.threshold.is_finite() && (0.0..=10.0).contains(&params.threshold)) {
        return Err(out_of_range(
            "Retinex threshold",
            f64::from(params.threshold),
            "a log-ratio threshold from 0 to 10",
        ));
    }
    if !(params.reach.is_finite() && (0.01..=4.0).contains(&params.reach)) {
        return Err(out_of_range("Retinex reach", params.reach, "0.01 to 4 image diagonals"));
    }
    if let Some(l) = params.length
        && !(4..=MAX_LENGTH).contains(&l)
    {
        return Err(out_of_range("Retinex path length", f64::from(l), "4 to 1 000 000 steps"));
    }
    if let Some(mask) = &params.emitters
        && mask.len() != len
    {
        return Err(Error::Image {
            problem: format!("the emitter mask has {} pixels, the image {len}", mask.len()),
        });
    }
    if let Some(keys) = &params.frameworks
        && keys.len() != len
    {
        return Err(Error::Image {
            problem: format!("the framework map has {} pixels, the image {len}", keys.len()),
        });
    }
    if !(params.framework_weight.is_finite() && (0.0..=1.0).contains(&params.framework_weight)) {
        return Err(out_of_range(
            "Retinex framework weight",
            f64::from(params.framework_weight),
            "a weight from 0 to 1",
        ));
    }
    if let Some(i) = pixels.iter().position(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0)) {
        return Err(Error::Image {
            problem: format!(
                "pixel {i} is {:?}; the Retinex needs finite values ≥ 0 (map out-of-gamut \
                 colours before it)",
                pixels[i]
            ),
        });
    }
    Ok(())
}

/// A pixel's lightness from its samples: its value relative to its cleaned value (the detail
/// the cleaning took out: noise, a firefly) times the cleaned value relative to the mean white
/// found. A light source is its value relative to the white found where the paths left the
/// last surface; a pixel no path reached from a surface (inside a large sky) is relative to
/// the image's white. `adaptation` is the log factor of the pixel's framework (see
/// [`framework_adaptation`]).
fn lightness(
    pixel: [f32; 3],
    white: &white::WhiteImage,
    p: usize,
    sums: &paths::Sums,
    emitter: bool,
    adaptation: [f64; 3],
) -> [f32; 3] {
    let samples = count(sums);
    std::array::from_fn(|c| {
        if pixel[c] <= 0.0 {
            return 0.0;
        }
        let value = f64::from(white::ln(pixel[c]));
        let mean_white = if samples == 0 {
            0.0
        } else {
            sums[c] as f64 / (f64::from(LOG_SCALE) * f64::from(samples))
        };
        let log = if emitter {
            value - white.zero[c] - mean_white
        } else {
            let own = f64::from(white.logs[p][c]) / f64::from(LOG_SCALE);
            (value - f64::from(white.cleaned[p][c])) + (own - mean_white) + adaptation[c]
        };
        // Finite whatever the input: a pixel e⁶⁰ above its white is shown as white anyway.
        log.clamp(-100.0, 60.0).exp() as f32
    })
}

/// Per framework, the log factor on its surfaces' lightness: the ratio r of the largest
/// framework's light to its own split into its mean over the channels r̄ and the rest, the
/// rest applied whole (the colour of a framework's light is discounted) and r̄ with the weight
/// w (its level counts half for a shadow at w = ½: log ℓ = log ℓ_image + (r − r̄) + w·r̄).
fn framework_adaptation(light_ratio: &[[f64; 3]], weight: f32) -> Vec<[f64; 3]> {
    light_ratio
        .iter()
        .map(|r| {
            let mean = (r[0] + r[1] + r[2]) / 3.0;
            r.map(|v| v - mean + f64::from(weight) * mean)
        })
        .collect()
}

/// How the paths are drawn: their seed, the least samples a pixel gets (N), the shared paths
/// of phase 1, their steps and their burn-in.
struct Plan {
    seed: u64,
    least: u32,
    shared_paths: u64,
    steps: u32,
    burn_in: u32,
}

/// The paths on a grid of `cells_x` × `cells_y` cells of `cell` pixels: their plan, the walk's
/// persistence (in cells) and the path length L (in steps).
fn plan(
    params: &RetinexParams,
    (cells_x, cells_y): (usize, usize),
    cell: usize,
) -> (Plan, f64, u32) {
    let (persistence, reach_length) = walk_for_reach(params.reach * diagonal(cells_x, cells_y));
    // A length given is in pixels of the image; a step of the grid is `cell` of them.
    let length = params.length.map_or(reach_length, |l| l.div_ceil(cell as u32).max(4));
    let (steps, burn_in) = (length - 1, length / 4);
    let samples_per_path = u64::from(steps - burn_in + 1);
    let shared_paths =
        (2 * u64::from(params.paths) * (cells_x * cells_y) as u64).div_ceil(samples_per_path);
    let plan = Plan { seed: params.seed, least: params.paths, shared_paths, steps, burn_in };
    (plan, persistence, length)
}

/// The samples of every pixel (row-major), with what it took.
struct Sampled {
    sums: Vec<paths::Sums>,
    top_up_paths: u64,
    top_up_steps: u64,
    /// The seconds of phase 2.
    top_up: f64,
}

/// Both phases of the paths on `walker`'s image.
fn sample<const C: usize>(
    walker: &Walker<'_, C>,
    plan: &Plan,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Sampled {
    let mut sums = walker.shared(plan.seed, plan.shared_paths, plan.steps, plan.burn_in, progress);
    let clock = std::time::Instant::now();
    let (top_up_paths, top_up_steps) =
        walker.top_up(&mut sums, plan.seed, plan.least, plan.steps, plan.burn_in);
    Sampled { sums, top_up_paths, top_up_steps, top_up: clock.elapsed().as_secs_f64() }
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
    check(pixels, width, height, params)?;
    let clock = std::time::Instant::now();
    let n = pixels.len();
    let no_emitters;
    let emitters = match &params.emitters {
        Some(mask) => mask.as_slice(),
        None => {
            no_emitters = vec![false; n];
            &no_emitters
        }
    };
    let counted = frameworks::counted(emitters, pixels);
    let frameworks = match &params.frameworks {
        Some(keys) => frameworks::frameworks(keys, counted, (width, height)),
        None => Frameworks::one(counted),
    };
    let framing = clock.elapsed().as_secs_f64();
    let (out, mut stats) = run(pixels, (width, height), params, emitters, &frameworks, progress)?;
    stats.seconds.cleaning += framing;
    Ok((out, stats))
}

/// [`retinex`] of a checked image whose frameworks are found.
pub(crate) fn run(
    pixels: &[[f32; 3]],
    (width, height): (usize, usize),
    params: &RetinexParams,
    emitters: &[bool],
    frameworks: &Frameworks,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Vec<[f32; 3]>, RetinexStats)> {
    let cell = grid::cell_px(width, height);
    run_on_grid(pixels, (width, height), params, emitters, frameworks, progress, cell)
}

/// [`run`] with the paths on a grid of `cell` × `cell` pixel cells (see [`grid`]).
fn run_on_grid(
    pixels: &[[f32; 3]],
    (width, height): (usize, usize),
    params: &RetinexParams,
    emitters: &[bool],
    frameworks: &Frameworks,
    progress: &(dyn Fn(u64, u64) + Sync),
    cell: usize,
) -> Result<(Vec<[f32; 3]>, RetinexStats)> {
    let clock = std::time::Instant::now();
    let lap = |since: &mut f64| {
        let now = clock.elapsed().as_secs_f64();
        let lap = now - *since;
        *since = now;
        lap
    };
    let mut since = 0.0;
    let n = pixels.len();
    let area = params.white == WhiteReference::Area;
    let white =
        white_image(pixels, emitters, (&frameworks.labels, frameworks.count), width, height, area);
    let adaptation = match params.anchor {
        Anchor::Brightest => framework_adaptation(
            &frameworks::light_ratios(pixels, frameworks, width),
            params.framework_weight,
        ),
        // The known white already holds each framework's light.
        Anchor::Known => vec![[0.0; 3]; frameworks.count],
    };
    let cleaning = lap(&mut since);
    let grid = grid::Grid::new(width, height, cell);
    let (cells_x, cells_y) = (grid.width, grid.height);
    let (plan, persistence, length) = plan(params, (cells_x, cells_y), cell);
    let tiling = tiling::Tiling::new(cells_x, cells_y);
    // The logs are relative to the brightest cleaned value; a known start needs them absolute.
    let prior = (params.anchor == Anchor::Known)
        .then(|| white.zero.map(|z| (z * f64::from(LOG_SCALE)).round() as i32));
    // A walker on logs of any number of lanes (a closure cannot be generic).
    macro_rules! walker {
        ($logs:expr) => {
            Walker {
                logs: $logs,
                tiling,
                width: cells_x,
                height: cells_y,
                turning: Turning::with_persistence(persistence),
                // A step of the grid spans `cell` pixels, and a smooth gradient's ratio over
                // it is `cell` times its ratio per pixel: the threshold is on a pixel's.
                threshold: (params.threshold * LOG_SCALE * cell as f32).round() as i32,
                prior,
            }
        };
    }
    let logs = grid.logs(&white.logs);
    // A grey image (the seen image's relative luminance in three equal channels) is walked
    // with its one channel: the same integers, in half the memory.
    let grey = logs.iter().all(|l| l[0] == l[1] && l[1] == l[2])
        && prior.is_none_or(|p| p[0] == p[1] && p[1] == p[2]);
    let sampled = if grey {
        let logs: Vec<[i16; 2]> = logs.iter().map(|l| [l[0], l[3]]).collect();
        sample(&walker!(&tiling.tiled(&logs, [0; 2])), &plan, progress)
    } else {
        sample(&walker!(&tiling.tiled(&logs, [0; 4])), &plan, progress)
    };
    let Sampled { sums, top_up_paths, top_up_steps, top_up } = sampled;
    // Phase 1 with the preparation of its image.
    let shared_seconds = lap(&mut since) - top_up;

    let out = (0..n)
        .into_par_iter()
        .map(|p| {
            let own =
                if emitters[p] { [0.0; 3] } else { adaptation[usize::from(frameworks.labels[p])] };
            lightness(pixels[p], &white, p, &sums[grid.cell_of(p)], emitters[p], own)
        })
        .collect();
    let stats = RetinexStats {
        length,
        persistence_px: persistence * cell as f64,
        cell_px: cell as u32,
        shared_paths: plan.shared_paths,
        top_up_paths,
        steps: plan.shared_paths * u64::from(plan.steps) + top_up_steps,
        min_samples: sums.iter().map(count).min().unwrap_or(0),
        max_samples: sums.iter().map(count).max().unwrap_or(0),
        noise: white.noise,
        frameworks: frameworks.count,
        seconds: PhaseSeconds {
            cleaning,
            shared_paths: shared_seconds,
            top_up,
            lightness: lap(&mut since),
        },
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
        let paper = RetinexParams { white: WhiteReference::Paper, ..Default::default() };
        let flat = run(&pixels, w, h, &RetinexParams { threshold: 0.01, ..paper.clone() });
        assert!(flat.iter().all(|p| *p == [1.0, 1.0, 1.0]));
        let long = RetinexParams { threshold: 0.0, length: Some(1000), ..paper };
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
    fn a_light_source_in_view_is_passed_over() {
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
        let base = RetinexParams { paths: 40, ..Default::default() };
        let unmarked = run(&pixels, w, h, &base);
        let marked = run(&pixels, w, h, &RetinexParams { emitters: Some(mask), ..base.clone() });
        let grey = 10 * w + 20;
        // Unmarked, the lamp is an area like any other and becomes the white.
        assert!(unmarked[grey][0] < 0.25, "the lamp is the white: {:?}", unmarked[grey]);
        // Marked, it is passed over: the white patch is the white (within what the few paths
        // that miss a patch of 4 % of the image make), and the lamp is 100 times it.
        assert!((marked[grey][0] - 0.5).abs() < 0.03, "{:?}", marked[grey]);
        assert!((marked[2 * w + 32][0] / 100.0 - 1.0).abs() < 0.1, "{:?}", marked[2 * w + 32]);
    }

    /// Left, a sunlit half: a white card and grey stone. Right, the same in a blue shadow (the
    /// light 0.2, 0.25, 0.4 of the sun's per channel). With one white for all, the card in
    /// the shadow is blue; told apart, the shadow's light is found from the ratio across the
    /// edge and discounted: the card is neutral, and its lightness lies half-way (w = ½) between
    /// its own framework's white and the sun's.
    #[test]
    fn each_framework_is_adapted_to_its_own_light() {
        let (w, h) = (120, 40);
        let shadow = [0.2f32, 0.25, 0.4];
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let reflectance = if (x % 60) < 16 && y < 16 { 0.9 } else { 0.3 };
                let light = if x < 60 { [1.0; 3] } else { shadow };
                light.map(|l| l * reflectance)
            })
            .collect();
        let keys: Vec<u32> = (0..w * h).map(|i| u32::from(i % w < 60)).collect();
        let base = RetinexParams { paths: 40, ..Default::default() };
        let (one, stats) = retinex(&pixels, w, h, &base, &|_, _| {}).unwrap();
        assert_eq!(stats.frameworks, 1);
        let told = RetinexParams { frameworks: Some(keys), ..base };
        let (two, stats) = retinex(&pixels, w, h, &told, &|_, _| {}).unwrap();
        assert_eq!(stats.frameworks, 2);
        let card = 4 * w + 66;
        let ratio = |p: [f32; 3]| p[2] / p[0];
        assert!(ratio(one[card]) > 1.5, "one white: the card is blue: {:?}", one[card]);
        assert!((ratio(two[card]) - 1.0).abs() < 0.02, "apart: neutral: {:?}", two[card]);
        // The factor is the light's ratio split: its colour whole, its level by half.
        let mean_log = shadow.iter().map(|v| f64::from(v.ln())).sum::<f64>() / 3.0;
        for c in 0..3 {
            let factor = f64::from(two[card][c] / one[card][c]);
            let expect = (-f64::from(shadow[c].ln()) + mean_log - 0.5 * mean_log).exp();
            assert!((factor / expect - 1.0).abs() < 0.01, "channel {c}: {factor} against {expect}");
        }
        // The sunlit card is the white either way.
        assert!(two[4 * w + 6].iter().all(|v| (v - 1.0).abs() < 0.01), "{:?}", two[4 * w + 6]);
        // w = 1: the shadow's card is as white as the sun's (a little above: a few of its paths
        // have not reached the sun's white, whose ratio to the shadow's the factor discounts).
        let local = RetinexParams { framework_weight: 1.0, ..told.clone() };
        let (full, _) = retinex(&pixels, w, h, &local, &|_, _| {}).unwrap();
        assert!(full[card].iter().all(|v| (v - 1.0).abs() < 0.05), "{:?}", full[card]);
    }

    /// On a grid of 2×2 cells (as a large image is walked) the white stays exactly white, a
    /// darker pixel in a cell at the white's edge is relative to that white, every pixel has
    /// its N samples and the output does not depend on the thread count. The white square's
    /// edges (odd coordinates) cut through cells.
    #[test]
    fn on_cells_the_white_stays_white_and_its_neighbours_are_relative_to_it() {
        let (w, h) = (41, 31);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (5..16).contains(&x) && (7..18).contains(&y) {
                    [8.0, 6.0, 4.0]
                } else {
                    [2.0; 3]
                }
            })
            .collect();
        let params = RetinexParams { paths: 12, seed: 3, ..Default::default() };
        let emitters = vec![false; w * h];
        let frameworks = Frameworks::one(counted(&emitters, &pixels));
        let on_cells = || {
            run_on_grid(&pixels, (w, h), &params, &emitters, &frameworks, &|_, _| {}, 2).unwrap()
        };
        let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
        let (one, stats) = pool(1).install(on_cells);
        let (two, _) = pool(2).install(on_cells);
        assert_eq!(one, two);
        assert_eq!(stats.cell_px, 2);
        assert!(stats.min_samples >= params.paths, "{stats:?}");
        for (i, p) in one.iter().enumerate() {
            let white = pixels[i][0] == 8.0;
            let expect = if white { [1.0; 3] } else { [0.25, 1.0 / 3.0, 0.5] };
            for c in 0..3 {
                assert!((p[c] - expect[c]).abs() < 1e-3 * expect[c], "pixel {i}: {p:?}");
            }
        }
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
            RetinexParams { reach: 0.0, ..Default::default() },
            RetinexParams { reach: f64::NAN, ..Default::default() },
            RetinexParams { emitters: Some(vec![false]), ..Default::default() },
            RetinexParams { frameworks: Some(vec![0]), ..Default::default() },
            RetinexParams { framework_weight: 1.5, ..Default::default() },
            RetinexParams { framework_weight: f32::NAN, ..Default::default() },
        ] {
            assert!(retinex(&ok, 2, 2, &bad, &|_, _| {}).is_err(), "{bad:?}");
        }
        // A one-pixel-wide image is valid.
        assert!(retinex(&[[1.0f32; 3]; 5], 1, 5, &p, &|_, _| {}).is_ok());
    }
}
