//! Adaptive sampling: a pixel stops taking samples once its own samples say that its mean is
//! known well enough, with the render's samples per pixel as the cap (as Cycles and Arnold do).
//!
//! The pixel takes its samples in batches of [`BATCH`], placed in the pixel by a net
//! ([`PixelKey::subpixel_net`](crate::sampler::PixelKey::subpixel_net)) that is even after every
//! batch, so that a pixel that stops early has sampled its whole area evenly. After each batch
//! it estimates the standard error of its mean X, Y and Z from the spread of its samples' own
//! values, with one pseudo-sample of prior doubt added,
//!
//! ```text
//!   s_c² = (Σ (x_c − x̄_c)² + L²) / n,     SE_c = s_c / √n,     L = Ȳ + L_floor,
//! ```
//!
//! and stops when every SE_c is at most `noise_target · (Ȳ + L_floor)`: a relative error of
//! its luminance (Weber's law: the eye sees a luminance's relative changes), held to an absolute
//! [`FLOOR_CD_M2`] in the dark, where a relative error of nothing would never be met. X and Z
//! are held to the same bound as Y, so colour noise stops the pixel as luminance noise does.
//!
//! The decision reads that pixel's samples only, and the samples are keyed by (seed, pixel,
//! sample) (`crate::sampler`), so a pixel takes the same samples and stops at the same count
//! whichever tile, thread or worker renders it: the image stays bit-identical.
//!
//! **Why the prior.** A path tracer's samples are heavy-tailed: past the third surface the
//! roulette lets a path of low throughput go on rarely, and multiplies what it brings back
//! (`crate::integrator`). In the furnace (a sphere of reflectance 0.5 around a lamp) seven
//! samples in eight give 87.5 % of the answer exactly and the eighth brings the rest, eight times
//! over, so half the pixels saw eight identical samples, judged themselves noiseless and stopped
//! 5 % dark (the test `the_furnace_is_rendered_to_its_noise_target` found it). The pseudo-sample,
//! as far from the mean as the mean itself, makes a pixel whose samples agree show it over
//! 1/`noise_target` samples before it stops (its SE is then L/n), as the rule of three bounds an
//! unseen event's rate by 3/n; where the samples do spread, it fades as 1/n against their own
//! variance.

/// Samples between two looks at a pixel's noise; also the fewest a pixel takes (when the cap
/// allows): a power of two, so that each batch is a net of its own.
pub const BATCH: u32 = 8;

/// The luminance (cd/m²) below which a pixel's noise is judged against this floor rather than
/// its own luminance: about the lower end of mesopic vision (CIE 191: 0.005 cd/m²), where what
/// a person sees has no colour left to keep.
pub const FLOOR_CD_M2: f64 = 0.005;

/// What a pixel's samples say of its noise so far: the sums of their X, Y, Z and of their
/// squares (f64: a daylight luminance squared over thousands of samples outgrows f32's digits).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoiseEstimate {
    sum: [f64; 3],
    sum_sq: [f64; 3],
    n: u32,
}

impl NoiseEstimate {
    /// One more sample, by its absolute X, Y, Z.
    #[inline]
    pub fn add(&mut self, xyz: [f32; 3]) {
        for ((sum, sum_sq), v) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(xyz) {
            let v = f64::from(v);
            *sum += v;
            *sum_sq += v * v;
        }
        self.n += 1;
    }

    /// The samples added.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// The largest standard error of the mean of X, Y and Z, with the prior's pseudo-sample
    /// (the module's formula), relative to the mean luminance held to [`FLOOR_CD_M2`];
    /// infinite before any sample.
    pub fn relative_error(&self) -> f64 {
        if self.n == 0 {
            return f64::INFINITY;
        }
        let n = f64::from(self.n);
        let luminance = (self.sum[1] / n).max(0.0) + FLOOR_CD_M2;
        let worst_spread = (0..3)
            .map(|c| (self.sum_sq[c] - self.sum[c] * self.sum[c] / n).max(0.0))
            .fold(0.0, f64::max);
        let variance = (worst_spread + luminance * luminance) / n;
        (variance / n).sqrt() / luminance
    }

    /// Whether the pixel may stop: its [`relative_error`](Self::relative_error) is within
    /// `noise_target`.
    pub fn converged(&self, noise_target: f32) -> bool {
        self.relative_error() <= f64::from(noise_target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples that agree must still show it: the error is 1/n, so a pixel takes 1/target.
    #[test]
    fn identical_samples_stop_after_one_over_the_target() {
        let mut e = NoiseEstimate::default();
        for _ in 0..BATCH {
            e.add([100.0, 120.0, 90.0]);
        }
        assert!((e.relative_error() - 1.0 / 8.0).abs() < 1e-12, "{}", e.relative_error());
        assert!(!e.converged(0.1) && e.converged(0.125));
        for _ in 0..3 * BATCH {
            e.add([100.0, 120.0, 90.0]);
        }
        assert!((e.relative_error() - 1.0 / 32.0).abs() < 1e-12);
    }

    #[test]
    fn error_is_the_standard_error_of_the_mean_with_the_prior() {
        // Y alternating 0 and 2: mean 1, Σ(y − ȳ)² = 8; with the prior's L² the variance is
        // (8 + L²)/8 and SE = √((8 + L²)/64), relative to L = 1 + floor.
        let mut e = NoiseEstimate::default();
        for i in 0..8 {
            let y = if i % 2 == 0 { 0.0 } else { 2.0 };
            e.add([1.0, y, 1.0]);
        }
        let l = 1.0 + FLOOR_CD_M2;
        let expected = ((8.0 + l * l) / 64.0f64).sqrt() / l;
        assert!((e.relative_error() - expected).abs() < 1e-12, "{}", e.relative_error());
        assert!(!e.converged(0.35) && e.converged(0.4));
    }

    #[test]
    fn colour_noise_counts_as_luminance_noise_does() {
        // Y steady, Z noisy: the pixel's colour is unknown and it must go on.
        let mut e = NoiseEstimate::default();
        for i in 0..8 {
            e.add([50.0, 50.0, if i % 2 == 0 { 0.0 } else { 100.0 }]);
        }
        assert!(!e.converged(0.1));
    }

    #[test]
    fn black_is_judged_against_the_floor() {
        let mut e = NoiseEstimate::default();
        for i in 0..8 {
            let y = if i == 0 { 1e-4 } else { 0.0 };
            e.add([y, y, y]);
        }
        for _ in 0..92 {
            e.add([0.0; 3]);
        }
        assert!(e.converged(0.011), "{}", e.relative_error());
        assert_eq!(NoiseEstimate::default().relative_error(), f64::INFINITY);
    }
}
