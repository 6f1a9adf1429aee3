//! How completely the eye discounts the colour of the light: the degree of adaptation D, and
//! the corresponding colour under D65 that it gives.
//!
//! **Luminance.** CAM16's (and CIECAM02's) degree of adaptation for an average surround
//! (CIE 159:2004; Li et al. 2017):
//!
//! ```text
//!   D_L = F · [1 − (1/3.6) · exp((−L_A − 42) / 92)],   F = 1,
//! ```
//!
//! with L_A the adapting luminance in cd/m², taken as a fifth of the white's luminance
//! (CIECAM02's L_A = L_W · Y_b / 100 with a background of Y_b = 20). D_L is 0.82 in the dark
//! and 1 in daylight.
//!
//! **Chromaticity: the blue bias.** People discount a bluish daylight almost wholly and a warm
//! or a coloured light only partly (Pearce et al. 2014; Weiss, Witzel & Gegenfurtner 2017;
//! Wei & Chen 2019 found D lower at 2700 and 3500 K than at higher CCTs, at one luminance). So
//! D is also scaled by how far the light lies from the bluish half of the daylight locus:
//!
//! ```text
//!   D = D_L · max(0, 1 − β · Δ),   Δ = the u′v′ distance from the light to the CIE daylight
//!                                      locus between 6500 K and 25 000 K,
//! ```
//!
//! zero for D65 and any bluer daylight (a clear sky), 0.012 for a 5000 K sun, 0.08 for CIE A or
//! a 3000 K lamp. β = [`BLUE_BIAS_PER_UV`] is the one parameter fitted here, on two of
//! Breneman's (1987) nine experiments (4, illuminant A at 75 cd/m², and 11, D55 against a
//! green light at 1560 cd/m²; `spectral/tests/breneman.rs` refits it and checks the constant);
//! the seven others are reported, not fitted.
//!
//! **The corresponding colour.** A colour seen under a white W with degree D is shown as the
//! colour that looks the same under D65 with the same D: CAM16's corresponding colour for the
//! same viewing conditions (Li et al. 2017), whose CAT16 part is, per cone,
//!
//! ```text
//!   ρ_65 = ρ · (D / ρ_W + 1 − D) / (D / ρ_D65 + 1 − D),   ρ = M16 · XYZ / Y_W,
//! ```
//!
//! (the two-step form of Smet et al. 2017 with CAT16's equal-energy baseline). CAM16's
//! non-linear stages, run forward under W and back under D65 at the same L_A, change the
//! result by less than 0.1 ΔE00 for the shipped stones under A, D50, D65 and 10 000 K; the
//! linear form is exact for a white and keeps a lightness factor a factor.

use crate::adaptation::ConeSpace;
use crate::appearance::d65_white;
use crate::colorimetry::Xyz;
use crate::illuminant::daylight_chromaticity;
use glam::{DMat3, DVec3};
use std::sync::LazyLock;

/// β: the loss of adaptation per unit of u′v′ distance from the bluish daylight locus. Fitted
/// on Breneman's experiments 4 and 11 only (mean ΔE00 over their pairs, a 0.1 grid from 0
/// to 4): 2.5.
pub const BLUE_BIAS_PER_UV: f64 = 2.5;
/// The adapting luminance as a share of the white's: a grey-world background of Y_b = 20.
pub const ADAPTING_SHARE_OF_WHITE: f64 = 0.2;
/// The warmest daylight whose colour is discounted wholly.
const BLUE_DAYLIGHT_FROM_K: f64 = 6500.0;

/// CAM16's degree of adaptation at adapting luminance `la_cd_m2`, average surround (F = 1).
pub fn luminance_term(la_cd_m2: f64) -> f64 {
    (1.0 - (1.0 / 3.6) * ((-la_cd_m2 - 42.0) / 92.0).exp()).clamp(0.0, 1.0)
}

/// CIE 1976 u′v′ of a colour (None for black).
pub fn uv(xyz: Xyz) -> Option<(f64, f64)> {
    let d = xyz.x + 15.0 * xyz.y + 3.0 * xyz.z;
    (d > 0.0).then(|| (4.0 * xyz.x / d, 9.0 * xyz.y / d))
}

/// Segments of the polyline that stands for the locus: its chords lie within 2·10⁻⁵ of it in
/// u′v′ (the distance of a 12 000 K daylight from it), and the distance is taken at every
/// pixel of a seen image.
const LOCUS_SEGMENTS: u32 = 16;

/// One chord of the locus polyline: its start, its direction and the reciprocal of its
/// squared length (so that the distance at each pixel multiplies rather than divides).
struct Chord {
    u0: f64,
    v0: f64,
    du: f64,
    dv: f64,
    inverse_length2: f64,
}

/// The bluish half of the CIE daylight locus in u′v′, as a polyline even in reciprocal
/// temperature (mired).
static BLUE_DAYLIGHT: LazyLock<Vec<Chord>> = LazyLock::new(|| {
    let (from, to) = (1e6 / BLUE_DAYLIGHT_FROM_K, 1e6 / 25_000.0);
    let points: Vec<(f64, f64)> = (0..=LOCUS_SEGMENTS)
        .map(|i| {
            let mired = from + (to - from) * f64::from(i) / f64::from(LOCUS_SEGMENTS);
            let c = daylight_chromaticity(1e6 / mired).expect("within the daylight locus");
            uv(c.to_xyz(1.0)).expect("a daylight is not black")
        })
        .collect();
    points
        .windows(2)
        .map(|s| {
            let ((u0, v0), (u1, v1)) = (s[0], s[1]);
            let (du, dv) = (u1 - u0, v1 - v0);
            Chord { u0, v0, du, dv, inverse_length2: 1.0 / (du * du + dv * dv) }
        })
        .collect()
});

/// Δ: the u′v′ distance from `white` to the daylight locus between 6500 K and 25 000 K.
pub fn distance_from_blue_daylight(white: Xyz) -> f64 {
    let Some((u, v)) = uv(white) else { return 0.0 };
    // The nearest chord by squared distance, one square root at the end: this runs at every
    // pixel of a seen image, where a `hypot` and a division per chord took a tenth of its time.
    BLUE_DAYLIGHT
        .iter()
        .map(|c| {
            let (pu, pv) = (u - c.u0, v - c.v0);
            let t = ((pu * c.du + pv * c.dv) * c.inverse_length2).clamp(0.0, 1.0);
            let (eu, ev) = (pu - t * c.du, pv - t * c.dv);
            eu * eu + ev * ev
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// The chromatic term of D: 1 − β·Δ, at least 0.
pub fn chromatic_term(white: Xyz) -> f64 {
    (1.0 - BLUE_BIAS_PER_UV * distance_from_blue_daylight(white)).max(0.0)
}

/// D for a white of this colour whose luminance is `white_cd_m2`.
pub fn degree_of_adaptation(white: Xyz, white_cd_m2: f64) -> f64 {
    luminance_term(ADAPTING_SHARE_OF_WHITE * white_cd_m2) * chromatic_term(white)
}

/// The CAT16 cone matrix and the cones of the D65 white (Y = 1).
static CAT16: LazyLock<(DMat3, DMat3, DVec3)> = LazyLock::new(|| {
    let m = ConeSpace::Cat16.matrix();
    let w = d65_white();
    (m, m.inverse(), m * DVec3::new(w.x, w.y, w.z))
});

/// The CAT16 cone matrix M16 and its inverse.
pub(super) fn cat16_matrices() -> (DMat3, DMat3) {
    let (m, m_inv, _) = &*CAT16;
    (*m, *m_inv)
}

/// The corresponding-colour transform of a white: the matrix that carries XYZ seen under
/// `white` (any luminance), divided by the white's luminance, to XYZ under D65 (Y = 1 for
/// white), with degree of adaptation `d` on both sides (see the module comment).
pub fn to_d65(white: Xyz, d: f64) -> DMat3 {
    let (m, m_inv, d65) = &*CAT16;
    let w = *m * DVec3::new(white.x, white.y, white.z) / white.y.max(f64::MIN_POSITIVE);
    let gain = DVec3::new(
        (d / w.x + 1.0 - d) / (d / d65.x + 1.0 - d),
        (d / w.y + 1.0 - d) / (d / d65.y + 1.0 - d),
        (d / w.z + 1.0 - d) / (d / d65.z + 1.0 - d),
    );
    *m_inv * DMat3::from_diagonal(gain) * *m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Chromaticity;

    #[test]
    fn the_luminance_term_is_cam16s() {
        // CIE 159:2004's values: L_A = 318.31 cd/m² gives D = 0.9944 (the standard's worked
        // example, F = 1).
        assert!((luminance_term(318.31) - 0.9944).abs() < 1e-4);
        assert!((luminance_term(0.0) - (1.0 - (-42.0f64 / 92.0).exp() / 3.6)).abs() < 1e-12);
    }

    #[test]
    fn daylight_bluer_than_d65_is_discounted_whole_and_a_warm_light_not() {
        let at = |x, y| Chromaticity::new(x, y).to_xyz(1.0);
        let d65 = d65_white();
        assert!(distance_from_blue_daylight(d65) < 1e-3, "{}", distance_from_blue_daylight(d65));
        let sky = daylight_chromaticity(12_000.0).unwrap().to_xyz(1.0);
        assert!(distance_from_blue_daylight(sky) < 2e-5, "{}", distance_from_blue_daylight(sky));
        let a = at(0.44758, 0.40745);
        let delta = distance_from_blue_daylight(a);
        assert!((0.075..0.09).contains(&delta), "CIE A: {delta}");
        assert!(chromatic_term(a) < 0.82 && chromatic_term(sky) > 0.9999);
    }

    #[test]
    fn white_goes_to_d65_when_adaptation_is_complete_and_d65_stays_itself() {
        let a = Chromaticity::new(0.44758, 0.40745).to_xyz(40.0);
        let m = to_d65(a, 1.0);
        let w = m * DVec3::new(a.x, a.y, a.z) / a.y;
        let d = d65_white();
        assert!((w.x - d.x).abs() < 1e-9 && (w.y - 1.0).abs() < 1e-9 && (w.z - d.z).abs() < 1e-9);
        // D65 itself is seen as D65 whatever the degree.
        for degree in [0.0, 0.5, 0.9] {
            let m = to_d65(d, degree);
            let v = m * DVec3::new(0.3, 0.2, 0.5);
            assert!((v - DVec3::new(0.3, 0.2, 0.5)).length() < 1e-9, "{degree}: {v}");
        }
        // Without adaptation the white under A keeps A's colour.
        let w = to_d65(a, 0.0) * DVec3::new(a.x, a.y, a.z) / a.y;
        assert!((w.x / w.y - a.x / a.y).abs() < 1e-9);
    }
}
