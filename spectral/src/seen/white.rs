//! The white a pixel is seen against: the light that falls on its surface, from the renderer's
//! adapting white, smoothed within its framework of illumination.
//!
//! The renderer gives every pixel W(p), what a perfect white diffuser at its surface would send
//! back (X, Y, Z and the scotopic luminance). W changes with the light and with the surface's
//! orientation, and carries the Monte Carlo noise of the sky and the bounced light. The white a
//! person adapts to is neither one pixel's nor the whole scene's, so:
//!
//! * **Local white Ŵ(p)**: W smoothed by a Gaussian of σ = [`RADIUS_OF_DIAGONAL`] of the image
//!   diagonal, over the area of p's framework only ([`super::smoothing`]), so the light on
//!   either side of a shadow's edge does not bleed into the other. A pixel outside every framework's area (a joint in shadow, a crack: a line,
//!   not an area) takes the white of the framework around it, so it stays as dark and as blue
//!   as small shadows look. The smoothing keeps the light's slow changes — a wall turned from
//!   the sun, the bounce light under an arch — and drops its noise.
//! * **White levels**: each framework's, Y_f, is the 90th percentile of Ŷ over its area (the
//!   light on its most lit faces, robust to a few pixels); the image's, Y_g, is the largest of
//!   them: the most lit framework's. Anchoring theory's highest luminance, taken from the light
//!   rather than from the stones.
//!
//! The seen image takes its level from these (see the parent module) and its colour from Ŵ's
//! chromaticity.

use super::smoothing::Smoother;
use crate::retinex::Frameworks;
use rayon::prelude::*;

/// σ of the smoothing, as a share of the image diagonal: 2 %, about 40 px at 1920 × 1080, a
/// degree or so of a usual field of view. Wide enough to average the sky's and the bounce
/// light's noise over a thousand pixels; narrow enough that a wall turned from the sun keeps its
/// own light.
pub const RADIUS_OF_DIAGONAL: f64 = 0.02;
/// The percentile of a framework's Ŷ that is its white level.
const LEVEL_PERCENTILE: f64 = 0.9;

/// The adapting white of every pixel.
pub(super) struct AdaptingWhite {
    /// Ŵ(p): X, Y, Z (Y in cd/m²) and the scotopic luminance of the light on p's surface,
    /// smoothed within its framework. For a light source in view, the overall white.
    pub local: Vec<[f64; 4]>,
    /// Y_g (cd/m²): the white level of the most lit framework.
    pub level_cd_m2: f64,
    /// Y_f (cd/m²) of each framework.
    pub framework_level_cd_m2: Vec<f64>,
    /// The framework each pixel is seen in: its own, or for a pixel outside every framework's
    /// area, the one around it.
    pub framework: Vec<u8>,
    /// The mean of W over every surface pixel: the scene's light, for light sources in view.
    pub overall: [f64; 4],
}

/// The value at `q` (0..1) of `values`, sorted in place.
fn percentile(values: &mut [f64], q: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let at = ((values.len() - 1) as f64 * q).round() as usize;
    Some(*values.select_nth_unstable_by(at, f64::total_cmp).1)
}

/// The adapting white of an image whose pixels have the renderer's whites `white`, in
/// `frameworks` (`emitters` marks the light sources in view).
pub(super) fn adapting_white(
    white: &[[f32; 4]],
    smoother: &Smoother<'_>,
    frameworks: &Frameworks,
    emitters: &[bool],
) -> AdaptingWhite {
    let n = white.len();
    let f64s = |w: &[f32; 4]| w.map(f64::from);
    let smoothed = smoother.smooth(|p| Some(f64s(&white[p])));
    // The overall white, and each framework's mean for pixels its smoothing does not reach.
    let mut sums = vec![[0.0f64; 5]; frameworks.count];
    for p in (0..n).filter(|&p| frameworks.solid[p]) {
        let s = &mut sums[usize::from(frameworks.labels[p])];
        let w = f64s(&white[p]);
        for c in 0..4 {
            s[c] += w[c];
        }
        s[4] += 1.0;
    }
    let mean = |s: &[f64; 5]| -> Option<[f64; 4]> {
        (s[4] > 0.0).then(|| std::array::from_fn(|c| s[c] / s[4]))
    };
    let total = sums.iter().fold([0.0; 5], |a, s| std::array::from_fn(|c| a[c] + s[c]));
    let overall = mean(&total).unwrap_or([0.0; 4]);
    let framework_mean: Vec<[f64; 4]> = sums.iter().map(|s| mean(s).unwrap_or(overall)).collect();
    let (local, framework): (Vec<[f64; 4]>, Vec<u8>) = (0..n)
        .into_par_iter()
        .map(|p| {
            if emitters[p] {
                return (overall, 0);
            }
            let f = smoother.framework_of(&smoothed, p);
            let white =
                smoother.at(&smoothed, f, p).map_or(framework_mean[f], |v| v.map(|c| c.max(0.0)));
            (white, f as u8)
        })
        .unzip();
    let framework_level_cd_m2: Vec<f64> = (0..frameworks.count)
        .map(|f| {
            let mut ys: Vec<f64> = (0..n)
                .filter(|&p| frameworks.solid[p] && usize::from(frameworks.labels[p]) == f)
                .map(|p| local[p][1])
                .collect();
            percentile(&mut ys, LEVEL_PERCENTILE).unwrap_or(0.0)
        })
        .collect();
    let level_cd_m2 = framework_level_cd_m2.iter().copied().fold(0.0, f64::max);
    AdaptingWhite { local, level_cd_m2, framework_level_cd_m2, framework, overall }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::retinex::{counted, frameworks_of};

    fn frameworks(keys: &[u32], (w, h): (usize, usize)) -> Frameworks {
        let pixels = vec![[1.0f32; 3]; w * h];
        frameworks_of(keys, counted(&vec![false; w * h], &pixels), (w, h))
    }

    fn adapting(white: &[[f32; 4]], f: &Frameworks, size: (usize, usize)) -> AdaptingWhite {
        let smoother = Smoother::new(f, size, RADIUS_OF_DIAGONAL);
        adapting_white(white, &smoother, f, &vec![false; white.len()])
    }

    /// A noisy white is smoothed to its mean, and a uniform white stays what it is.
    #[test]
    fn noise_is_smoothed_and_a_uniform_white_kept() {
        let (w, h) = (160, 90);
        let mut rng = crate::keyed_random::KeyedRng::new(1);
        let white: Vec<[f32; 4]> = (0..w * h)
            .map(|_| {
                let k = 1.0 + 0.4 * (rng.next_f32() - 0.5);
                [95.0 * k, 100.0 * k, 108.0 * k, 250.0 * k]
            })
            .collect();
        let f = frameworks(&vec![1; w * h], (w, h));
        let a = adapting(&white, &f, (w, h));
        for p in [0, w * h / 2 + w / 2, w * h - 1] {
            assert!((a.local[p][1] / 100.0 - 1.0).abs() < 0.03, "{:?}", a.local[p]);
            assert!((a.local[p][0] / a.local[p][1] - 0.95).abs() < 1e-6);
        }
        assert!((a.level_cd_m2 / 100.0 - 1.0).abs() < 0.03, "{}", a.level_cd_m2);
    }

    /// Two frameworks side by side, a sunlit half and a shadow ten times darker and bluer: each
    /// keeps its own white up to the edge; a stripe of shadow two pixels wide inside the sun
    /// (a joint) takes the sun's; the level is the sun's.
    #[test]
    fn a_framework_keeps_its_light_up_to_its_edge() {
        let (w, h) = (200, 100);
        let sun = [96.0f32, 100.0, 90.0, 200.0];
        let shade = [9.0f32, 10.0, 14.0, 30.0];
        let joint = |x: usize| x == 50 || x == 51;
        let keys: Vec<u32> = (0..w * h).map(|p| u32::from(p % w < 100 && !joint(p % w))).collect();
        let white: Vec<[f32; 4]> = keys.iter().map(|&k| if k == 1 { sun } else { shade }).collect();
        let f = frameworks(&keys, (w, h));
        assert_eq!(f.count, 2);
        let a = adapting(&white, &f, (w, h));
        let at = |x: usize, y: usize| a.local[y * w + x];
        let close =
            |v: [f64; 4], e: [f32; 4]| (0..4).all(|c| (v[c] / f64::from(e[c]) - 1.0).abs() < 1e-6);
        assert!(close(at(98, 50), sun), "{:?}", at(98, 50));
        assert!(close(at(101, 50), shade), "{:?}", at(101, 50));
        assert!(close(at(50, 50), sun), "the joint is seen in the sun's light: {:?}", at(50, 50));
        assert!((a.level_cd_m2 - 100.0).abs() < 1e-6);
    }
}
