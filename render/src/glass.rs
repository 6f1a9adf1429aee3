//! Thin clear glazing: a plane-parallel pane of index n and internal transmittance τ per pass.
//! Light meets two faces; at each the Fresnel reflectance r(θ) for the s and p polarisations,
//! and between them absorption over the path through the glass, τ(θ) = τ₀^(1/cos θ_t) (Beer–
//! Lambert). Summing the inter-reflections between the faces (a geometric series), for each
//! polarisation:
//!
//! ```text
//!   R = r + (1 − r)² r τ² / (1 − r² τ²),     T = (1 − r)² τ / (1 − r² τ²),
//! ```
//!
//! averaged over s and p for unpolarised light (e.g. Rubin, "Optical properties of soda lime
//! silica glasses", Solar Energy Materials 12, 1985; the method of ISO 9050 and EN 410). The
//! pane is thin: a ray goes straight through it, displaced by nothing, and the same numbers hold
//! from either side. τ₀ follows from the normal transmittance T(0) given for the pane.

/// 6 mm of clear float glass transmits 0.88 at normal incidence (n = 1.52).
pub const DEFAULT_THICKNESS_MM: f64 = 6.0;
pub const DEFAULT_TRANSMITTANCE: f64 = 0.88;
pub const DEFAULT_IOR: f64 = 1.52;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    pub ior: f32,
    /// −ln τ₀: the optical depth through the pane at normal incidence.
    pub depth: f32,
}

/// The Fresnel reflectances (s, p) of one face for a cosine of incidence `cos_i` in air.
fn fresnel(n: f64, cos_i: f64) -> (f64, f64, f64) {
    let sin_t = (1.0 - cos_i * cos_i).max(0.0).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let rs = ((cos_i - n * cos_t) / (cos_i + n * cos_t)).powi(2);
    let rp = ((n * cos_i - cos_t) / (n * cos_i + cos_t)).powi(2);
    (rs, rp, cos_t)
}

/// The internal transmittance τ₀ a pane of normal transmittance `t_normal` has: the positive
/// root of r² T τ² + (1 − r)² τ − T = 0 (the slab formula at normal incidence, r = ((n−1)/(n+1))²).
fn tau_of(n: f64, t_normal: f64) -> f64 {
    let r = ((n - 1.0) / (n + 1.0)).powi(2);
    if t_normal <= 0.0 {
        return 0.0;
    }
    let (a, b) = (r * r * t_normal, (1.0 - r) * (1.0 - r));
    ((b * b + 4.0 * a * t_normal).sqrt() - b) / (2.0 * a)
}

/// The most a pane of index `n` can transmit at normal incidence (no absorption): (1 − r)/(1 + r).
pub fn max_transmittance(n: f64) -> f64 {
    let r = ((n - 1.0) / (n + 1.0)).powi(2);
    (1.0 - r) / (1.0 + r)
}

impl Glass {
    /// A pane of index `ior`, `thickness_mm` thick, of normal transmittance `transmittance`; or,
    /// without it, of the default glass's absorption over its thickness.
    pub fn new(ior: f64, thickness_mm: f64, transmittance: Option<f64>) -> Self {
        let depth = match transmittance {
            Some(t) => -tau_of(ior, t).max(1e-30).ln(),
            None => {
                let per_mm =
                    -tau_of(DEFAULT_IOR, DEFAULT_TRANSMITTANCE).ln() / DEFAULT_THICKNESS_MM;
                per_mm * thickness_mm
            }
        };
        Self { ior: ior as f32, depth: depth as f32 }
    }

    /// The pane's reflectance and transmittance (R, T) for light meeting it at `cos_i` (either
    /// side).
    pub fn reflect_transmit(&self, cos_i: f32) -> (f32, f32) {
        let (n, cos_i) = (f64::from(self.ior), f64::from(cos_i.abs()).min(1.0));
        let (rs, rp, cos_t) = fresnel(n, cos_i);
        let tau = (-f64::from(self.depth) / cos_t.max(1e-9)).exp();
        let (mut r, mut t) = (0.0, 0.0);
        for f in [rs, rp] {
            let denominator = 1.0 - f * f * tau * tau;
            r += 0.5 * (f + (1.0 - f) * (1.0 - f) * f * tau * tau / denominator);
            t += 0.5 * (1.0 - f) * (1.0 - f) * tau / denominator;
        }
        (r as f32, t as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default pane transmits 0.88 at normal incidence, and at any angle R + T + A = 1
    /// with A ≥ 0; without absorption R + T = 1 exactly; at grazing incidence all is reflected.
    #[test]
    fn the_slab_conserves_energy_and_meets_its_normal_transmittance() {
        let g = Glass::new(DEFAULT_IOR, DEFAULT_THICKNESS_MM, None);
        let (r, t) = g.reflect_transmit(1.0);
        assert!((t - 0.88).abs() < 1e-6, "{t}");
        assert!(r > 0.07 && r < 0.09, "{r}");
        let clear = Glass::new(1.52, 6.0, Some(max_transmittance(1.52)));
        for cos in [1.0, 0.8, 0.5, 0.2, 0.05] {
            let (r, t) = g.reflect_transmit(cos);
            assert!(r + t <= 1.0 && r >= 0.0 && t >= 0.0);
            let (r, t) = clear.reflect_transmit(cos);
            assert!((r + t - 1.0).abs() < 1e-5, "{cos}: {r} + {t}");
        }
        let (r, t) = g.reflect_transmit(1e-6);
        assert!(r > 0.99 && t < 0.01);
        // Twice the thickness of the default glass absorbs twice the optical depth.
        let double = Glass::new(DEFAULT_IOR, 12.0, None);
        assert!((double.depth - 2.0 * g.depth).abs() < 1e-6);
    }
}
