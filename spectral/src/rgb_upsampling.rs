//! RGB → spectrum upsampling after Jakob & Hanika, "A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling", Computer Graphics Forum 38(2):147–155, 2019
//! (doi:10.1111/cgf.13626).
//!
//! The paper's function space: a reflectance is a quadratic polynomial passed through a sigmoid,
//!
//! ```text
//! ρ(λ) = S(c₀λ² + c₁λ + c₂),     S(x) = 1/2 + x / (2·√(1 + x²)),
//! ```
//!
//! S maps ℝ onto the open interval (0, 1), so every member is a physically valid reflectance,
//! smooth, and stored in three numbers. Three coefficients for three colour coordinates make the
//! fit a square non-linear system, which the paper solves (§4) by Gauss–Newton iteration on the
//! CIE 1976 difference ΔE*ab between the target colour and the spectrum's colour.
//!
//! What this module fixes, and why:
//!
//! * **λ is normalised on restauro's grid**: t = (λ − 380 nm) / (780 nm − 380 nm), which is
//!   i / 80 for band i, and ρᵢ = S(c₀tᵢ² + c₁tᵢ + c₂). Over t ∈ [0, 1] the three coefficients are
//!   of like size (tens to a few hundred across the sRGB gamut) where nanometres would put
//!   c₀ ~ 10⁻³ beside c₂ ~ 10², badly conditioned and losing digits in f32. A quadratic in t is a
//!   quadratic in λ, so the normalisation changes the coefficients, not the family of spectra nor
//!   the fitted spectrum. It is colour-science's dimensionless form on the same grid (its
//!   `numpy.linspace(0, 1, 81)`), so coefficients compare directly with
//!   `find_coefficients_Jakob2019(..., dimensionalise=False)`.
//! * **The colour** is the reflectance's under CIE D65 for the CIE 1931 2° observer, summed over
//!   the grid exactly as [`crate::colorimetry::relative_xyz`] does (CIE 15:2004 §7.1). The target
//!   is linear sRGB → XYZ with the sRGB primaries and, as white, D65 summed over the same grid
//!   (x, y = 0.31272, 0.32903, which IEC 61966-2-1 rounds to 0.3127, 0.3290): RGB (1, 1, 1) is
//!   then the perfect reflector and a grey g the flat spectrum g, exactly. Against the IEC matrix
//!   ([`crate::rgb_space::RgbSpace::Srgb`]) the difference is at most 2.7·10⁻⁴ of a channel.
//! * **Inputs are clamped** to [[`RGB_EPSILON`], 1 − [`RGB_EPSILON`]] per channel: S never
//!   reaches 0 or 1, so a channel at exactly 0 or 1 has no finite coefficients. At 10⁻⁴ the
//!   clamp moves a colour by less than anything a display shows (an 8-bit sRGB code value of 1 is
//!   3·10⁻⁴ in linear light), and it keeps the coefficients of the sRGB primaries below a few
//!   hundred.
//!
//! Every colour of that clamped sRGB cube is reached (the tests fit a 5×5×5 grid of it, corners
//! included, to 10⁻³ per channel); colours outside sRGB are not this module's business.

use crate::colorimetry::{Observer, Xyz, relative_xyz, white_point};
use crate::error::{Error, Result};
use crate::grid::BANDS;
use crate::illuminant::Illuminant;
use crate::lab::Lab;
use crate::rgb_space::RgbSpace;
use crate::spectrum::Spectrum;
use glam::{DMat3, DVec3};
use std::sync::LazyLock;

/// Each linear sRGB channel is clamped to [`RGB_EPSILON`, 1 − `RGB_EPSILON`] before fitting:
/// the sigmoid reaches 0 and 1 only as its argument goes to ∓∞.
pub const RGB_EPSILON: f64 = 1e-4;

/// tᵢ = (λᵢ − 380) / 400 = i / 80, the normalised wavelength of each band, as a table so that
/// [`SigmoidPolynomial::value`] is a multiply-add and a square root per band.
const NORMALISED_WAVELENGTHS: [f32; BANDS] = {
    let mut t = [0.0f32; BANDS];
    let mut i = 0;
    while i < BANDS {
        t[i] = i as f32 / (BANDS - 1) as f32;
        i += 1;
    }
    t
};

/// The normalised wavelength of band `i` in f64, for the fit.
fn normalised_wavelength(i: usize) -> f64 {
    i as f64 / (BANDS - 1) as f64
}

/// A reflectance in the paper's function space: ρ(t) = S(c₀t² + c₁t + c₂) with
/// t = (λ − 380 nm) / 400 nm (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SigmoidPolynomial {
    /// c₀, c₁, c₂ for the normalised wavelength t ∈ [0, 1]. All zero is the flat reflectance 0.5.
    pub c: [f32; 3],
}

impl SigmoidPolynomial {
    /// The reflectance in band `band` (0..81, panics beyond, like indexing a [`Spectrum`]):
    /// S(c₀t² + c₁t + c₂), the polynomial in Horner form, one square root and one division.
    #[inline]
    pub fn value(&self, band: usize) -> f32 {
        let t = NORMALISED_WAVELENGTHS[band];
        sigmoid((self.c[0] * t + self.c[1]) * t + self.c[2])
    }

    /// The reflectance on the whole grid.
    pub fn spectrum(&self) -> Spectrum {
        Spectrum(std::array::from_fn(|i| self.value(i)))
    }
}

/// The paper's sigmoid S(x) = 1/2 + x / (2√(1 + x²)), computed without cancellation: with
/// r = √(1 + x²), S(−|x|) = (r − |x|) / (2r) = 1 / (2r(r + |x|)), and S(x) = 1 − S(−x). The
/// textbook form loses the small tail to cancellation (in f32 S(−1000) = 2.5·10⁻⁷ comes out 5 %
/// low, S(−3000) 7 % high); this one keeps its relative precision, and the tail is never exactly
/// 0. The clamp keeps r(r + |x|) from overflowing (|x| ≳ 10¹⁹) and maps ±∞ to finite values:
/// beyond ±10⁶, S is within 2.5·10⁻¹³ of its limit. (S near 1 is 1 − tail, which f32 rounds to 1
/// for x ≳ 4000; the fits of the clamped sRGB cube stay below x ≈ 150.)
#[inline]
fn sigmoid(x: f32) -> f32 {
    let x = x.clamp(-1e6, 1e6);
    let a = x.abs();
    let r = (1.0 + a * a).sqrt();
    let tail = 0.5 / (r * (r + a));
    if x < 0.0 { tail } else { 1.0 - tail }
}

/// S in f64 with its derivative S′(x) = 1 / (2(1 + x²)^{3/2}), for the fit's Jacobian.
fn sigmoid_and_slope(x: f64) -> (f64, f64) {
    let a = x.abs();
    let r2 = 1.0 + a * a;
    let r = r2.sqrt();
    let tail = 0.5 / (r * (r + a));
    let s = if x < 0.0 { tail } else { 1.0 - tail };
    (s, 0.5 / (r2 * r))
}

/// The inverse of S: x = u / √(1 − u²) with u = 2y − 1, for 0 < y < 1. The flat reflectance y is
/// c = (0, 0, S⁻¹(y)).
fn sigmoid_inverse(y: f64) -> f64 {
    let u = 2.0 * y - 1.0;
    u / (1.0 - u * u).sqrt()
}

/// What every fit shares, computed once from the crate's CIE tables.
struct Setup {
    /// Wⱼ(λᵢ): the XYZ of the reflectance that is 1 in band i and 0 elsewhere, under D65, on the
    /// scale Y = 1 for the perfect reflector. A reflectance's XYZ is Σᵢ Wⱼ(λᵢ) ρᵢ: the
    /// relative_xyz sum with the illuminant and normalisation folded in.
    weights: [[f64; BANDS]; 3],
    /// D65 summed over the grid, Y = 1.
    white: Xyz,
    /// Linear sRGB → XYZ (Y = 1) with that white.
    rgb_to_xyz: DMat3,
}

static SETUP: LazyLock<Setup> = LazyLock::new(|| {
    let observer = Observer::Cie1931TwoDegree;
    let d65 = Illuminant::D65.spd().expect("D65 is a tabulated illuminant");
    let mut weights = [[0.0; BANDS]; 3];
    for i in 0..BANDS {
        let mut unit = Spectrum::ZERO;
        unit[i] = 1.0;
        let xyz = relative_xyz(&unit, &d65, observer).scale(0.01).to_array();
        for j in 0..3 {
            weights[j][i] = xyz[j];
        }
    }
    let white = white_point(&d65, observer).scale(0.01);
    Setup { weights, white, rgb_to_xyz: RgbSpace::Srgb.rgb_to_xyz_with_white(white) }
});

/// XYZ (Y = 1 for the perfect reflector under D65) of a linear sRGB reflectance colour, as this
/// module defines it: sRGB primaries with D65 summed over the grid as white, so that
/// (1, 1, 1) ↦ that white. No clamping; [`fit`] clamps before calling it.
pub fn xyz_of_linear_srgb(rgb: [f64; 3]) -> Xyz {
    let v = SETUP.rgb_to_xyz * DVec3::from_array(rgb);
    Xyz::new(v.x, v.y, v.z)
}

/// Linear sRGB of `xyz` (Y = 1 for the perfect reflector under D65): the inverse of
/// [`xyz_of_linear_srgb`].
pub fn linear_srgb_of_xyz(xyz: Xyz) -> [f64; 3] {
    (SETUP.rgb_to_xyz.inverse() * DVec3::new(xyz.x, xyz.y, xyz.z)).to_array()
}

/// The fit stops once ΔE*ab is this small: far below any visible difference (a just-noticeable
/// difference is about 2.3) and far above the rounding of the sums (≈ 10⁻¹³), so it is reached
/// by the iteration's quadratic convergence rather than by luck.
const DELTA_E_CONVERGED: f64 = 1e-8;
/// Gauss–Newton converges in a handful of steps when it converges at all; a start that needs
/// more is too far from the solution and is better helped by the continuation in [`fit`].
const MAX_ITERATIONS: usize = 30;
/// A step is halved until it lowers ΔE; this many halvings without a decrease is a failure.
const MAX_HALVINGS: usize = 12;
/// Coefficients this large belong to no colour of the clamped cube (those need a few hundred at
/// most): an iteration that gets there is running off to an unreachable colour.
const MAX_COEFFICIENT: f64 = 1e5;
/// The continuation gives up when its step towards the target falls below this fraction.
const MIN_CONTINUATION_STEP: f64 = 1.0 / 4096.0;

/// CIE 15:2004 Eq. 8.3's f and its derivative: f(t) = ∛t above (6/29)³, a line of slope
/// (29/6)²/3 below.
fn lab_f_slope(t: f64) -> f64 {
    const DELTA: f64 = 6.0 / 29.0;
    if t > DELTA * DELTA * DELTA {
        1.0 / (3.0 * t.cbrt() * t.cbrt())
    } else {
        1.0 / (3.0 * DELTA * DELTA)
    }
}

/// The CIELAB colour of S(c₀t² + c₁t + c₂) and its Jacobian ∂(L*, a*, b*)/∂(c₀, c₁, c₂) as the
/// columns of a matrix: ∂XYZⱼ/∂cₖ = Σᵢ Wⱼ(λᵢ) S′(xᵢ) tᵢ^(2−k), then the chain rule through
/// L* = 116 f(Y/Yₙ) − 16, a* = 500 (f(X/Xₙ) − f(Y/Yₙ)), b* = 200 (f(Y/Yₙ) − f(Z/Zₙ))
/// (CIE 15:2004 Eqs. 8.1–8.3).
fn lab_and_jacobian(c: [f64; 3]) -> (Lab, DMat3) {
    let setup = &*SETUP;
    let mut xyz = [0.0; 3];
    let mut d_xyz = [[0.0; 3]; 3]; // d_xyz[j][k] = ∂XYZⱼ/∂cₖ
    for i in 0..BANDS {
        let t = normalised_wavelength(i);
        let (s, slope) = sigmoid_and_slope((c[0] * t + c[1]) * t + c[2]);
        let basis = [t * t, t, 1.0];
        for j in 0..3 {
            let w = setup.weights[j][i];
            xyz[j] += w * s;
            for k in 0..3 {
                d_xyz[j][k] += w * slope * basis[k];
            }
        }
    }
    let white = setup.white.to_array();
    let lab = Lab::from_xyz(Xyz::from_array(xyz), setup.white);
    // ∂f(XYZⱼ/XYZₙⱼ)/∂cₖ
    let df: [[f64; 3]; 3] = std::array::from_fn(|j| {
        let slope = lab_f_slope(xyz[j] / white[j]) / white[j];
        std::array::from_fn(|k| slope * d_xyz[j][k])
    });
    let column = |k: usize| {
        DVec3::new(116.0 * df[1][k], 500.0 * (df[0][k] - df[1][k]), 200.0 * (df[1][k] - df[2][k]))
    };
    (lab, DMat3::from_cols(column(0), column(1), column(2)))
}

fn lab_vec(lab: Lab) -> DVec3 {
    DVec3::new(lab.l, lab.a, lab.b)
}

/// Gauss–Newton from `c` towards the CIELAB colour `target` (the paper's §4): the residual
/// r(c) = Lab(c) − target has as many components as unknowns, so the Gauss–Newton step
/// δ = −(JᵀJ)⁻¹Jᵀr is the Newton step δ = −J⁻¹r. Each step is halved until it lowers ΔE*ab = |r|,
/// which keeps the iteration from overshooting where the sigmoid saturates. `None` when ΔE*ab
/// does not fall below [`DELTA_E_CONVERGED`].
fn gauss_newton(target: DVec3, c: [f64; 3]) -> Option<[f64; 3]> {
    let mut c = DVec3::from_array(c);
    let (lab, mut jacobian) = lab_and_jacobian(c.to_array());
    let mut residual = lab_vec(lab) - target;
    let mut error = residual.length();
    for _ in 0..MAX_ITERATIONS {
        if error <= DELTA_E_CONVERGED {
            return Some(c.to_array());
        }
        let determinant = jacobian.determinant();
        if !(determinant.is_finite() && determinant != 0.0) {
            return None;
        }
        let step = -(jacobian.inverse() * residual);
        let mut scale = 1.0;
        let mut improved = false;
        for _ in 0..MAX_HALVINGS {
            let trial = c + step * scale;
            let (trial_lab, trial_jacobian) = lab_and_jacobian(trial.to_array());
            let trial_residual = lab_vec(trial_lab) - target;
            let trial_error = trial_residual.length();
            if trial_error < error {
                (c, jacobian, residual, error) =
                    (trial, trial_jacobian, trial_residual, trial_error);
                improved = true;
                break;
            }
            scale *= 0.5;
        }
        if !improved || !c.is_finite() || c.abs().max_element() > MAX_COEFFICIENT {
            return None;
        }
    }
    (error <= DELTA_E_CONVERGED).then_some(c.to_array())
}

/// The CIELAB colour (white D65 summed over the grid) of a linear sRGB reflectance colour.
fn target_lab(rgb: [f64; 3]) -> DVec3 {
    lab_vec(Lab::from_xyz(xyz_of_linear_srgb(rgb), SETUP.white))
}

/// The sigmoid polynomial whose colour under D65 (CIE 1931 2°, on restauro's grid) is the linear
/// sRGB reflectance colour `rgb`, to ΔE*ab ≤ 10⁻⁸ before the coefficients are rounded to f32.
///
/// Each channel is clamped to [[`RGB_EPSILON`], 1 − [`RGB_EPSILON`]] first (values outside
/// 0..1 are out of the reflectance range and clamped too). A grey (g, g, g) gives the flat
/// spectrum g.
///
/// The iteration starts from c = 0, the flat reflectance 0.5, as colour-science's does. Should it
/// fail there (a saturated colour can be out of Gauss–Newton's reach from so far away), the fit
/// walks from the grey of the same luminance Y, whose coefficients (0, 0, S⁻¹(Y)) are exact,
/// towards the colour along rgb(s) = Y + s·(rgb − Y), each fit starting from the one before, the
/// step in s doubled after a success and halved after a failure: the continuation of
/// colour-science's `find_coefficients_Jakob2019`, which steps from a less saturated colour to the
/// target, as the paper fills its table outwards, each fit starting from a neighbour's solution.
/// With its step halving the direct start converged for every colour of an 11×11×11 grid over
/// the clamped sRGB cube when this was written, so the continuation is a safeguard, which the
/// unit tests check on its own. The fit is deterministic: no randomness, a fixed sequence of
/// trials, the same coefficients bit for bit.
///
/// # Errors
///
/// [`Error::OutOfRange`] for a channel that is not a finite number, or (for no colour of the
/// clamped sRGB cube; the tests check a grid of it) when no sigmoid reaches the colour.
pub fn fit(rgb: [f64; 3]) -> Result<SigmoidPolynomial> {
    for value in rgb {
        if !value.is_finite() {
            return Err(Error::OutOfRange {
                quantity: "linear sRGB channel",
                value,
                expected: "a finite number (0..1; values outside are clamped)",
            });
        }
    }
    let rgb = rgb.map(|v| v.clamp(RGB_EPSILON, 1.0 - RGB_EPSILON));
    let c = match gauss_newton(target_lab(rgb), [0.0; 3]) {
        Some(c) => c,
        None => continuation(rgb)?,
    };
    Ok(SigmoidPolynomial { c: c.map(|v| v as f32) })
}

/// The fit by continuation from the grey of the same luminance (see [`fit`]). `rgb` must have a
/// luminance Y in (0, 1); Y is a convex combination of the channels (the sRGB luminance row is
/// positive and sums to 1), so for a colour of the clamped cube the grey and every rgb(s) stay
/// inside the cube.
fn continuation(rgb: [f64; 3]) -> Result<[f64; 3]> {
    let y = xyz_of_linear_srgb(rgb).y;
    let mut c = [0.0, 0.0, sigmoid_inverse(y)];
    let (mut s, mut ds) = (0.0f64, 0.5f64);
    while s < 1.0 {
        let next = (s + ds).min(1.0);
        let colour = rgb.map(|v| y + next * (v - y));
        match gauss_newton(target_lab(colour), c) {
            Some(found) => {
                (c, s) = (found, next);
                ds *= 2.0;
            }
            None => {
                ds *= 0.5;
                if ds < MIN_CONTINUATION_STEP {
                    return Err(Error::OutOfRange {
                        quantity: "the fraction of the colour's saturation a sigmoid reaches",
                        value: s,
                        expected: "1; this colour has no sigmoid spectrum",
                    });
                }
            }
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmoid_is_the_papers_with_a_precise_tail() {
        for k in -400..=400 {
            // x on the f32 grid, so that the f32 result is compared at the same argument.
            let x = f64::from(k as f32 / 20.0);
            let textbook = 0.5 + x / (2.0 * (1.0 + x * x).sqrt());
            let got = f64::from(sigmoid(x as f32));
            // A few f32 roundings of the result, relative: the tail keeps its digits too.
            assert!((got - textbook).abs() <= 3e-7 * textbook, "S({x}) = {got} vs {textbook}");
            let (s, slope) = sigmoid_and_slope(x);
            assert!((s - textbook).abs() < 1e-15, "{x}");
            // The slope against a central difference.
            let h = 1e-6;
            let (up, down) = (sigmoid_and_slope(x + h).0, sigmoid_and_slope(x - h).0);
            assert!((slope - (up - down) / (2.0 * h)).abs() < 1e-8, "S'({x}) = {slope}");
        }
        // The small tail keeps its digits where 1/2 + x/(2r) would cancel: S(−x) ≈ 1/(4x²).
        let tail = f64::from(sigmoid(-1000.0));
        assert!((tail / 2.5e-7 - 1.0).abs() < 1e-6, "{tail}");
        // Far out the tail stays positive, and +∞ gives the limit 1 (as f32 rounds 1 − 2.5e-13).
        assert!(sigmoid(-1e30) > 0.0 && sigmoid(f32::NEG_INFINITY) > 0.0);
        assert_eq!(sigmoid(f32::INFINITY), 1.0);
        for y in [1e-4, 0.02, 0.5, 0.93, 1.0 - 1e-4] {
            assert!((sigmoid_and_slope(sigmoid_inverse(y)).0 - y).abs() < 1e-15, "{y}");
        }
    }

    #[test]
    fn zero_coefficients_are_the_flat_half() {
        assert_eq!(SigmoidPolynomial::default().spectrum(), Spectrum::splat(0.5));
    }

    #[test]
    fn value_follows_the_normalised_wavelength() {
        // c = (0, 1, −0.5): x = t − 1/2 runs from −1/2 at 380 nm to 1/2 at 780 nm.
        let p = SigmoidPolynomial { c: [0.0, 1.0, -0.5] };
        let at = |x: f64| (0.5 + x / (2.0 * (1.0 + x * x).sqrt())) as f32;
        assert!((p.value(0) - at(-0.5)).abs() < 1e-7);
        assert!((p.value(40) - 0.5).abs() < 1e-7);
        assert!((p.value(80) - at(0.5)).abs() < 1e-7);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let c = [12.0, -9.0, 1.5];
        let (_, jacobian) = lab_and_jacobian(c);
        for k in 0..3 {
            let h = 1e-6;
            let (mut up, mut down) = (c, c);
            up[k] += h;
            down[k] -= h;
            let numeric =
                (lab_vec(lab_and_jacobian(up).0) - lab_vec(lab_and_jacobian(down).0)) / (2.0 * h);
            let analytic = jacobian.col(k);
            assert!((numeric - analytic).abs().max_element() < 1e-5, "{numeric} vs {analytic}");
        }
    }

    #[test]
    fn white_and_matrix_agree_with_the_grid() {
        // The perfect reflector is (1, 1, 1), and the weights sum to the white.
        let w = xyz_of_linear_srgb([1.0; 3]);
        let sums: Vec<f64> = SETUP.weights.iter().map(|row| row.iter().sum()).collect();
        for (a, b) in [w.x, w.y, w.z].iter().zip(&sums) {
            assert!((a - b).abs() < 1e-12, "{w:?} vs {sums:?}");
        }
        let back = linear_srgb_of_xyz(xyz_of_linear_srgb([0.2, 0.5, 0.7]));
        for (a, b) in back.iter().zip([0.2, 0.5, 0.7]) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn non_finite_input_is_refused() {
        assert!(fit([f64::NAN, 0.5, 0.5]).is_err());
        assert!(fit([0.5, f64::INFINITY, 0.5]).is_err());
        // Out-of-range finite values are clamped, not refused.
        let clamped = fit([-1.0, 2.0, 0.5]).unwrap();
        assert_eq!(clamped, fit([0.0, 1.0, 0.5]).unwrap());
    }

    /// On the sRGB cube the direct start converges everywhere (an 11×11×11 grid was checked when
    /// this was written), so the continuation is a safeguard; it is checked here on its own: from
    /// the grey it must reach the same coefficients as the direct start, since the solution is
    /// unique.
    #[test]
    fn continuation_reaches_the_direct_solution() {
        for rgb in [
            [0.9999, 0.0001, 0.0001],
            [0.0001, 0.9999, 0.0001],
            [0.0001, 0.0001, 0.9999],
            [0.9999, 0.9999, 0.0001],
            [0.0001, 0.0001, 0.1],
            [0.7, 0.05, 0.8],
        ] {
            let direct = gauss_newton(target_lab(rgb), [0.0; 3]).unwrap();
            let continued = continuation(rgb).unwrap();
            for (a, b) in direct.iter().zip(continued) {
                assert!(
                    (a - b).abs() < 1e-6 * a.abs().max(1.0),
                    "{rgb:?}: {direct:?} vs {continued:?}"
                );
            }
        }
    }

    /// A colour outside the spectral locus (its Z is negative, which no light's is) has no
    /// sigmoid spectrum, and the continuation says so rather than returning a wrong one.
    #[test]
    fn continuation_refuses_an_unreachable_colour() {
        let rgb = [-0.5, 1.0, -0.5];
        let error = continuation(rgb).unwrap_err().to_string();
        assert!(error.contains("no sigmoid spectrum"), "{error}");
    }
}
