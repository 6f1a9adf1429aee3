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

use rayon::prelude::*;

/// Fixed-point units per natural-log unit.
pub(super) const LOG_SCALE: f32 = 1024.0;
/// The floor of the relative logs, in natural-log units.
pub(super) const LOG_FLOOR: f32 = -20.0;
/// Lane 3 of a pixel's logs for a light source; a surface's is its framework, 0 or more.
pub(super) const EMITTER: i16 = -1;

/// The bilateral mean's spatial σ, in pixels, and its window's half-width.
const SPATIAL_SIGMA_PX: f32 = 1.25;
const RADIUS: i32 = 2;
/// The bilateral mean is applied this many times (each pass with the range cut of the input's
/// noise): noise falls with every pass while edges stronger than the cut stay.
const BILATERAL_PASSES: usize = 4;
/// Neighbours within this many noise σ of the pixel (in every channel) are averaged. At 3σ the
/// rendered travertine of `render/tests/retinex_rendered.rs` lost 13° of hue to its grey
/// ground, whose S differs by 7 % (about the render's noise); at 2σ, 4°, and a flat noisy field
/// is averaged as well.
const RANGE_SIGMAS: f32 = 2.0;

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

/// The 3×3 median of one channel's logs over surface pixels (light sources left out; a light
/// source keeps its own value).
fn median(logs: &[f32], emitter: &[bool], width: usize, height: usize) -> Vec<f32> {
    (0..width * height)
        .into_par_iter()
        .map(|p| {
            if emitter[p] {
                return logs[p];
            }
            let (x, y) = ((p % width) as i32, (p / width) as i32);
            let mut window = [0f32; 9];
            let mut n = 0;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= width as i32 || qy >= height as i32 {
                        continue;
                    }
                    let q = qy as usize * width + qx as usize;
                    if !emitter[q] {
                        window[n] = logs[q];
                        n += 1;
                    }
                }
            }
            let window = &mut window[..n];
            window.sort_unstable_by(f32::total_cmp);
            // An even count (at a border or beside a light source): the lower middle, so that
            // the median is always one of the values.
            window[(n - 1) / 2]
        })
        .collect()
}

/// The 2×2 opening of one channel's logs (each pixel: the largest, over the 2×2 blocks inside
/// the image that hold it, of the block's smallest surface value). An area that is a union of
/// 2×2 blocks keeps every pixel, its corners included, which the 3×3 median would cut off.
fn opening(logs: &[f32], emitter: &[bool], width: usize, height: usize) -> Vec<f32> {
    let block_min = |bx: usize, by: usize| {
        let mut m = f32::INFINITY;
        for q in
            [by * width + bx, by * width + bx + 1, (by + 1) * width + bx, (by + 1) * width + bx + 1]
        {
            if !emitter[q] {
                m = m.min(logs[q]);
            }
        }
        m
    };
    (0..width * height)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % width, p / width);
            let mut best = f32::NEG_INFINITY;
            for by in y.saturating_sub(1)..=y.min(height.saturating_sub(2)) {
                for bx in x.saturating_sub(1)..=x.min(width.saturating_sub(2)) {
                    if by + 1 < height && bx + 1 < width {
                        let m = block_min(bx, by);
                        if m < f32::INFINITY {
                            best = best.max(m);
                        }
                    }
                }
            }
            best
        })
        .collect()
}

/// What the filters need to know of a pixel besides its logs: whether it is a light source
/// (`None`) or a surface of which framework.
fn region(emitter: &[bool], frameworks: &[u8], p: usize) -> Option<u8> {
    (!emitter[p]).then(|| frameworks[p])
}

/// The robust noise σ of one channel's logs in framework `f`: 1.4826 · median
/// |ℓ(x+1) − ℓ(x)| / √2 over horizontal pairs of its surface pixels with finite logs.
fn noise_sigma(logs: &[f32], emitter: &[bool], frameworks: &[u8], width: usize, f: u8) -> f32 {
    let mut differences: Vec<f32> = (0..logs.len() / width)
        .into_par_iter()
        .flat_map_iter(|y| {
            (y * width..(y + 1) * width - 1).filter_map(move |p| {
                let d = (logs[p + 1] - logs[p]).abs();
                let same = region(emitter, frameworks, p) == Some(f)
                    && region(emitter, frameworks, p + 1) == Some(f);
                (same && d.is_finite()).then_some(d)
            })
        })
        .collect();
    if differences.is_empty() {
        return 0.0;
    }
    let middle = differences.len() / 2;
    let (_, m, _) = differences.select_nth_unstable_by(middle, f32::total_cmp);
    1.4826 * *m / std::f32::consts::SQRT_2
}

/// One pass of the joint bilateral mean of the three channels' median images (see the module
/// comment): a neighbour is taken only if it is within the cut in *every* channel, so an edge
/// that is strong in one channel keeps the others from mixing across it too (a travertine on
/// grey ground differs by 7 % in S but by 40 % in L).
fn bilateral(
    channels: &[Vec<f32>; 3],
    emitter: &[bool],
    frameworks: &[u8],
    (width, height): (usize, usize),
    noise: &[[f32; 3]],
) -> [Vec<f32>; 3] {
    let cuts: Vec<[f32; 3]> = noise.iter().map(|n| n.map(|n| RANGE_SIGMAS * n)).collect();
    let weight = |dx: i32, dy: i32| {
        (-((dx * dx + dy * dy) as f32) / (2.0 * SPATIAL_SIGMA_PX * SPATIAL_SIGMA_PX)).exp()
    };
    let side = (2 * RADIUS + 1) as usize;
    let kernel: Vec<f32> = (0..side * side)
        .map(|i| weight(i as i32 % side as i32 - RADIUS, i as i32 / side as i32 - RADIUS))
        .collect();
    let out: Vec<[f32; 3]> = (0..width * height)
        .into_par_iter()
        .map(|p| {
            let centre: [f32; 3] = std::array::from_fn(|c| channels[c][p]);
            let Some(own) = region(emitter, frameworks, p) else { return centre };
            let cut = cuts[usize::from(own)];
            if centre.iter().any(|v| !v.is_finite()) || cut.contains(&0.0) {
                return centre;
            }
            let (x, y) = ((p % width) as i32, (p / width) as i32);
            let (mut sum, mut total) = ([0.0f32; 3], 0.0f32);
            for dy in -RADIUS..=RADIUS {
                for dx in -RADIUS..=RADIUS {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= width as i32 || qy >= height as i32 {
                        continue;
                    }
                    let q = qy as usize * width + qx as usize;
                    let v: [f32; 3] = std::array::from_fn(|c| channels[c][q]);
                    if region(emitter, frameworks, q) != Some(own)
                        || (0..3).any(|c| (v[c] - centre[c]).abs() > cut[c])
                    {
                        continue;
                    }
                    let k = kernel[((dy + RADIUS) * side as i32 + dx + RADIUS) as usize];
                    for c in 0..3 {
                        sum[c] += k * v[c];
                    }
                    total += k;
                }
            }
            sum.map(|s| s / total)
        })
        .collect();
    std::array::from_fn(|c| out.iter().map(|v| v[c]).collect())
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
    let logs: [Vec<f32>; 3] =
        std::array::from_fn(|c| pixels.par_iter().map(|p| ln(p[c])).collect());
    let mut noise = vec![[0f32; 3]; count];
    let cleaned: [Vec<f32>; 3] = if area {
        let mut medians: [Vec<f32>; 3] = std::array::from_fn(|c| {
            let open = opening(&logs[c], emitter, width, height);
            let mut m = median(&logs[c], emitter, width, height);
            m.par_iter_mut().zip(&open).zip(emitter.par_iter()).for_each(|((m, o), e)| {
                if !e {
                    *m = m.max(*o);
                }
            });
            m
        });
        noise = (0..count as u8)
            .map(|f| std::array::from_fn(|c| noise_sigma(&logs[c], emitter, frameworks, width, f)))
            .collect();
        for _ in 0..BILATERAL_PASSES {
            medians = bilateral(&medians, emitter, frameworks, (width, height), &noise);
        }
        medians
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
