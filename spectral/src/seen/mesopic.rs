//! Night: mesopic vision, where the rods take part and colour weakens.
//!
//! Below about 5 cd/m² of adapting luminance the rods add to the cones' signal, and below
//! 0.005 cd/m² they see alone (CIE 191:2010, "Recommended system for mesopic photometry based
//! on visual performance"). CIE 191 weighs the two with the adaptation coefficient m:
//!
//! ```text
//!   L_mes = (m · L_p + (1 − m) · L_s · V′(λ₀)) / (m + (1 − m) · V′(λ₀)),   V′(λ₀) = 683/1699,
//!   m = a + b · log₁₀ L_mes,   a = 0.7670, b = 0.3334,   m clipped to 0 … 1,
//! ```
//!
//! solved by iteration from the photopic and scotopic luminances of the adapting field. m is 1
//! in daylight and at a lit shop window, about 0.6 on a floodlit facade (0.5 cd/m²), 0.3 under
//! a full moon.
//!
//! The rods have one kind of pigment: what they add has no hue. We take m as the share of the
//! signal that still carries colour, so a colour's CIELAB chroma is scaled by m, its hue and
//! lightness kept — a warm light on pale stone at 0.5 cd/m² is still seen warm, weaker. (Kirk &
//! O'Brien 2011 and Wanat & Mantiuk 2014 model the rods' intrusion into the opponent channels
//! in more detail, with a shift of hue towards blue-green; that shift and the loss of acuity at
//! night are not modelled here.)

/// CIE 191:2010's coefficients.
const A: f64 = 0.7670;
const B: f64 = 0.3334;
/// The mesopic range of CIE 191, in cd/m² of mesopic luminance.
pub const PHOTOPIC_FROM_CD_M2: f64 = 5.0;
pub const SCOTOPIC_BELOW_CD_M2: f64 = 0.005;

/// V′(λ₀), λ₀ = 555 nm, as CIE 191 takes it: 683/1699.
fn v_prime_555() -> f64 {
    crate::colorimetry::K_M_LM_PER_W / crate::cie::scotopic_efficacy_lm_per_w()
}

/// m for an adapting field of photopic luminance `photopic_cd_m2` and scotopic luminance
/// `scotopic_cd_m2` (scotopic cd/m², K′_m = 1699 lm/W).
pub fn adaptation_coefficient(photopic_cd_m2: f64, scotopic_cd_m2: f64) -> f64 {
    if photopic_cd_m2.is_nan() || photopic_cd_m2 <= 0.0 {
        return 0.0;
    }
    let v0 = v_prime_555();
    let scotopic = scotopic_cd_m2.max(0.0);
    let mut m = 0.5;
    for _ in 0..100 {
        let mesopic = (m * photopic_cd_m2 + (1.0 - m) * scotopic * v0) / (m + (1.0 - m) * v0);
        let next = if mesopic >= PHOTOPIC_FROM_CD_M2 {
            1.0
        } else if mesopic <= SCOTOPIC_BELOW_CD_M2 {
            0.0
        } else {
            (A + B * mesopic.log10()).clamp(0.0, 1.0)
        };
        if (next - m).abs() < 1e-9 {
            return next;
        }
        m = next;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photopic_and_scotopic_ends() {
        assert_eq!(adaptation_coefficient(100.0, 200.0), 1.0);
        assert_eq!(adaptation_coefficient(0.001, 0.002), 0.0);
        assert_eq!(adaptation_coefficient(0.0, 0.0), 0.0);
    }

    /// When the scotopic luminance equals the photopic one (S/P = 1), L_mes = L_p whatever m,
    /// so m = a + b log₁₀ L_p: a = 0.767 at 1 cd/m², and m reaches 1 at 5 cd/m².
    #[test]
    fn the_standards_line() {
        for lp in [0.01, 0.1, 0.5, 1.0, 3.0] {
            let m = adaptation_coefficient(lp, lp);
            assert!((m - (A + B * f64::log10(lp))).abs() < 1e-6, "{lp}: {m}");
        }
        // A bluer light (more scotopic per photopic) is seen more photopically at the same L_p.
        let warm = adaptation_coefficient(0.5, 0.5 * 1.2);
        let cool = adaptation_coefficient(0.5, 0.5 * 2.4);
        assert!(cool > warm, "{cool} {warm}");
    }
}
