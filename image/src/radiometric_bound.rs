//! The largest radiometric value restauro accepts anywhere: in a tile from a worker and in an
//! OpenEXR a user gives it.
//!
//! The brightest a tracer can make within the scene limits: a light of
//! `MAX_INTENSITY_CD` = 10⁹ cd at its nearest, 1 mm (nearer, the inverse-square law no longer
//! holds and the tracer lights as at 1 mm), gives 10¹⁵ lx; the sharpest Cook–Torrance lobe
//! (roughness 10⁻³: a Beckmann peak of 1/(πα²) ≈ 3·10⁵ sr⁻¹, over 4·cos θ₀ ≥ 4·10⁻⁶) returns at
//! most about 10¹¹ sr⁻¹ of it: about 10²⁶ cd/m². A spectral band of a light normalised to one
//! candela is at most about 30 times its luminance (V(λ) ≥ 10⁻⁵ at 780 nm, over 683 lm/W and
//! 5 nm). So [`MAX_RADIOMETRIC`], 10³⁰, leaves four orders of margin above anything a honest
//! worker sends, while every later stage stays finite in `f32`: a sum over the
//! [`crate::image_files::MAX_PIXELS`] = 2²⁸ pixels of an image is at most 2.7·10³⁸, below
//! `f32::MAX` = 3.4·10³⁸, and a colour-space matrix (entries ≤ 3.3) applied to a value does not
//! reach it either.

/// The bound on X, Y, Z (Y in cd/m²), on an adapting white's values and on spectral radiance
/// (W·m⁻²·sr⁻¹·nm⁻¹): finite, ≥ 0 and at most this.
pub const MAX_RADIOMETRIC: f32 = 1e30;

/// Whether `v` is a value a tracer can produce: finite, not negative, within [`MAX_RADIOMETRIC`].
#[inline]
pub fn is_radiometric(v: f32) -> bool {
    (0.0..=MAX_RADIOMETRIC).contains(&v)
}

/// Whether `v` is a colour value an image file may carry: finite and within
/// ±[`MAX_RADIOMETRIC`] (an RGB channel may be negative outside its gamut).
#[inline]
pub fn is_colour_value(v: f32) -> bool {
    (-MAX_RADIOMETRIC..=MAX_RADIOMETRIC).contains(&v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_keeps_sums_and_matrices_finite_in_f32() {
        let pixels = crate::image_files::MAX_PIXELS as f32;
        assert!((MAX_RADIOMETRIC * pixels).is_finite());
        // The largest entry of the XYZ → linear sRGB matrix (IEC 61966-2-1) is 3.2406.
        assert!((MAX_RADIOMETRIC * 3.3 * 3.0).is_finite());
        for v in [f32::NAN, f32::INFINITY, -1.0, 3.4e38, 1.01e30] {
            assert!(!is_radiometric(v), "{v}");
        }
        for v in [0.0, 1e-30, 1e29, MAX_RADIOMETRIC] {
            assert!(is_radiometric(v), "{v}");
        }
        assert!(is_colour_value(-1e29) && !is_colour_value(-3.4e38) && !is_colour_value(f32::NAN));
    }
}
