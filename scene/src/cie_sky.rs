//! The CIE standard general sky (CIE S 011/E:2003 = ISO 15469:2004): fifteen relative luminance
//! distributions from a heavily overcast to a cloudless sky,
//!
//! ```text
//!   L(Z, χ) / L_z = f(χ) φ(Z) / (f(Z_s) φ(0)),
//!   gradation  φ(Z) = 1 + a exp(b / cos Z),          φ(0) = 1 + a e^b,
//!   indicatrix f(χ) = 1 + c (e^{dχ} − e^{dπ/2}) + e cos²χ,
//! ```
//!
//! Z the zenith angle of the sky element, Z_s the sun's, χ the angle between the element and
//! the sun. A sky is normalised to a given diffuse horizontal illuminance D_v = ∫ L cos Z dω, so
//! L_z = D_v / (D_v/L_z), the ratio found here by quadrature. The sun's disc is not part of it:
//! a scene's sun is its own light.

/// The standard's parameters (a, b, c, d, e) of types 1 to 15 (ISO 15469:2004, Table 1).
pub const PARAMETERS: [[f64; 5]; 15] = [
    [4.0, -0.70, 0.0, -1.0, 0.0],
    [4.0, -0.70, 2.0, -1.5, 0.15],
    [1.1, -0.80, 0.0, -1.0, 0.0],
    [1.1, -0.80, 2.0, -1.5, 0.15],
    [0.0, -1.00, 0.0, -1.0, 0.0],
    [0.0, -1.00, 2.0, -1.5, 0.15],
    [0.0, -1.00, 5.0, -2.5, 0.30],
    [0.0, -1.00, 10.0, -3.0, 0.45],
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.30],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// A general sky of one type with the sun in one place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeneralSky {
    /// 1 to 15.
    pub sky_type: u8,
    /// The unit direction towards the sun (+Z up). Its elevation shapes the sky even where the
    /// sun itself is not a light of the scene.
    pub sun: [f64; 3],
    /// 1 / (f(Z_s) φ(0)): the zenith's luminance, constant for the sky, computed once.
    over_zenith: f64,
}

/// φ(Z) with cos Z given; at and below the horizon the limit, 1 (b < 0).
fn gradation(a: f64, b: f64, cos_z: f64) -> f64 {
    if cos_z <= 0.0 { 1.0 } else { 1.0 + a * (b / cos_z).exp() }
}

/// f(χ).
fn indicatrix(c: f64, d: f64, e: f64, chi: f64) -> f64 {
    let cos = chi.cos();
    1.0 + c * ((d * chi).exp() - (d * std::f64::consts::FRAC_PI_2).exp()) + e * cos * cos
}

impl GeneralSky {
    /// The sky of `sky_type` (1 to 15; others are taken as the nearest) with the sun towards the
    /// unit direction `sun`.
    pub fn new(sky_type: u8, sun: [f64; 3]) -> Self {
        let [a, b, c, d, e] = PARAMETERS[(sky_type.clamp(1, 15) - 1) as usize];
        let z_s = sun[2].clamp(-1.0, 1.0).acos();
        let over_zenith = 1.0 / (indicatrix(c, d, e, z_s) * gradation(a, b, 1.0));
        Self { sky_type, sun, over_zenith }
    }

    fn parameters(&self) -> [f64; 5] {
        PARAMETERS[(self.sky_type.clamp(1, 15) - 1) as usize]
    }

    /// L/L_z along the unit `direction` (+Z up); 0 below the horizon.
    pub fn relative_luminance(&self, direction: [f64; 3]) -> f64 {
        let cos_z = direction[2];
        if cos_z <= 0.0 {
            return 0.0;
        }
        let [a, b, c, d, e] = self.parameters();
        let dot: f64 = (0..3).map(|k| direction[k] * self.sun[k]).sum();
        let chi = dot.clamp(-1.0, 1.0).acos();
        indicatrix(c, d, e, chi) * gradation(a, b, cos_z) * self.over_zenith
    }

    /// D_v/L_z = ∫ (L/L_z) cos Z dω over the sky, by the midpoint rule in (cos Z, azimuth) —
    /// dω = d(cos Z) dα — on 512 × 1024 cells: within 1.2 × 10⁻⁵ of 2048 × 4096 cells for
    /// types 1, 7, 10, 12, 13 and 15 with the sun 10° to 85° high (the kink of f(χ) at the sun
    /// keeps the rule from its h² order).
    pub fn horizontal_over_zenith(&self) -> f64 {
        let (rows, columns) = (512usize, 1024usize);
        let (d_mu, d_alpha) = (1.0 / rows as f64, std::f64::consts::TAU / columns as f64);
        let mut sum = 0.0;
        for i in 0..rows {
            let mu = (i as f64 + 0.5) * d_mu;
            let s = (1.0 - mu * mu).sqrt();
            let mut row = 0.0;
            for j in 0..columns {
                let alpha = (j as f64 + 0.5) * d_alpha;
                row += self.relative_luminance([s * alpha.cos(), s * alpha.sin(), mu]);
            }
            sum += row * mu;
        }
        sum * d_mu * d_alpha
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sun::{SunPosition, direction_to_sun};

    fn sun_direction(elevation_deg: f64, azimuth_deg: f64) -> [f64; 3] {
        direction_to_sun(SunPosition { azimuth_deg, elevation_deg })
    }

    /// The uniform sky (type 5) is π whatever the sun; the zenith is 1.
    #[test]
    fn type_5_is_uniform_and_the_zenith_is_one() {
        for el in [20.0, 60.0] {
            let sky = GeneralSky::new(5, sun_direction(el, 135.0));
            assert!((sky.horizontal_over_zenith() - std::f64::consts::PI).abs() < 1e-5);
        }
        for t in 1..=15 {
            let sky = GeneralSky::new(t, sun_direction(40.0, 200.0));
            assert!((sky.relative_luminance([0.0, 0.0, 1.0]) - 1.0).abs() < 1e-12, "type {t}");
            assert_eq!(sky.relative_luminance([1.0, 0.0, -0.1]), 0.0);
        }
    }
}
