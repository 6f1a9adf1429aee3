//! The image the paths read: where the Retinex may find its white.
//!
//! The paper's path function takes the brightest *pixel* a path crosses as the white. In a
//! Monte Carlo render that is a bad witness: a firefly, a glint or the noise of a shadow each
//! make a pixel brighter than the surface it belongs to, and one such pixel on a path darkens
//! every pixel after it (a firefly made the rest of an image almost black, and 3 % noise on a
//! flat field lowered its lightness to 0.85: the maximum of a noisy path is above its mean).
//! So the paths read a cleaned log image, per channel:
//!
//! 1. **The larger of the 3×3 median and the 2×2 opening** — a bright feature must cover most
//!    of a 3×3 window or a whole 2×2 block to survive, so a single pixel or a one-pixel line (a
//!    firefly, a glint) cannot be the white. Both keep straight edges where they are, and the
//!    opening keeps the corners of areas, so the ratios of a clean image are unchanged. (The
//!    median alone cuts off an area's corners; the opening alone is biased low on noise.)
//! 2. **Noise-adaptive joint bilateral mean**, four passes over 5×5 (spatial Gaussian of
//!    σ = 1.25 px) of the median image, taking only neighbours whose median logs lie within
//!    2σ_n of the pixel's in every channel,
//!    where σ_n is the image's own noise, estimated robustly (1.4826 · median |Δ log| / √2
//!    over horizontal neighbours, Donoho & Johnstone's MAD estimator). On a noisy flat field
//!    this averages the noise far below the Retinex threshold (3 % noise: the lightness of a
//!    flat field is 0.9928 after three passes, 0.9992 after four); across an edge stronger than the
//!    noise it takes nothing from the other side, and on a noise-free image (σ_n = 0) it is the
//!    median itself.
//!
//! With frameworks of illumination (see `frameworks`), each is cleaned by itself: its noise
//! is its own (a Monte Carlo render is noisier in the sky-lit shadow, lit by sampled sky and
//! bounced light, than in the sun, and a noise σ of the whole image, set by the sunlit stone,
//! left the shadow's noise in place: the maxima of its noise became its white, a different
//! one in each channel, and the shadow of the demo's facade turned olive), and the bilateral
//! mean takes no neighbour from another framework.
//!
//! Pixels marked as light sources (the sky or an emitter seen by the camera) take no part:
//! they are left out of both filters and flagged, and the paths pass over them (see
//! `paths`), so a bright sky is neither the white of the building nor a wall across the
//! ratios between two of its surfaces.
//!
//! Logs are held in fixed point, 1/1024 of a natural-log unit (a 0.1 % step), relative to the
//! brightest cleaned value of each channel and floored at e⁻²⁰ of it.

mod bilateral;
mod median;

use bilateral::{bilateral, noise_sigma, regions};
use median::{median, opening};
use rayon::prelude::*;

/// Fixed-point units per natural-log unit.
pub(super) const LOG_SCALE: f32 = 1024.0;
/// The floor of the relative logs, in natural-log units.
pub(super) const LOG_FLOOR: f32 = -20.0;
/// Lane 3 of a pixel's logs for a light source; a surface's is its framework, 0 or more.
pub(super) const EMITTER: i16 = -1;

/// The bilateral mean is applied this many times (each pass with the range cut of the input's
/// noise): noise falls with every pass while edges stronger than the cut stay.
const BILATERAL_PASSES: usize = 4;

/// The cleaned image, as the paths read it.
pub(super) struct WhiteImage {
    /// Per pixel, the fixed-point logs of the three channels; lane 3 is [`EMITTER`] or 0 (a
    /// surface, whose framework the caller may write there).
    pub logs: Vec<[i16; 4]>,
    /// Per pixel, the cleaned natural logs themselves (not relative, not floored).
    pub cleaned: Vec<[f32; 3]>,
    /// Per channel, the natural log of the brightest cleaned value (the logs' zero).
    pub zero: [f64; 3],
    /// Per framework and channel, the noise σ estimated (natural-log units).
    pub noise: Vec<[f32; 3]>,
}

/// `ln v`, with 0 as −∞. The lightness divides by the cleaned value with the same function,
/// so that a pixel equal to it gives exactly 1.
pub(super) fn ln(v: f32) -> f32 {
    if v > 0.0 { v.ln() } else { f32::NEG_INFINITY }
}

/// [`BILATERAL_PASSES`] of the bilateral mean on the first `C` of the three channels (`C` = 1
/// for a grey image, whose other two are copies of the first), returned as three channels.
fn bilateral_mean<const C: usize>(
    medians: &[Vec<f32>; 3],
    regions: &[u8],
    size: (usize, usize),
    noise: &[[f32; 3]],
) -> [Vec<f32>; 3] {
    let mut image: Vec<[f32; C]> = (0..medians[0].len())
        .into_par_iter()
        .map(|p| std::array::from_fn(|c| medians[c][p]))
        .collect();
    let noise: Vec<[f32; C]> = noise.iter().map(|n| std::array::from_fn(|c| n[c])).collect();
    for _ in 0..BILATERAL_PASSES {
        image = bilateral(&image, regions, size, &noise);
    }
    std::array::from_fn(|c| image.par_iter().map(|v| v[c.min(C - 1)]).collect())
}

/// The cleaned image of `pixels` (non-negative, finite), with `emitter` marking light sources
/// and `frameworks` each surface's framework (0..count). `area` false gives the paper's image:
/// every pixel as it is.
pub(super) fn white_image(
    pixels: &[[f32; 3]],
    emitter: &[bool],
    (frameworks, count): (&[u8], usize),
    width: usize,
    height: usize,
    area: bool,
) -> WhiteImage {
    // A grey image (the seen image's relative luminance, in three equal channels) has its one
    // channel filtered once and copied: each filter of a channel reads that channel alone, and
    // the joint bilateral mean gives equal channels equal results.
    let grey = pixels
        .par_iter()
        .all(|p| p[1].to_bits() == p[0].to_bits() && p[2].to_bits() == p[0].to_bits());
    let channels = if grey { 1 } else { 3 };
    let per_channel = |f: &(dyn Fn(usize) -> Vec<f32> + Sync)| -> [Vec<f32>; 3] {
        let distinct: Vec<Vec<f32>> = (0..channels).map(f).collect();
        std::array::from_fn(|c| distinct[c.min(channels - 1)].clone())
    };
    let logs = per_channel(&|c| pixels.par_iter().map(|p| ln(p[c])).collect());
    let mut noise = vec![[0f32; 3]; count];
    let cleaned: [Vec<f32>; 3] = if area {
        let medians = per_channel(&|c| {
            let open = opening(&logs[c], emitter, width, height);
            let mut m = median(&logs[c], emitter, width, height);
            m.par_iter_mut().zip(&open).zip(emitter.par_iter()).for_each(|((m, o), e)| {
                if !e {
                    *m = m.max(*o);
                }
            });
            m
        });
        let regions = regions(emitter, frameworks);
        noise = (0..count as u8)
            .map(|f| {
                let sigma: Vec<f32> =
                    (0..channels).map(|c| noise_sigma(&logs[c], &regions, width, f)).collect();
                std::array::from_fn(|c| sigma[c.min(channels - 1)])
            })
            .collect();
        let size = (width, height);
        if grey {
            bilateral_mean::<1>(&medians, &regions, size, &noise)
        } else {
            bilateral_mean::<3>(&medians, &regions, size, &noise)
        }
    } else {
        logs
    };
    let zero: [f64; 3] = std::array::from_fn(|c| {
        let max = cleaned[c]
            .iter()
            .zip(emitter)
            .filter(|(_, e)| !**e)
            .map(|(v, _)| *v)
            .fold(f32::NEG_INFINITY, f32::max);
        // A channel black everywhere (or an image all light sources) is uniformly at the floor.
        if max.is_finite() { f64::from(max) } else { 0.0 }
    });
    let logs = (0..pixels.len())
        .into_par_iter()
        .map(|p| {
            let mut out = [0i16; 4];
            for c in 0..3 {
                let relative = (f64::from(cleaned[c][p]) - zero[c]) as f32;
                // −∞ (a black pixel) is at the floor.
                out[c] = (relative.clamp(LOG_FLOOR, 0.0) * LOG_SCALE).round() as i16;
            }
            out[3] = if emitter[p] { EMITTER } else { i16::from(frameworks[p]) };
            out
        })
        .collect();
    let cleaned = (0..pixels.len())
        .into_par_iter()
        // Floored as the fixed-point logs are, so that a lone bright pixel in a black area has
        // a finite ratio to its cleaned value.
        .map(|p| {
            std::array::from_fn(|c| cleaned[c][p].max((zero[c] + f64::from(LOG_FLOOR)) as f32))
        })
        .collect();
    WhiteImage { logs, cleaned, zero, noise }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_firefly_is_not_a_candidate_for_the_white() {
        let (w, h) = (9, 9);
        let mut pixels = vec![[0.5f32; 3]; w * h];
        pixels[40] = [500.0; 3];
        let white = white_image(&pixels, &vec![false; w * h], (&vec![0; w * h], 1), w, h, true);
        assert!(white.logs.iter().all(|l| l[..3] == [0, 0, 0]), "the firefly survived");
        assert!((white.zero[0] - 0.5f64.ln()).abs() < 1e-6);
    }

    #[test]
    fn edges_of_a_clean_image_stay_where_they_are() {
        // Two halves, e² apart: the cleaned logs are the halves' own, to the last unit.
        let (w, h) = (12, 6);
        let pixels: Vec<[f32; 3]> =
            (0..w * h).map(|i| if i % w < 5 { [1.0; 3] } else { [(-2.0f32).exp(); 3] }).collect();
        let white = white_image(&pixels, &vec![false; w * h], (&vec![0; w * h], 1), w, h, true);
        for (i, l) in white.logs.iter().enumerate() {
            let expect = if i % w < 5 { 0 } else { -2048 };
            assert_eq!(l[0], expect, "pixel {i}");
        }
    }

    #[test]
    fn noise_is_averaged_below_the_threshold() {
        // 3 % multiplicative noise: the cleaned image's spread is a fraction of it.
        let (w, h) = (64, 64);
        let mut rng = crate::keyed_random::KeyedRng::new(3);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|_| {
                let g: f32 = (0..12).map(|_| rng.next_f32()).sum::<f32>() - 6.0;
                [1.0 + 0.03 * g; 3]
            })
            .collect();
        let white = white_image(&pixels, &vec![false; w * h], (&vec![0; w * h], 1), w, h, true);
        assert!((white.noise[0][0] / 0.03 - 1.0).abs() < 0.15, "σ_n {}", white.noise[0][0]);
        let values: Vec<f32> = white.logs.iter().map(|l| f32::from(l[0]) / LOG_SCALE).collect();
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        let sd =
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / values.len() as f32).sqrt();
        // A sixth of the input's noise or less: far enough below the paper's threshold (1 %)
        // that a step of noise seldom counts as an edge.
        assert!(sd < 0.03 / 6.0, "cleaned σ {sd}");
    }

    #[test]
    fn light_sources_take_no_part() {
        let (w, h) = (6, 6);
        let mut pixels = vec![[0.2f32; 3]; w * h];
        let mut emitter = vec![false; w * h];
        for p in 0..w {
            pixels[p] = [1000.0; 3];
            emitter[p] = true;
        }
        let white = white_image(&pixels, &emitter, (&vec![0; w * h], 1), w, h, true);
        assert!((white.zero[0] - 0.2f64.ln()).abs() < 1e-6, "{:?}", white.zero);
        assert!(white.logs[..w].iter().all(|l| l[3] == EMITTER));
        assert!(white.logs[w..].iter().all(|l| l[..] == [0, 0, 0, 0]));
    }
}
