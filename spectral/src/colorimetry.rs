//! Tristimulus values from spectra (CIE 15:2004 §7), in the two forms restauro needs:
//!
//! * absolute, for radiance: X = K_m Σ L_e(λ) x̄(λ) Δλ with K_m = 683 lm/W, so that Y is the
//!   luminance in cd/m² when L_e is spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ (paper §2.2);
//! * relative, for a reflecting object under an illuminant: X = k Σ S(λ) ρ(λ) x̄(λ) Δλ with
//!   k = 100 / Σ S(λ) ȳ(λ) Δλ, so that the perfect reflecting diffuser has Y = 100
//!   (CIE 15:2004 Eqs. 7.1–7.4).

use crate::cie::TABLES;
use crate::grid::STEP_NM;
use crate::spectrum::Spectrum;
use serde::Serialize;
use std::fmt;

/// K_m, the maximum luminous efficacy of photopic vision: a CIE constant, kept with the tables.
pub use crate::cie::K_M_LM_PER_W;

/// The CIE standard colorimetric observers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize)]
pub enum Observer {
    /// The CIE 1931 2° standard observer, for fields of view up to about 4°.
    #[default]
    #[serde(rename = "CIE 1931 2°")]
    Cie1931TwoDegree,
    /// The CIE 1964 10° supplementary standard observer, for larger fields.
    #[serde(rename = "CIE 1964 10°")]
    Cie1964TenDegree,
}

impl Observer {
    /// The colour-matching functions x̄, ȳ, z̄ on the grid.
    pub fn cmf(self) -> &'static [Spectrum; 3] {
        match self {
            Observer::Cie1931TwoDegree => &TABLES.cmf_1931,
            Observer::Cie1964TenDegree => &TABLES.cmf_1964,
        }
    }

    /// The field size in degrees: 2 or 10.
    pub fn degrees(self) -> u32 {
        match self {
            Observer::Cie1931TwoDegree => 2,
            Observer::Cie1964TenDegree => 10,
        }
    }
}

impl fmt::Display for Observer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Observer::Cie1931TwoDegree => f.write_str("CIE 1931 2°"),
            Observer::Cie1964TenDegree => f.write_str("CIE 1964 10°"),
        }
    }
}

/// CIE XYZ tristimulus values. Their scale is the caller's: absolute (Y in cd/m²) or relative
/// (Y = 100 for the perfect white).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Xyz {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// CIE 1931 (x, y) chromaticity coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Chromaticity {
    pub x: f64,
    pub y: f64,
}

impl Chromaticity {
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }

    /// The XYZ with this chromaticity and luminance factor `y_value` (CIE 15:2004 Eq. 7.9).
    pub fn to_xyz(self, y_value: f64) -> Xyz {
        Xyz::new(self.x * y_value / self.y, y_value, (1.0 - self.x - self.y) * y_value / self.y)
    }
}

impl Xyz {
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    /// x = X / (X + Y + Z), y = Y / (X + Y + Z) (CIE 15:2004 Eq. 7.8). Black has no chromaticity.
    pub fn chromaticity(self) -> Option<Chromaticity> {
        let sum = self.x + self.y + self.z;
        (sum > 0.0).then(|| Chromaticity::new(self.x / sum, self.y / sum))
    }

    /// Every component multiplied by `k`.
    pub fn scale(self, k: f64) -> Xyz {
        Xyz::new(self.x * k, self.y * k, self.z * k)
    }

    pub fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }

    pub fn from_array(v: [f64; 3]) -> Self {
        Xyz::new(v[0], v[1], v[2])
    }
}

/// Σ w(λ) x̄(λ) Δλ and so on: the un-normalised tristimulus integral of a stimulus w.
fn integrate(stimulus: &Spectrum, observer: Observer) -> Xyz {
    let [xb, yb, zb] = observer.cmf();
    Xyz::new(stimulus.dot(xb) * STEP_NM, stimulus.dot(yb) * STEP_NM, stimulus.dot(zb) * STEP_NM)
}

/// Absolute tristimulus values of a spectral radiance L_e(λ) in W·sr⁻¹·m⁻²·nm⁻¹: Y is the
/// luminance in cd/m² (with the 2° observer; the 10° Y is its large-field analogue).
pub fn absolute_xyz(radiance: &Spectrum, observer: Observer) -> Xyz {
    integrate(radiance, observer).scale(K_M_LM_PER_W)
}

/// Relative tristimulus values of a reflectance ρ(λ) under an illuminant of relative spectral
/// power S(λ): the perfect reflecting diffuser has Y = 100 (CIE 15:2004 Eqs. 7.1–7.3).
pub fn relative_xyz(reflectance: &Spectrum, illuminant: &Spectrum, observer: Observer) -> Xyz {
    let [_, yb, _] = observer.cmf();
    let k = 100.0 / (illuminant.dot(yb) * STEP_NM);
    integrate(&(*reflectance * *illuminant), observer).scale(k)
}

/// The white point of an illuminant: the relative XYZ of the perfect reflecting diffuser.
pub fn white_point(illuminant: &Spectrum, observer: Observer) -> Xyz {
    relative_xyz(&Spectrum::ONE, illuminant, observer)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::band_of;

    #[test]
    fn absolute_luminance_of_monochromatic_radiance() {
        // 1 W·sr⁻¹·m⁻²·nm⁻¹ in the 555 nm band only: L_v = 683 · 1 · V(555) · 5 nm = 3415 cd/m².
        let mut l = Spectrum::ZERO;
        l[band_of(555.0).unwrap()] = 1.0;
        let xyz = absolute_xyz(&l, Observer::Cie1931TwoDegree);
        assert!((xyz.y - 3415.0).abs() < 1e-9, "{}", xyz.y);
    }

    #[test]
    fn chromaticity_round_trip() {
        let xyz = Xyz::new(41.24, 21.26, 1.93);
        let c = xyz.chromaticity().unwrap();
        let back = c.to_xyz(xyz.y);
        assert!((back.x - xyz.x).abs() < 1e-12 && (back.z - xyz.z).abs() < 1e-12);
        assert_eq!(Xyz::new(0.0, 0.0, 0.0).chromaticity(), None);
    }
}
