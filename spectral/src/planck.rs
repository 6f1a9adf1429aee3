//! Planck's law for the spectral radiance of a black body (CIE 15:2004 Eq. 3.1), and CIE
//! illuminant A, which is defined by it.

use crate::error::{Error, Result};
use crate::spectrum::Spectrum;

/// The first radiation constant for spectral radiance, c₁L = 2hc² in W·m²·sr⁻¹ (CODATA 2018,
/// exact since the 2019 SI).
pub const C1L_W_M2_PER_SR: f64 = 1.191_042_972_397_188e-16;
/// The second radiation constant c₂ = hc/k in m·K (CODATA 2018, exact).
pub const C2_M_K: f64 = 1.438_776_877e-2;

/// Planck's law: the spectral radiance of a black body at `temperature_k`, in W·sr⁻¹·m⁻²·nm⁻¹,
/// with the second radiation constant `c2_m_k` (the modern value is [`C2_M_K`]; older CIE
/// definitions fix other values).
pub fn spectral_radiance_with_c2(wavelength_nm: f64, temperature_k: f64, c2_m_k: f64) -> f64 {
    let lambda_m = wavelength_nm * 1e-9;
    // L = c1L λ⁻⁵ / (exp(c2 / λT) − 1), per metre of wavelength; × 1e-9 per nanometre.
    C1L_W_M2_PER_SR / lambda_m.powi(5) / (c2_m_k / (lambda_m * temperature_k)).exp_m1() * 1e-9
}

/// Planck's law with the CODATA constants, in W·sr⁻¹·m⁻²·nm⁻¹.
pub fn spectral_radiance(wavelength_nm: f64, temperature_k: f64) -> f64 {
    spectral_radiance_with_c2(wavelength_nm, temperature_k, C2_M_K)
}

/// The relative spectral power of a black body at `temperature_k` on the grid, normalised to 100
/// at 560 nm as the CIE tabulates illuminants.
pub fn blackbody_spd(temperature_k: f64) -> Result<Spectrum> {
    if !(temperature_k.is_finite() && (100.0..=1.0e6).contains(&temperature_k)) {
        return Err(Error::OutOfRange {
            quantity: "black-body temperature (K)",
            value: temperature_k,
            expected: "a temperature between 100 K and 1 000 000 K",
        });
    }
    let reference = spectral_radiance(560.0, temperature_k);
    Ok(Spectrum::from_fn_nm(|l| 100.0 * spectral_radiance(l, temperature_k) / reference))
}

/// CIE illuminant A by its defining formula (CIE 15:2004 Eq. 3.1): a Planckian radiator with
/// c₂ = 1.435 × 10⁻² m·K at 2848 K, normalised to 100 at 560 nm. (With today's c₂ the same
/// curve is a black body at about 2856 K, the temperature usually quoted.)
pub fn illuminant_a_formula(wavelength_nm: f64) -> f64 {
    const C2_CIE_A: f64 = 1.435e-2;
    const T_A: f64 = 2848.0;
    100.0 * spectral_radiance_with_c2(wavelength_nm, T_A, C2_CIE_A)
        / spectral_radiance_with_c2(560.0, T_A, C2_CIE_A)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cie::TABLES;
    use crate::grid::{BANDS, wavelength_nm};

    #[test]
    fn illuminant_a_table_matches_its_formula() {
        for i in 0..BANDS {
            let formula = illuminant_a_formula(wavelength_nm(i));
            let table = f64::from(TABLES.a[i]);
            assert!(
                (table / formula - 1.0).abs() < 1e-5,
                "{}: {table} vs {formula}",
                wavelength_nm(i)
            );
        }
    }

    #[test]
    fn illuminant_a_is_a_black_body_at_2856_k() {
        let planck = blackbody_spd(2856.0).unwrap();
        for i in 0..BANDS {
            let table = f64::from(TABLES.a[i]);
            let rel = (f64::from(planck[i]) / table - 1.0).abs();
            // c₂/T differs from the CIE definition by 1.6e-4 relative, which moves the curve by
            // up to 7e-4 relative at the ends of the grid.
            assert!(rel < 1e-3, "{}: {rel}", wavelength_nm(i));
        }
    }

    #[test]
    fn wien_displacement_and_stefan_boltzmann() {
        // Peak of λ⁵-weighted Planck at λ_max = b / T, b = 2.897771955e-3 m·K (CODATA).
        let t = 5000.0;
        let peak = (4000..7000)
            .map(|k| f64::from(k) * 0.1)
            .max_by(|a, b| spectral_radiance(*a, t).total_cmp(&spectral_radiance(*b, t)))
            .unwrap();
        assert!((peak - 2.897_771_955e-3 / t * 1e9).abs() < 0.1, "{peak}");
        // ∫ L dλ over all wavelengths = σT⁴/π (σ = 5.670374419e-8 W·m⁻²·K⁻⁴), by a fine sum.
        let total: f64 =
            (1..2_000_000).map(|k| spectral_radiance(f64::from(k) * 0.05, t) * 0.05).sum();
        let expect = 5.670_374_419e-8 * t.powi(4) / std::f64::consts::PI;
        assert!((total / expect - 1.0).abs() < 1e-4, "{total} vs {expect}");
    }

    #[test]
    fn refuses_absurd_temperatures() {
        assert!(blackbody_spd(f64::NAN).is_err());
        assert!(blackbody_spd(-5.0).is_err());
        assert!(blackbody_spd(3000.0).is_ok());
    }
}
