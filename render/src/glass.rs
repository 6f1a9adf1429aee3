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

use restauro_scene::glazing::face_reflectance;
pub use restauro_scene::glazing::{
    DEFAULT_IOR, DEFAULT_THICKNESS_MM, DEFAULT_TRANSMITTANCE, max_transmittance,
};
use restauro_spectral::Spectrum;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    pub ior: f32,
    /// −ln τ₀ in each band: the optical depth through the pane at normal incidence.
    pub depth: Spectrum,
    /// Whether the depth differs between bands: a tinted pane, whose reflectance and
    /// transmittance are spectra.
    pub tinted: bool,
}

/// A pane's reflectance and transmittance at one angle: numbers for clear glass, spectra for
/// tinted glass.
// On the stack, not boxed: the tracer allocates nothing per ray.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Optics {
    Neutral { r: f32, t: f32 },
    Tinted { r: Spectrum, t: Spectrum },
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
    let r = face_reflectance(n);
    if t_normal <= 0.0 {
        return 0.0;
    }
    let (a, b) = (r * r * t_normal, (1.0 - r) * (1.0 - r));
    ((b * b + 4.0 * a * t_normal).sqrt() - b) / (2.0 * a)
}

/// The slab's (R, T) for unpolarised light: the faces' reflectances (s, p) and the internal
/// transmittance τ along the path, by the series in the module's header.
fn slab((rs, rp): (f64, f64), tau: f64) -> (f64, f64) {
    let (mut r, mut t) = (0.0, 0.0);
    for f in [rs, rp] {
        let denominator = 1.0 - f * f * tau * tau;
        r += 0.5 * (f + (1.0 - f) * (1.0 - f) * f * tau * tau / denominator);
        t += 0.5 * (1.0 - f) * (1.0 - f) * tau / denominator;
    }
    (r, t)
}

impl Glass {
    /// A pane of index `ior`, `thickness_mm` thick, of normal transmittance `transmittance` in
    /// each band; or, without it, of the default glass's absorption over its thickness.
    pub fn new(ior: f64, thickness_mm: f64, transmittance: Option<&Spectrum>) -> Self {
        let depth = match transmittance {
            Some(t) => t.map(|t| -tau_of(ior, f64::from(t)).clamp(1e-30, 1.0).ln() as f32),
            None => {
                let per_mm =
                    -tau_of(DEFAULT_IOR, DEFAULT_TRANSMITTANCE).ln() / DEFAULT_THICKNESS_MM;
                Spectrum([(per_mm * thickness_mm) as f32; restauro_spectral::grid::BANDS])
            }
        };
        let tinted = depth.0.iter().any(|&d| d != depth.0[0]);
        Self { ior: ior as f32, depth, tinted }
    }

    /// The pane's reflectance and transmittance (R, T) for light meeting it at `cos_i` (either
    /// side), in the first band: all of them for clear glass.
    pub fn reflect_transmit(&self, cos_i: f32) -> (f32, f32) {
        let (rs, rp, cos_t) = fresnel(f64::from(self.ior), f64::from(cos_i.abs()).min(1.0));
        let tau = (-f64::from(self.depth.0[0]) / cos_t.max(1e-9)).exp();
        let (r, t) = slab((rs, rp), tau);
        (r as f32, t as f32)
    }

    /// The pane's reflectance and transmittance at `cos_i`, band by band when it is tinted.
    pub fn optics(&self, cos_i: f32) -> Optics {
        if !self.tinted {
            let (r, t) = self.reflect_transmit(cos_i);
            return Optics::Neutral { r, t };
        }
        let (rs, rp, cos_t) = fresnel(f64::from(self.ior), f64::from(cos_i.abs()).min(1.0));
        let (mut r, mut t) = (Spectrum::ZERO, Spectrum::ZERO);
        for (i, &depth) in self.depth.0.iter().enumerate() {
            let (ri, ti) = slab((rs, rp), (-f64::from(depth) / cos_t.max(1e-9)).exp());
            (r.0[i], t.0[i]) = (ri as f32, ti as f32);
        }
        Optics::Tinted { r, t }
    }
}

impl Optics {
    /// The transmittance alone.
    pub fn transmittance(&self) -> Transmission {
        match *self {
            Optics::Neutral { t, .. } => Transmission::Neutral(t),
            Optics::Tinted { t, .. } => Transmission::Tinted(t),
        }
    }
}

/// The share of light that passes along a shadow ray: the same in every band, or by band
/// behind tinted glass. [`Transmission::Neutral`]`(0)` is blocked.
// On the stack, not boxed: the tracer allocates nothing per ray.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transmission {
    Neutral(f32),
    Tinted(Spectrum),
}

impl Transmission {
    /// Nothing passes.
    pub fn is_blocked(&self) -> bool {
        match self {
            Transmission::Neutral(t) => *t <= 0.0,
            Transmission::Tinted(t) => t.max_value() <= 0.0,
        }
    }

    /// This share followed by `next` (panes in a row).
    pub fn then(self, next: Transmission) -> Transmission {
        match (self, next) {
            (Transmission::Neutral(a), Transmission::Neutral(b)) => Transmission::Neutral(a * b),
            (Transmission::Neutral(a), Transmission::Tinted(t))
            | (Transmission::Tinted(t), Transmission::Neutral(a)) => Transmission::Tinted(t * a),
            (Transmission::Tinted(a), Transmission::Tinted(b)) => Transmission::Tinted(a * b),
        }
    }

    /// The mean share over the bands: for weighing how much a light gives (not for its colour).
    pub fn mean(&self) -> f32 {
        match self {
            Transmission::Neutral(t) => *t,
            Transmission::Tinted(t) => t.mean(),
        }
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
        let clear = Glass::new(1.52, 6.0, Some(&Spectrum([max_transmittance(1.52) as f32; 81])));
        for cos in [1.0, 0.8, 0.5, 0.2, 0.05] {
            let (r, t) = g.reflect_transmit(cos);
            assert!(r + t <= 1.0 && r >= 0.0 && t >= 0.0);
            let (r, t) = clear.reflect_transmit(cos);
            assert!((r + t - 1.0).abs() < 2e-5, "{cos}: {r} + {t}");
        }
        let (r, t) = g.reflect_transmit(1e-6);
        assert!(r > 0.99 && t < 0.01);
        // Twice the thickness of the default glass absorbs twice the optical depth.
        let double = Glass::new(DEFAULT_IOR, 12.0, None);
        assert!((double.depth[0] - 2.0 * g.depth[0]).abs() < 1e-6);
    }

    /// A tinted pane meets its normal transmittance in every band, and a band where it equals a
    /// clear pane's value reflects and transmits exactly as that clear pane does at any angle.
    #[test]
    fn a_tinted_pane_is_a_clear_pane_in_each_band() {
        let tint = Spectrum::from_fn_nm(|nm| 0.3 + 0.5 * (-((nm - 520.0) / 60.0).powi(2)).exp());
        let tinted = Glass::new(1.52, 6.0, Some(&tint));
        assert!(tinted.tinted);
        let Optics::Tinted { t, .. } = tinted.optics(1.0) else { panic!("tinted") };
        for i in 0..81 {
            assert!((t[i] - tint[i]).abs() < 1e-5, "band {i}: {} against {}", t[i], tint[i]);
        }
        let band = 28; // 520 nm, the peak: 0.8
        let clear = Glass::new(1.52, 6.0, Some(&Spectrum([tint[band]; 81])));
        assert!(!clear.tinted);
        for cos in [0.9f32, 0.5, 0.1] {
            let Optics::Tinted { r, t } = tinted.optics(cos) else { panic!("tinted") };
            let (rc, tc) = clear.reflect_transmit(cos);
            assert!((r[band] - rc).abs() < 1e-6 && (t[band] - tc).abs() < 1e-6, "{cos}");
            for i in 0..81 {
                assert!(r[i] + t[i] <= 1.0 && t[i] <= tc + 1e-6, "band {i} at {cos}");
            }
        }
    }
}
