//! The CIEDE2000 colour-difference formula ΔE00 (CIE 142-2001, ISO/CIE 11664-6).
//!
//! The computation follows G. Sharma, W. Wu and E. N. Dalal, "The CIEDE2000 color-difference
//! formula: Implementation notes, supplementary test data, and mathematical observations",
//! Color Res. Appl. 30(1), 21–30 (2005), equation by equation; equation numbers in the comments
//! below are theirs. Their implementation notes are followed where the standard's text leaves
//! room for error: the hue angle of a colour with a′ = b* = 0 is 0 (eq. 7), the hue difference
//! and the mean hue fall back to special rules when the product of the chromas is zero
//! (eqs. 10 and 14), and hue angles are taken from atan2 and mapped to [0°, 360°).
//!
//! Angles are kept in degrees, as in the paper, so that the branch thresholds (180°, 360°) and
//! the constants of T and Δθ (30°, 6°, 63°, 275°, 25°) read exactly as published; they are
//! converted to radians only at the point where a trigonometric function is called.

use crate::lab::Lab;

/// Parametric weights k_L, k_C, k_H (all 1 under reference conditions).
///
/// They divide the lightness, chroma and hue terms of eq. 22 (for instance k_L = 2 is common
/// in the textile industry). They must be positive; a zero weight gives an infinite or NaN
/// result rather than a panic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    pub k_l: f64,
    pub k_c: f64,
    pub k_h: f64,
}

impl Default for Weights {
    /// The reference conditions of CIE 142-2001: k_L = k_C = k_H = 1.
    fn default() -> Self {
        Self { k_l: 1.0, k_c: 1.0, k_h: 1.0 }
    }
}

/// 25⁷, from eqs. 4 and 17: the ratio C⁷ / (C⁷ + 25⁷) that drives G and R_C is one half at a
/// mean chroma of 25. Written out as a constant because it is exact in f64.
const TWENTY_FIVE_POW_7: f64 = 6_103_515_625.0;

/// ΔE00 between `reference` (colour 1 of Sharma et al.) and `sample` (colour 2) under the
/// reference conditions k_L = k_C = k_H = 1.
///
/// The result is symmetric in its arguments and 0 for identical colours.
#[must_use]
pub fn ciede2000(reference: Lab, sample: Lab) -> f64 {
    ciede2000_weighted(reference, sample, Weights::default())
}

/// ΔE00 between `reference` (colour 1) and `sample` (colour 2) with parametric weights `w`.
///
/// Sharma et al. (2005) eqs. 2–22. Non-finite inputs propagate to a non-finite result; the
/// function never panics and does not allocate.
#[must_use]
pub fn ciede2000_weighted(reference: Lab, sample: Lab, w: Weights) -> f64 {
    let (l1, a1, b1) = (reference.l, reference.a, reference.b);
    let (l2, a2, b2) = (sample.l, sample.a, sample.b);

    // Step 1: C′ᵢ and h′ᵢ.

    // Eqs. 2–3: CIELAB chromas and their mean. The mean drives G, so that the a* stretch
    // is the same for both colours.
    let c_ab_mean = (a1.hypot(b1) + a2.hypot(b2)) / 2.0;

    // Eq. 4: G rises towards 0.5 for near-neutral pairs, stretching a* there; this is the
    // correction that improves CIELAB's performance close to the achromatic axis.
    let c_ab_mean_7 = c_ab_mean.powi(7);
    let g = 0.5 * (1.0 - (c_ab_mean_7 / (c_ab_mean_7 + TWENTY_FIVE_POW_7)).sqrt());

    // Eq. 5: the stretched a′ᵢ; L′ = L* and b′ = b* are unchanged.
    let a1p = (1.0 + g) * a1;
    let a2p = (1.0 + g) * a2;

    // Eq. 6: chroma in the a′b* plane.
    let c1p = a1p.hypot(b1);
    let c2p = a2p.hypot(b2);

    // Eq. 7: hue angles in [0°, 360°).
    let h1p = hue_deg(a1p, b1);
    let h2p = hue_deg(a2p, b2);

    // The special cases of eqs. 10 and 14 hinge on whether either colour is neutral (has
    // no hue). The test is exact, as in the paper: any non-zero chroma has a hue.
    let chroma_product = c1p * c2p;
    let either_neutral = chroma_product == 0.0;

    // Step 2: ΔL′, ΔC′, ΔH′.

    // Eqs. 8–9: lightness and chroma differences, sample minus reference.
    let delta_l = l2 - l1;
    let delta_c = c2p - c1p;

    // Eq. 10: the hue difference, taken the short way round the hue circle so that it lies
    // in [−180°, 180°]. It is 0 when either colour is neutral, since a hue difference is
    // then meaningless (and ΔH′ of eq. 11 would be 0 regardless).
    let delta_h_deg = if either_neutral {
        0.0
    } else {
        let d = h2p - h1p;
        if d > 180.0 {
            d - 360.0
        } else if d < -180.0 {
            d + 360.0
        } else {
            d
        }
    };

    // Eq. 11: the metric hue difference ΔH′, the chord subtended by Δh′ at the geometric
    // mean chroma.
    let delta_h = 2.0 * chroma_product.sqrt() * (delta_h_deg / 2.0).to_radians().sin();

    // Step 3: ΔE00.

    // Eqs. 12–13: arithmetic means of L′ and C′.
    let l_mean = (l1 + l2) / 2.0;
    let c_mean = (c1p + c2p) / 2.0;

    // Eq. 14: the mean hue, again the short way round. When either colour is neutral its hue
    // (0 by eq. 7) carries no information, so the sum h′₁ + h′₂ is used: it equals the hue of
    // the other colour (or 0 if both are neutral).
    let h_sum = h1p + h2p;
    let h_mean = if either_neutral {
        h_sum
    } else if (h1p - h2p).abs() <= 180.0 {
        h_sum / 2.0
    } else if h_sum < 360.0 {
        (h_sum + 360.0) / 2.0
    } else {
        (h_sum - 360.0) / 2.0
    };

    // Eq. 15: T, the hue dependence of the hue weighting function S_H.
    let t = 1.0 - 0.17 * cos_deg(h_mean - 30.0)
        + 0.24 * cos_deg(2.0 * h_mean)
        + 0.32 * cos_deg(3.0 * h_mean + 6.0)
        - 0.20 * cos_deg(4.0 * h_mean - 63.0);

    // Eq. 16: Δθ, a bump of up to 30° centred on the blue region (h̄′ ≈ 275°) where the
    // rotation term below acts.
    let delta_theta_deg = 30.0 * (-((h_mean - 275.0) / 25.0).powi(2)).exp();

    // Eq. 17: R_C, the chroma dependence of the rotation term (rises to 2 at high chroma).
    let c_mean_7 = c_mean.powi(7);
    let r_c = 2.0 * (c_mean_7 / (c_mean_7 + TWENTY_FIVE_POW_7)).sqrt();

    // Eqs. 18–20: the weighting functions for lightness, chroma and hue.
    let l_off_2 = (l_mean - 50.0).powi(2);
    let s_l = 1.0 + 0.015 * l_off_2 / (20.0 + l_off_2).sqrt();
    let s_c = 1.0 + 0.045 * c_mean;
    let s_h = 1.0 + 0.015 * c_mean * t;

    // Eq. 21: the rotation term R_T, which tilts the tolerance ellipses in the blue region
    // where CIELAB's chroma and hue differences are not perceptually independent.
    let r_t = -(2.0 * delta_theta_deg).to_radians().sin() * r_c;

    // Eq. 22: the weighted, rotated distance. The radicand is a positive-definite quadratic
    // form (|R_T| ≤ 2 sin 60° < 2), so it is never negative and `sqrt` needs no guard.
    let dl = delta_l / (w.k_l * s_l);
    let dc = delta_c / (w.k_c * s_c);
    let dh = delta_h / (w.k_h * s_h);
    (dl * dl + dc * dc + dh * dh + r_t * dc * dh).sqrt()
}

/// Eq. 7: the hue angle h′ = atan2(b*, a′) in degrees, mapped to [0°, 360°), and 0 when
/// a′ = b* = 0.
///
/// The explicit zero case matters: although atan2(0, 0) is 0, atan2(−0, −0) is −180°, which
/// would map to 180° and make the hue of a neutral colour depend on the sign of zero.
fn hue_deg(a_prime: f64, b: f64) -> f64 {
    if a_prime == 0.0 && b == 0.0 {
        return 0.0;
    }
    let h = b.atan2(a_prime).to_degrees();
    if h >= 0.0 {
        h
    } else {
        // A tiny negative angle would round to exactly 360°, outside the range; it is
        // (numerically) 0°.
        let wrapped = h + 360.0;
        if wrapped < 360.0 { wrapped } else { 0.0 }
    }
}

/// Cosine of an angle in degrees (eq. 15 is written in degrees).
fn cos_deg(deg: f64) -> f64 {
    deg.to_radians().cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 34 colour pairs of Sharma, Wu & Dalal, Color Res. Appl. 30(1) (2005), Table 1:
    /// (L*₁, a*₁, b*₁), (L*₂, a*₂, b*₂) and ΔE00 to four decimals, as published with the
    /// paper (the supplementary data file `ciede2000testdata.txt` on the first author's
    /// website). Transcribed data only; the values were cross-checked for agreement across
    /// three independent public copies of the table.
    #[rustfmt::skip]
    const SHARMA_TABLE_1: [([f64; 3], [f64; 3], f64); 34] = [
        ([50.0000,   2.6772, -79.7751], [50.0000,   0.0000, -82.7485],  2.0425),
        ([50.0000,   3.1571, -77.2803], [50.0000,   0.0000, -82.7485],  2.8615),
        ([50.0000,   2.8361, -74.0200], [50.0000,   0.0000, -82.7485],  3.4412),
        ([50.0000,  -1.3802, -84.2814], [50.0000,   0.0000, -82.7485],  1.0000),
        ([50.0000,  -1.1848, -84.8006], [50.0000,   0.0000, -82.7485],  1.0000),
        ([50.0000,  -0.9009, -85.5211], [50.0000,   0.0000, -82.7485],  1.0000),
        ([50.0000,   0.0000,   0.0000], [50.0000,  -1.0000,   2.0000],  2.3669),
        ([50.0000,  -1.0000,   2.0000], [50.0000,   0.0000,   0.0000],  2.3669),
        ([50.0000,   2.4900,  -0.0010], [50.0000,  -2.4900,   0.0009],  7.1792),
        ([50.0000,   2.4900,  -0.0010], [50.0000,  -2.4900,   0.0010],  7.1792),
        ([50.0000,   2.4900,  -0.0010], [50.0000,  -2.4900,   0.0011],  7.2195),
        ([50.0000,   2.4900,  -0.0010], [50.0000,  -2.4900,   0.0012],  7.2195),
        ([50.0000,  -0.0010,   2.4900], [50.0000,   0.0009,  -2.4900],  4.8045),
        ([50.0000,  -0.0010,   2.4900], [50.0000,   0.0010,  -2.4900],  4.8045),
        ([50.0000,  -0.0010,   2.4900], [50.0000,   0.0011,  -2.4900],  4.7461),
        ([50.0000,   2.5000,   0.0000], [50.0000,   0.0000,  -2.5000],  4.3065),
        ([50.0000,   2.5000,   0.0000], [73.0000,  25.0000, -18.0000], 27.1492),
        ([50.0000,   2.5000,   0.0000], [61.0000,  -5.0000,  29.0000], 22.8977),
        ([50.0000,   2.5000,   0.0000], [56.0000, -27.0000,  -3.0000], 31.9030),
        ([50.0000,   2.5000,   0.0000], [58.0000,  24.0000,  15.0000], 19.4535),
        ([50.0000,   2.5000,   0.0000], [50.0000,   3.1736,   0.5854],  1.0000),
        ([50.0000,   2.5000,   0.0000], [50.0000,   3.2972,   0.0000],  1.0000),
        ([50.0000,   2.5000,   0.0000], [50.0000,   1.8634,   0.5757],  1.0000),
        ([50.0000,   2.5000,   0.0000], [50.0000,   3.2592,   0.3350],  1.0000),
        ([60.2574, -34.0099,  36.2677], [60.4626, -34.1751,  39.4387],  1.2644),
        ([63.0109, -31.0961,  -5.8663], [62.8187, -29.7946,  -4.0864],  1.2630),
        ([61.2901,   3.7196,  -5.3901], [61.4292,   2.2480,  -4.9620],  1.8731),
        ([35.0831, -44.1164,   3.7933], [35.0232, -40.0716,   1.5901],  1.8645),
        ([22.7233,  20.0904, -46.6940], [23.0331,  14.9730, -42.5619],  2.0373),
        ([36.4612,  47.8580,  18.3852], [36.2715,  50.5065,  21.2231],  1.4146),
        ([90.8027,  -2.0831,   1.4410], [91.1528,  -1.6435,   0.0447],  1.4441),
        ([90.9257,  -0.5406,  -0.9208], [88.6381,  -0.8985,  -0.7239],  1.5381),
        ([ 6.7747,  -0.2908,  -2.4247], [ 5.8714,  -0.0985,  -2.2286],  0.6377),
        ([ 2.0776,   0.0795,  -1.1350], [ 0.9033,  -0.0636,  -0.5514],  0.9082),
    ];

    fn lab([l, a, b]: [f64; 3]) -> Lab {
        Lab::new(l, a, b)
    }

    #[test]
    fn matches_sharma_table_1() {
        for (i, &(c1, c2, expected)) in SHARMA_TABLE_1.iter().enumerate() {
            let got = ciede2000(lab(c1), lab(c2));
            // The table is rounded to four decimals, so the true value lies within 5e-5.
            assert!(
                (got - expected).abs() <= 1e-4,
                "pair {}: {c1:?} vs {c2:?}: got {got}, table {expected}",
                i + 1
            );
        }
    }

    #[test]
    fn symmetric_on_sharma_pairs() {
        for (i, &(c1, c2, _)) in SHARMA_TABLE_1.iter().enumerate() {
            let forward = ciede2000(lab(c1), lab(c2));
            let backward = ciede2000(lab(c2), lab(c1));
            assert!((forward - backward).abs() <= 1e-12, "pair {}: {forward} vs {backward}", i + 1);
        }
    }

    #[test]
    fn identical_colours_have_zero_difference() {
        let colours = SHARMA_TABLE_1.iter().flat_map(|&(c1, c2, _)| [lab(c1), lab(c2)]).chain([
            Lab::new(0.0, 0.0, 0.0),
            Lab::new(100.0, 0.0, 0.0),
            Lab::new(50.0, -0.0, -0.0),
            Lab::new(40.0, -120.0, 90.0),
        ]);
        for c in colours {
            assert_eq!(ciede2000(c, c), 0.0, "{c:?}");
        }
    }

    #[test]
    fn weights_divide_their_terms() {
        // Default weights are the reference conditions.
        let (c1, c2, _) = SHARMA_TABLE_1[24];
        assert_eq!(
            ciede2000_weighted(lab(c1), lab(c2), Weights::default()),
            ciede2000(lab(c1), lab(c2))
        );
        // For a pure lightness difference only the first term of eq. 22 is non-zero, so
        // doubling k_L halves ΔE00.
        let (grey1, grey2) = (Lab::new(40.0, 0.0, 0.0), Lab::new(45.0, 0.0, 0.0));
        let k_l_2 = Weights { k_l: 2.0, ..Weights::default() };
        let ratio = ciede2000_weighted(grey1, grey2, k_l_2) / ciede2000(grey1, grey2);
        assert!((ratio - 0.5).abs() <= 1e-15, "ratio {ratio}");
    }
}
