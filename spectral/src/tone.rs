//! The display's tone curve: how a luminance relative to the reference white (1 = the white of
//! the exposure) becomes display luminance (1 = the display's white).
//!
//! The curve acts on luminance alone; [`crate::display`] scales the linear RGB of a colour by
//! Y′/Y, so its chromaticity is kept, and gamut-maps only what is still outside the cube.
//!
//! * **The reference white is shown at [`REFERENCE_WHITE`] = 0.7 of the display's white.** A
//!   white lit by a chromatic light is outside the display's gamut near the display's white: the
//!   white tile under CIE A (x 0.44757, y 0.40745) needs linear sRGB ≈ (1.85, 0.83, 0.23) · Y
//!   (IEC 61966-2-1), so at Y = 1 only the grey (1, 1, 1) is left and its hue is lost, and it
//!   fits whole only below Y ≈ 0.54. At 0.7 the whites of CIE B (R 1.25 · Y), C and every
//!   daylight are shown whole and A's keeps half its chroma (at 0.8 it would keep 30 % and look
//!   as B's white does, though their ΔE00 to D65 are 27 and 13); a lower level would dim every
//!   image for A alone. The 0.3 left above it are for what is brighter than the white:
//!   speculars, the sky, a lamp.
//! * **Linear up to the knee, [`KNEE`] = the reference white's level.** Below it the display
//!   luminance is 0.7 · Y exactly, so every surface no brighter than the reference white keeps
//!   its colorimetry up to one common factor — what a restorer compares. Only what is brighter
//!   than the reference white is compressed.
//! * **Above the knee, a Reinhard shoulder** (Reinhard, Stark, Shirley & Ferwerda, "Photographic
//!   tone reproduction for digital images", SIGGRAPH 2002, Eq. 3, L_d = L / (1 + L)), shifted
//!   and scaled to start at the knee with the linear part's slope:
//!
//!   L_d = k + (1 − k) · u / (1 + u),  u = (0.7 · Y − k) / (1 − k),
//!
//!   which is monotonic, C¹ at the knee (both slopes are 0.7 in Y), and approaches 1 only
//!   asymptotically: twice the reference white is shown at 0.91, and a neutral colour reaches
//!   the 8-bit white (0.99568, code 255) only at about 30 times the reference white. Nothing is
//!   clipped to white unless it is far above the reference white.

/// The display luminance of the reference white (the display's white = 1).
pub const REFERENCE_WHITE: f64 = 0.7;

/// The display luminance where the linear part ends and the shoulder begins: the reference
/// white's, so that nothing up to the reference white is compressed.
pub const KNEE: f64 = REFERENCE_WHITE;

/// The display luminance (0 ≤ L_d < 1, the display's white = 1) of a luminance `y` relative to
/// the reference white (1 = the reference white). Zero and negative luminances pass through
/// linearly (the gamut mapping shows them as black); infinity is the display's white.
pub fn display_luminance(y: f64) -> f64 {
    let linear = REFERENCE_WHITE * y;
    if linear <= KNEE || linear.is_nan() {
        return linear;
    }
    if linear.is_infinite() {
        return 1.0;
    }
    let u = (linear - KNEE) / (1.0 - KNEE);
    KNEE + (1.0 - KNEE) * u / (1.0 + u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn below_the_knee_the_curve_is_the_stated_linear_part() {
        for y in [0.0, 1e-6, 0.18, 0.5, 0.9, 1.0] {
            assert!((display_luminance(y) - 0.7 * y).abs() < 1e-15, "{y}");
        }
        // The reference white is shown at 0.7 of the display's white.
        assert!((display_luminance(1.0) - 0.7).abs() < 1e-15);
    }

    #[test]
    fn the_curve_is_monotonic_below_one_and_c1_at_the_knee() {
        let mut previous = display_luminance(0.0);
        for i in 1..=200_000 {
            let y = f64::from(i) * 1e-4;
            let l = display_luminance(y);
            assert!(l > previous, "not increasing at {y}: {previous} → {l}");
            assert!(l < 1.0, "{y} → {l}");
            previous = l;
        }
        // One-sided difference quotients on either side of the knee (Y = 1) agree with each
        // other and with the linear part's slope 0.7; the shoulder's curvature at the knee is
        // −2 · 0.7² / (1 − k) ≈ −3.3, so a step h leaves an error of about 1.6 h.
        let h = 1e-7;
        let knee_y = KNEE / REFERENCE_WHITE;
        let below = (display_luminance(knee_y) - display_luminance(knee_y - h)) / h;
        let above = (display_luminance(knee_y + h) - display_luminance(knee_y)) / h;
        assert!((below - 0.7).abs() < 1e-6, "{below}");
        assert!((above - 0.7).abs() < 1e-5, "{above}");
        // A kink would show as a jump between the two; the value is continuous too.
        assert!((above - below).abs() < 1e-5, "{below} vs {above}");
        assert!((display_luminance(knee_y + 1e-12) - KNEE).abs() < 1e-11);
    }

    #[test]
    fn only_what_is_far_above_the_reference_white_reaches_the_display_white() {
        // Twice the reference white: u = (1.4 − 0.7) / 0.3 = 7/3, L_d = 0.7 + 0.3 · 0.7 = 0.91.
        assert!((display_luminance(2.0) - 0.91).abs() < 1e-12);
        // The 8-bit white: an sRGB code of 255 needs an encoded value of at least 254.5/255,
        // i.e. linear ((254.5/255 + 0.055)/1.055)^2.4 ≈ 0.99568 (IEC 61966-2-1). That is
        // u ≥ 0.3/0.00432 − 1 ≈ 68.4, Y ≥ (0.7 + 0.3 · 68.4)/0.7 ≈ 30.
        let code_255 = ((254.5 / 255.0 + 0.055) / 1.055f64).powf(2.4);
        assert!(display_luminance(25.0) < code_255);
        assert!(display_luminance(35.0) > code_255);
        assert_eq!(display_luminance(f64::INFINITY), 1.0);
        assert!(display_luminance(f64::NAN).is_nan());
    }
}
