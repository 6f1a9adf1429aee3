//! `Spectrum`: a quantity sampled on the 81-band grid ([`crate::grid`]).
//!
//! A fixed `[f32; 81]` array so that spectra live on the stack, cost no allocation per ray, and
//! the element-wise loops below are plain counted loops the compiler vectorises. The same type
//! carries reflectances, relative spectral power distributions, irradiance and radiance; the
//! unit is the caller's and belongs in the variable's name.

use crate::grid::{BANDS, STEP_NM, wavelength_nm};
use std::ops::{Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, MulAssign, Sub, SubAssign};

#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct Spectrum(pub [f32; BANDS]);

impl Default for Spectrum {
    fn default() -> Self {
        Self::ZERO
    }
}

impl Spectrum {
    pub const ZERO: Spectrum = Spectrum([0.0; BANDS]);
    pub const ONE: Spectrum = Spectrum([1.0; BANDS]);

    /// The same value in every band.
    #[inline]
    pub const fn splat(value: f32) -> Self {
        Self([value; BANDS])
    }

    /// Band `i` set to `f(wavelength_nm(i))`.
    pub fn from_fn_nm(mut f: impl FnMut(f64) -> f64) -> Self {
        Self(std::array::from_fn(|i| f(wavelength_nm(i)) as f32))
    }

    /// The value at a wavelength on or between grid points, by linear interpolation; `None`
    /// outside 380–780 nm.
    pub fn at_nm(&self, wavelength_nm: f64) -> Option<f64> {
        let k = (wavelength_nm - crate::grid::LAMBDA_MIN_NM) / STEP_NM;
        if !(0.0..=(BANDS - 1) as f64).contains(&k) {
            return None;
        }
        let i = (k.floor() as usize).min(BANDS - 2);
        let t = k - i as f64;
        Some(f64::from(self.0[i]) * (1.0 - t) + f64::from(self.0[i + 1]) * t)
    }

    /// Apply `f` to every band.
    #[inline]
    pub fn map(&self, mut f: impl FnMut(f32) -> f32) -> Self {
        let mut out = *self;
        for v in &mut out.0 {
            *v = f(*v);
        }
        out
    }

    /// The largest band value.
    pub fn max_value(&self) -> f32 {
        // Eight running maxima side by side, not one chain of 81 that waits on itself (the
        // path tracer asks at every bounce). A maximum is one of the values whatever the
        // order, so the result is the same (NaNs are passed over either way).
        let mut lanes = [f32::NEG_INFINITY; 8];
        let chunks = self.0.chunks_exact(8);
        let rest = chunks.remainder().iter().copied().fold(f32::NEG_INFINITY, f32::max);
        for chunk in chunks {
            for (lane, &v) in lanes.iter_mut().zip(chunk) {
                *lane = lane.max(v);
            }
        }
        lanes.into_iter().fold(rest, f32::max)
    }

    /// The mean over the bands.
    pub fn mean(&self) -> f32 {
        self.0.iter().sum::<f32>() / self.0.len() as f32
    }

    /// The smallest band value.
    pub fn min_value(&self) -> f32 {
        self.0.iter().copied().fold(f32::INFINITY, f32::min)
    }

    /// True when every band is finite (no NaN, no infinity).
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }

    /// True when every band is zero.
    pub fn is_black(&self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }

    /// The band-by-band product summed in f64: Σ a(λ)·b(λ). Multiply by Δλ for an integral.
    pub fn dot(&self, other: &Spectrum) -> f64 {
        self.0.iter().zip(&other.0).map(|(&a, &b)| f64::from(a) * f64::from(b)).sum()
    }

    /// Σ a(λ)·b(λ) in f32, with eight partial sums so the products and additions vectorise:
    /// for hot loops (the film of every rendered sample), where a relative error of about 1e-6
    /// is well below anything an image shows.
    #[inline]
    pub fn dot_f32(&self, other: &Spectrum) -> f32 {
        let (a, b) = (&self.0, &other.0);
        let mut acc = [0.0f32; 8];
        for k in 0..BANDS / 8 {
            for (j, slot) in acc.iter_mut().enumerate() {
                *slot += a[8 * k + j] * b[8 * k + j];
            }
        }
        let tail: f32 = (BANDS / 8 * 8..BANDS).map(|i| a[i] * b[i]).sum();
        acc.iter().sum::<f32>() + tail
    }

    /// Σ a(λ)·b(λ)·c(λ) in f64, the shape of every colorimetric integral (source × object ×
    /// colour-matching function).
    pub fn dot3(&self, b: &Spectrum, c: &Spectrum) -> f64 {
        (0..BANDS).map(|i| f64::from(self.0[i]) * f64::from(b.0[i]) * f64::from(c.0[i])).sum()
    }

    /// The rectangle-rule integral Σ a(λ)·Δλ over the grid (CIE 15:2004 §7.1 summation).
    pub fn integral(&self) -> f64 {
        self.0.iter().map(|&v| f64::from(v)).sum::<f64>() * STEP_NM
    }

    /// `self += light · (ρ·a + b)`, band by band, in one pass: the light reflected by a surface
    /// whose reflection is a spectral part ρ(λ)·a plus a neutral part b (the hot path of the
    /// tracer, which would otherwise build and add three temporary spectra).
    #[inline]
    pub fn add_reflected(&mut self, light: &Spectrum, rho: &Spectrum, a: f32, b: f32) {
        for ((o, &l), &r) in self.0.iter_mut().zip(&light.0).zip(&rho.0) {
            *o += l * (r * a + b);
        }
    }

    /// `self += k · light`: light seen directly (the sky behind a camera ray).
    #[inline]
    pub fn add_scaled(&mut self, light: &Spectrum, k: f32) {
        for (o, &l) in self.0.iter_mut().zip(&light.0) {
            *o += l * k;
        }
    }

    /// `self += weight · light · (ρ·a + b)`: [`Spectrum::add_reflected`] behind a spectral
    /// path throughput.
    #[inline]
    pub fn add_reflected_weighted(
        &mut self,
        weight: &Spectrum,
        light: &Spectrum,
        rho: &Spectrum,
        a: f32,
        b: f32,
    ) {
        for (((o, &w), &l), &r) in self.0.iter_mut().zip(&weight.0).zip(&light.0).zip(&rho.0) {
            *o += w * l * (r * a + b);
        }
    }

    /// The linear mixture `(1 − t)·self + t·other`: the areal mixing of two surfaces in the
    /// proportions 1 − t and t.
    pub fn lerp(&self, other: &Spectrum, t: f32) -> Spectrum {
        let mut out = *self;
        for (o, &b) in out.0.iter_mut().zip(&other.0) {
            *o += t * (b - *o);
        }
        out
    }
}

impl Index<usize> for Spectrum {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl IndexMut<usize> for Spectrum {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

/// Element-wise operators between spectra, and between a spectrum and a scalar. Each is a
/// counted loop over the fixed array, which the compiler unrolls and vectorises.
macro_rules! elementwise {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tra for Spectrum {
            #[inline]
            fn $fa(&mut self, rhs: Spectrum) {
                for i in 0..BANDS {
                    self.0[i] $op rhs.0[i];
                }
            }
        }
        impl $tra<f32> for Spectrum {
            #[inline]
            fn $fa(&mut self, rhs: f32) {
                for v in &mut self.0 {
                    *v $op rhs;
                }
            }
        }
        impl $tr for Spectrum {
            type Output = Spectrum;
            #[inline]
            fn $f(mut self, rhs: Spectrum) -> Spectrum {
                self $op rhs;
                self
            }
        }
        impl $tr<f32> for Spectrum {
            type Output = Spectrum;
            #[inline]
            fn $f(mut self, rhs: f32) -> Spectrum {
                self $op rhs;
                self
            }
        }
    };
}

elementwise!(Add, add, AddAssign, add_assign, +=);
elementwise!(Sub, sub, SubAssign, sub_assign, -=);
elementwise!(Mul, mul, MulAssign, mul_assign, *=);
elementwise!(Div, div, DivAssign, div_assign, /=);

impl Mul<Spectrum> for f32 {
    type Output = Spectrum;
    #[inline]
    fn mul(self, rhs: Spectrum) -> Spectrum {
        rhs * self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_is_band_by_band() {
        let a = Spectrum::from_fn_nm(|l| l);
        let b = Spectrum::splat(2.0);
        assert_eq!((a * b)[10], 2.0 * 430.0);
        assert_eq!((a + b)[0], 382.0);
        assert_eq!((a - b)[80], 778.0);
        assert_eq!((a / 2.0)[1], 192.5);
        assert_eq!((2.0 * a)[1], 770.0);
        let mut c = a;
        c *= b;
        c -= a;
        assert_eq!(c, a);
    }

    #[test]
    fn integral_and_dot_are_rectangle_sums() {
        assert_eq!(Spectrum::ONE.integral(), 81.0 * 5.0);
        let a = Spectrum::splat(2.0);
        assert_eq!(a.dot(&Spectrum::splat(3.0)), 6.0 * 81.0);
        assert_eq!(a.dot3(&a, &a), 8.0 * 81.0);
    }

    #[test]
    fn the_fast_dot_agrees_with_the_exact_one() {
        let a = Spectrum::from_fn_nm(|l| (l / 37.0).sin().abs());
        let b = Spectrum::from_fn_nm(|l| 1.0 + (l / 53.0).cos());
        let (fast, exact) = (f64::from(a.dot_f32(&b)), a.dot(&b));
        assert!((fast / exact - 1.0).abs() < 1e-6, "{fast} vs {exact}");
    }

    #[test]
    fn interpolation_between_bands() {
        let a = Spectrum::from_fn_nm(|l| l);
        assert!((a.at_nm(382.5).unwrap() - 382.5).abs() < 1e-4);
        assert!((a.at_nm(780.0).unwrap() - 780.0).abs() < 1e-4);
        assert_eq!(a.at_nm(379.0), None);
        assert_eq!(a.at_nm(781.0), None);
    }

    #[test]
    fn reflected_light_is_light_times_the_two_parts() {
        let light = Spectrum::from_fn_nm(|nm| nm / 100.0);
        let rho = Spectrum::from_fn_nm(|nm| (nm - 380.0) / 400.0);
        let weight = Spectrum::from_fn_nm(|nm| 1.0 + nm / 1000.0);
        let mut a = Spectrum::splat(1.0);
        a.add_reflected(&light, &rho, 0.3, 0.02);
        let mut b = Spectrum::splat(1.0);
        b.add_reflected_weighted(&weight, &light, &rho, 0.3, 0.02);
        for i in 0..BANDS {
            let plain = light[i] * (rho[i] * 0.3 + 0.02);
            assert!((a[i] - (1.0 + plain)).abs() < 1e-6);
            assert!((b[i] - (1.0 + weight[i] * plain)).abs() < 1e-5);
        }
    }

    #[test]
    fn lerp_mixes_areally() {
        let white = Spectrum::ONE;
        let black = Spectrum::ZERO;
        assert_eq!(white.lerp(&black, 0.25), Spectrum::splat(0.75));
    }

    #[test]
    fn finiteness_and_extremes() {
        let mut a = Spectrum::from_fn_nm(|l| l);
        assert!(a.is_finite());
        assert_eq!(a.max_value(), 780.0);
        assert_eq!(a.min_value(), 380.0);
        a[3] = f32::NAN;
        assert!(!a.is_finite());
        assert!(Spectrum::ZERO.is_black());
        // The largest band wherever it lies: in a lane of the eight, in the remainder, first.
        for at in [0, 5, 40, 79, 80] {
            let mut b = Spectrum::from_fn_nm(|l| -l);
            b[at] = 7.0;
            b[(at + 1) % 81] = f32::NAN;
            assert_eq!(b.max_value(), 7.0, "the largest at band {at}");
        }
    }
}
