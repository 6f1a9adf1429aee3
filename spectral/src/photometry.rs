//! Photometry of the paper (Rossi, Marini & Rizzi 2004, §2.2): light sources are specified the
//! way the lighting industry measures them — luminous intensity in candela, illuminance in lux —
//! together with a relative spectral power distribution, and converted here to the absolute
//! spectral quantities the tracer carries.
//!
//! * Eq. 2: the relative spectral power S_e(λ) = 100 · P(λ) / P(555 nm).
//! * Eq. 8: a luminaire of luminous intensity I_v (cd) at distance r, incidence α, gives the
//!   spectral irradiance E_e(λ) = I_v · S_e(λ) · cos α / (r² · Σ K(λ) S_e(λ) Δλ), with
//!   K(λ) = K_m · V(λ).
//! * The sun (and any distant source) of illuminance E_v (lux) on a surface normal to it gives
//!   E_e(λ) = E_v · S_e(λ) · cos θ / Σ K(λ) S_e(λ) Δλ.
//!
//! Both follow from one identity: Σ K(λ) E_e(λ) Δλ must equal the photometric quantity, so the
//! spectral shape is scaled by the photometric value over the shape's own luminous integral.

use crate::cie::photopic_v;
use crate::colorimetry::K_M_LM_PER_W;
use crate::error::{Error, Result, SpectrumProblem};
use crate::grid::{STEP_NM, band_of};
use crate::spectrum::Spectrum;

/// Σ K(λ) S(λ) Δλ with K(λ) = K_m V(λ): the luminous integral of a spectral power
/// distribution. For a radiant quantity in W/nm units it is the photometric quantity (lm, cd,
/// lux or cd/m²).
pub fn luminous_integral(spd: &Spectrum) -> f64 {
    K_M_LM_PER_W * spd.dot(photopic_v()) * STEP_NM
}

/// Eq. 2: a spectral power distribution scaled to 100 at 555 nm.
pub fn relative_to_555(spd: &Spectrum, source: &str) -> Result<Spectrum> {
    let p555 = spd[band_of(555.0).expect("555 nm is on the grid")];
    if !(p555 > 0.0 && p555.is_finite()) {
        return Err(Error::Spectrum {
            file: source.to_owned(),
            line: None,
            problem: SpectrumProblem::Degenerate {
                what: format!(
                    "the spectral power at 555 nm is {p555}, so it cannot be normalised to 100 at \
                     555 nm (paper Eq. 2); a light source must emit at 555 nm"
                ),
            },
        });
    }
    Ok(*spd * (100.0 / p555))
}

/// The largest relative spectral power S_e(λ) (100 at 555 nm) a light may have: 10⁹, a band
/// 10⁷ times as strong as 555 nm (a 500 K blackbody reaches 5 × 10⁵; low-pressure sodium
/// about 10³). The radiance is S_e(λ) × photometric value ÷ Σ K S_e Δλ ≥ 3.4 × 10⁵, so
/// with the lights' own bounds (10⁹ cd, 10⁶ lx) it stays far inside 32-bit floats.
pub const MAX_RELATIVE_POWER: f64 = 1e9;

/// A light source's spectral shape, ready for photometric scaling: the relative spectral power
/// S_e(λ) (Eq. 2) and its luminous integral. Built once per light; the per-ray work is one
/// multiply of [`LuminousSpectrum::per_lumen`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LuminousSpectrum {
    /// S_e(λ), 100 at 555 nm.
    pub relative: Spectrum,
    /// S_e(λ) / Σ K(λ) S_e(λ) Δλ: the spectral radiant quantity per unit of the photometric one
    /// (W·nm⁻¹ per lm, or W·m⁻²·nm⁻¹ per lux, or W·sr⁻¹·nm⁻¹ per cd).
    pub per_lumen: Spectrum,
}

impl LuminousSpectrum {
    /// `spd` is any spectral power distribution of the source; `source` names it in messages.
    pub fn new(spd: &Spectrum, source: &str) -> Result<Self> {
        if !spd.is_finite() || spd.min_value() < 0.0 {
            return Err(Error::Spectrum {
                file: source.to_owned(),
                line: None,
                problem: SpectrumProblem::Degenerate {
                    what: "a spectral power distribution must be finite and not negative".into(),
                },
            });
        }
        let relative = relative_to_555(spd, source)?;
        // Eq. 2 divides by the power at 555 nm: a source that emits almost nothing there would
        // have an enormous relative spectrum, and its radiance would overflow 32-bit floats.
        let (peak_band, peak) = relative
            .0
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0.0f32), |a, (i, v)| if v > a.1 { (i, v) } else { a });
        if !(relative.is_finite() && f64::from(peak) <= MAX_RELATIVE_POWER) {
            return Err(Error::Spectrum {
                file: source.to_owned(),
                line: None,
                problem: SpectrumProblem::Degenerate {
                    what: format!(
                        "the spectral power at {} nm is {:e} times that at 555 nm; restauro \
                         accepts at most {:e} times (beyond, the radiance overflows 32-bit \
                         floats), so a light must emit noticeably at 555 nm",
                        crate::grid::wavelength_nm(peak_band),
                        f64::from(peak) / 100.0,
                        MAX_RELATIVE_POWER / 100.0
                    ),
                },
            });
        }
        let integral = luminous_integral(&relative);
        Ok(Self { relative, per_lumen: relative * (1.0 / integral) as f32 })
    }
}

fn check(quantity: &'static str, value: f64, ok: bool, expected: &'static str) -> Result<()> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(Error::OutOfRange { quantity, value, expected })
    }
}

/// Eq. 8: the spectral irradiance (W·m⁻²·nm⁻¹) at distance `distance_m` from a luminaire of
/// luminous intensity `intensity_cd` towards the point, on a surface whose normal makes the
/// angle α with the direction to the source (`cos_incidence` = cos α; back-facing gives zero).
pub fn luminaire_spectral_irradiance(
    intensity_cd: f64,
    spectrum: &LuminousSpectrum,
    distance_m: f64,
    cos_incidence: f64,
) -> Result<Spectrum> {
    check(
        "luminous intensity (cd)",
        intensity_cd,
        intensity_cd >= 0.0,
        "a finite intensity ≥ 0 cd",
    )?;
    check("distance (m)", distance_m, distance_m > 0.0, "a finite distance > 0 m")?;
    check("cos α", cos_incidence, (-1.0..=1.0).contains(&cos_incidence), "a cosine in −1..1")?;
    let scale = intensity_cd * cos_incidence.max(0.0) / (distance_m * distance_m);
    Ok(spectrum.per_lumen * scale as f32)
}

/// The spectral irradiance (W·m⁻²·nm⁻¹) of a distant source, such as the sun, whose illuminance
/// on a surface normal to it is `illuminance_lux`, on a surface at `cos_incidence` to it.
pub fn distant_spectral_irradiance(
    illuminance_lux: f64,
    spectrum: &LuminousSpectrum,
    cos_incidence: f64,
) -> Result<Spectrum> {
    check(
        "illuminance (lx)",
        illuminance_lux,
        illuminance_lux >= 0.0,
        "a finite illuminance ≥ 0 lx",
    )?;
    check("cos θ", cos_incidence, (-1.0..=1.0).contains(&cos_incidence), "a cosine in −1..1")?;
    Ok(spectrum.per_lumen * (illuminance_lux * cos_incidence.max(0.0)) as f32)
}

/// The illuminance presets of the paper (§3): the sun 50° above the horizon, a cloudy day, the
/// full moon, in lux on a surface normal to the light.
pub mod presets {
    pub const SUN_50_DEG_LUX: f64 = 100_000.0;
    pub const CLOUDY_DAY_LUX: f64 = 10_000.0;
    pub const FULL_MOON_LUX: f64 = 0.2;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::illuminant::Illuminant;

    fn only_at(bands: &[(f64, f32)]) -> Spectrum {
        let mut s = Spectrum::ZERO;
        for &(nm, v) in bands {
            s[band_of(nm).unwrap()] = v;
        }
        s
    }

    #[test]
    fn eq2_normalises_to_100_at_555() {
        let d65 = Illuminant::D65.spd().unwrap();
        let rel = relative_to_555(&d65, "D65").unwrap();
        assert!((rel[band_of(555.0).unwrap()] - 100.0).abs() < 1e-4);
        assert!(relative_to_555(&only_at(&[(450.0, 1.0)]), "blue").is_err());
    }

    /// A source with next to nothing at 555 nm: Eq. 2's division makes its relative spectrum
    /// overflow (1e20 × 100 / 1e-20 = 1e42 > f32's 3.4e38), or nearly; refused with the bound.
    #[test]
    fn a_light_that_barely_emits_at_555_is_refused() {
        for (blue, green) in [(1e20, 1e-20), (1.0, 1e-9)] {
            let err = LuminousSpectrum::new(&only_at(&[(450.0, blue), (555.0, green)]), "lamp.csv")
                .unwrap_err()
                .to_string();
            assert!(err.starts_with("lamp.csv: the spectral power at 450 nm is"), "{err}");
            assert!(err.contains("at most 1e7 times"), "{err}");
        }
        // A thousand times the 555 nm power, like low-pressure sodium's 589 nm line, is fine.
        let s =
            LuminousSpectrum::new(&only_at(&[(590.0, 1000.0), (555.0, 1.0)]), "sodium").unwrap();
        assert!(s.per_lumen.is_finite());
    }

    /// Hand-computed: all power in the 555 nm band (V = 1). Σ K S Δλ = 683 · 100 · 5 = 341 500.
    /// I_v = 1000 cd at r = 2 m, α = 60°: E_e(555) = 1000 · 100 · 0.5 / (4 · 341 500)
    /// = 0.036 603 221 W·m⁻²·nm⁻¹, and the illuminance is 683 · 0.036603 · 5 = 125 lx
    /// = I cos α / r².
    #[test]
    fn eq8_single_band_by_hand() {
        let s = LuminousSpectrum::new(&only_at(&[(555.0, 3.0)]), "green").unwrap();
        let e = luminaire_spectral_irradiance(1000.0, &s, 2.0, 0.5).unwrap();
        let e555 = f64::from(e[band_of(555.0).unwrap()]);
        assert!((e555 - 0.036_603_221).abs() < 1e-8, "{e555}");
        assert_eq!(e.integral() - e555 * 5.0, 0.0);
        assert!((luminous_integral(&e) - 125.0).abs() < 1e-4);
    }

    /// Hand-computed: two bands, 100 at 555 nm (V = 1) and 50 at 600 nm (V = 0.631).
    /// Σ K S Δλ = 683 · 5 · (100 + 50 · 0.631) = 3415 · 131.55 = 449 243.25.
    /// I_v = 200 cd, r = 4 m, α = 0: E_e(555) = 200 · 100 / (16 · 449 243.25) = 0.002 782 5,
    /// E_e(600) = half of it.
    #[test]
    fn eq8_two_bands_by_hand() {
        let s = LuminousSpectrum::new(&only_at(&[(555.0, 100.0), (600.0, 50.0)]), "two").unwrap();
        let e = luminaire_spectral_irradiance(200.0, &s, 4.0, 1.0).unwrap();
        let denominator: f64 = 683.0 * 5.0 * (100.0 + 50.0 * 0.631);
        assert!((denominator - 449_243.25).abs() < 1e-6);
        assert!((f64::from(e[band_of(555.0).unwrap()]) - 0.002_782_5).abs() < 1e-7);
        let e555 = 200.0 * 100.0 / (16.0 * denominator);
        assert!((f64::from(e[band_of(555.0).unwrap()]) / e555 - 1.0).abs() < 1e-6);
        assert!((f64::from(e[band_of(600.0).unwrap()]) / (e555 / 2.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn photometric_quantities_are_preserved_for_any_spectrum() {
        for name in ["A", "D65", "F11", "E"] {
            let spd = name.parse::<Illuminant>().unwrap().spd().unwrap();
            let s = LuminousSpectrum::new(&spd, name).unwrap();
            // Inverse-square and cosine laws, E_v = I cos α / r².
            for (i, r, cos) in [(1000.0, 1.0, 1.0), (1000.0, 3.0, 1.0), (50.0, 0.5, 0.25)] {
                let e = luminaire_spectral_irradiance(i, &s, r, cos).unwrap();
                let expect = i * cos / (r * r);
                assert!((luminous_integral(&e) / expect - 1.0).abs() < 1e-5, "{name}");
            }
            let sun = distant_spectral_irradiance(presets::SUN_50_DEG_LUX, &s, 1.0).unwrap();
            assert!((luminous_integral(&sun) / presets::SUN_50_DEG_LUX - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn back_faces_receive_nothing_and_bad_numbers_are_refused() {
        let s = LuminousSpectrum::new(&Illuminant::D65.spd().unwrap(), "D65").unwrap();
        assert!(luminaire_spectral_irradiance(100.0, &s, 1.0, -0.5).unwrap().is_black());
        assert!(luminaire_spectral_irradiance(-1.0, &s, 1.0, 1.0).is_err());
        assert!(luminaire_spectral_irradiance(f64::NAN, &s, 1.0, 1.0).is_err());
        assert!(luminaire_spectral_irradiance(1.0, &s, 0.0, 1.0).is_err());
        assert!(distant_spectral_irradiance(f64::INFINITY, &s, 1.0).is_err());
        let mut bad = Illuminant::D65.spd().unwrap();
        bad[3] = -1.0;
        assert!(LuminousSpectrum::new(&bad, "bad").is_err());
    }
}
