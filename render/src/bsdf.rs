//! The reflection models of the paper's materials, in a local frame whose +Z is the surface
//! normal; directions point away from the surface.
//!
//! * Lambert: f = ρ(λ)/π.
//! * Cook–Torrance (Cook & Torrance, "A reflectance model for computer graphics", ACM TOG 1(1),
//!   1982): a specular microfacet lobe D·G·F / (4 cos θi cos θo) with the Beckmann distribution
//!   D, their geometric attenuation G and Schlick's Fresnel F, over a diffuse base ρ(λ) coupled
//!   as Ashikhmin & Shirley ("An anisotropic Phong BRDF model", 2000, Eq. 5) couple theirs: the
//!   diffuse part only gets the light the specular interface lets through, on the way in and
//!   out, so the sum does not reflect more than arrives and stays reciprocal.
//!
//! Stone is a dielectric: its specular reflection is neutral (F0 from the index of
//! refraction), its colour is in the diffuse ρ(λ).

use glam::Vec3A;
use restauro_spectral::Spectrum;
use std::f32::consts::{FRAC_1_PI, PI};

#[derive(Clone, Debug, PartialEq)]
pub enum Bsdf {
    Lambert {
        rho: Spectrum,
    },
    CookTorrance {
        rho: Spectrum,
        f0: f32,
        roughness: f32,
    },
    /// A pane of glass: no diffuse or glossy part. The integrators follow it as a specular
    /// interface ([`crate::glass`]), and shadow rays pass through it.
    Glass(crate::glass::Glass),
}

/// The diffuse reflectance of a material that has none.
static NO_REFLECTANCE: Spectrum = Spectrum::ZERO;

/// Schlick's approximation of the Fresnel reflectance.
#[inline]
fn schlick(f0: f32, cos: f32) -> f32 {
    f0 + (1.0 - f0) * (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// The Beckmann distribution of microfacet normals with rms slope m.
#[inline]
fn beckmann(cos_h: f32, m: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let c2 = cos_h * cos_h;
    let tan2 = (1.0 - c2) / c2;
    (-tan2 / (m * m)).exp() / (PI * m * m * c2 * c2)
}

/// Cosine-weighted direction on the hemisphere (Malley's method).
#[inline]
pub fn cosine_sample(u1: f32, u2: f32) -> Vec3A {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    Vec3A::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt())
}

impl Bsdf {
    /// The spectral and the neutral parts of f(wo, wi): f = ρ(λ)·a + b. Lights are summed with
    /// these scalar weights and ρ(λ) applied once, instead of multiplying whole spectra per
    /// light.
    #[inline]
    pub fn parts(&self, wo: Vec3A, wi: Vec3A) -> (f32, f32) {
        let (co, ci) = (wo.z, wi.z);
        if co <= 0.0 || ci <= 0.0 {
            return (0.0, 0.0);
        }
        match *self {
            Bsdf::Lambert { .. } => (FRAC_1_PI, 0.0),
            Bsdf::Glass(_) => (0.0, 0.0),
            Bsdf::CookTorrance { f0, roughness, .. } => {
                let h = (wo + wi).normalize();
                let oh = wo.dot(h).max(1e-6);
                let g = (2.0 * h.z * co / oh).min(2.0 * h.z * ci / oh).min(1.0);
                let specular = beckmann(h.z, roughness) * g * schlick(f0, oh) / (4.0 * ci * co);
                let through = |c: f32| 1.0 - (1.0 - c / 2.0).powi(5);
                let diffuse = 28.0 / (23.0 * PI) * (1.0 - f0) * through(ci) * through(co);
                (diffuse, specular)
            }
        }
    }

    pub fn rho(&self) -> &Spectrum {
        match self {
            Bsdf::Lambert { rho } | Bsdf::CookTorrance { rho, .. } => rho,
            Bsdf::Glass(_) => &NO_REFLECTANCE,
        }
    }

    /// f(wo, wi), spectral, in sr⁻¹.
    #[inline]
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Spectrum {
        self.eval_with(self.rho(), wo, wi)
    }

    /// f(wo, wi) with the diffuse reflectance `rho` in place of the material's own: its value
    /// at a point of a textured surface ([`crate::prepared::PreparedScene::reflectance`]).
    #[inline]
    pub fn eval_with(&self, rho: &Spectrum, wo: Vec3A, wi: Vec3A) -> Spectrum {
        let (a, b) = self.parts(wo, wi);
        let mut f = *rho * a;
        if b != 0.0 {
            f += b;
        }
        f
    }

    /// The probability of choosing the specular lobe when sampling.
    #[inline]
    fn specular_probability(&self) -> f32 {
        match self {
            Bsdf::Lambert { .. } | Bsdf::Glass(_) => 0.0,
            Bsdf::CookTorrance { .. } => 0.5,
        }
    }

    /// The density (per solid angle) with which [`Bsdf::sample`] picks wi.
    #[inline]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let diffuse = wi.z * FRAC_1_PI;
        match *self {
            Bsdf::Lambert { .. } => diffuse,
            Bsdf::Glass(_) => 0.0,
            Bsdf::CookTorrance { roughness, .. } => {
                let p = self.specular_probability();
                let h = (wo + wi).normalize();
                let specular = beckmann(h.z, roughness) * h.z / (4.0 * wo.dot(h).max(1e-6));
                p * specular + (1.0 - p) * diffuse
            }
        }
    }

    /// Choose wi for wo with three uniform numbers; `None` when the choice falls below the
    /// surface.
    #[inline]
    pub fn sample(&self, wo: Vec3A, u: f32, u1: f32, u2: f32) -> Option<(Vec3A, f32)> {
        if let Bsdf::Glass(_) = self {
            return None;
        }
        let wi = match *self {
            Bsdf::CookTorrance { roughness, .. } if u < self.specular_probability() => {
                // Beckmann half vector: tan²θh = −m² ln(1 − u1), φ = 2π u2.
                let tan2 = -roughness * roughness * (1.0 - u1).max(1e-12).ln();
                let cos_h = 1.0 / (1.0 + tan2).sqrt();
                let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
                let phi = 2.0 * PI * u2;
                let h = Vec3A::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
                2.0 * wo.dot(h) * h - wo
            }
            _ => cosine_sample(u1, u2),
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then_some((wi, pdf))
    }

    /// Whether the material has a specular part that the Whitted integrator follows, and its
    /// reflectance towards the mirror direction.
    pub fn mirror_reflectance(&self, cos_o: f32) -> Option<f32> {
        match *self {
            Bsdf::Lambert { .. } | Bsdf::Glass(_) => None,
            Bsdf::CookTorrance { f0, .. } => Some(schlick(f0, cos_o)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restauro_spectral::keyed_random::KeyedRng;

    fn dir(theta_deg: f32, phi_deg: f32) -> Vec3A {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        Vec3A::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// ∫ f(wo, wi) cos θi dωi over the hemisphere, by a fine midpoint rule in (θ, φ).
    fn albedo(b: &Bsdf, wo: Vec3A) -> f32 {
        let (nt, np) = (400, 400);
        let mut sum = 0.0f64;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..np {
                let p = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                let wi = Vec3A::new(
                    (t.sin() * p.cos()) as f32,
                    (t.sin() * p.sin()) as f32,
                    t.cos() as f32,
                );
                let f = f64::from(b.eval(wo, wi)[40]);
                sum += f * t.cos() * t.sin();
            }
        }
        (sum * (std::f64::consts::FRAC_PI_2 / nt as f64) * (2.0 * std::f64::consts::PI / np as f64))
            as f32
    }

    #[test]
    fn lambert_reflects_rho() {
        let b = Bsdf::Lambert { rho: Spectrum::splat(0.6) };
        assert!((albedo(&b, dir(30.0, 0.0)) - 0.6).abs() < 1e-3);
    }

    /// White furnace: with ρ = 1 nothing reflects more than arrives, at any angle, for rough
    /// and polished surfaces and any F0.
    #[test]
    fn cook_torrance_never_reflects_more_than_arrives() {
        for roughness in [0.05, 0.2, 0.5, 1.0] {
            for f0 in [0.04, 0.2, 1.0] {
                let b = Bsdf::CookTorrance { rho: Spectrum::ONE, f0, roughness };
                for theta in [0.0, 30.0, 60.0, 80.0, 89.0] {
                    let a = albedo(&b, dir(theta, 10.0));
                    assert!(a <= 1.0 + 2e-3, "m {roughness} F0 {f0} θ {theta}: albedo {a}");
                }
            }
        }
    }

    #[test]
    fn cook_torrance_is_reciprocal() {
        let b = Bsdf::CookTorrance { rho: Spectrum::splat(0.5), f0: 0.05, roughness: 0.3 };
        let mut r = KeyedRng::new(3);
        for _ in 0..200 {
            let a = cosine_sample(r.next_f32(), r.next_f32());
            let c = cosine_sample(r.next_f32(), r.next_f32());
            let (f1, f2) = (b.eval(a, c)[10], b.eval(c, a)[10]);
            assert!((f1 - f2).abs() <= 1e-5 * f1.abs().max(1.0), "{f1} vs {f2}");
        }
    }

    /// The sampler's density is the one it reports: E[f cos / pdf] over samples equals the
    /// albedo computed by quadrature.
    #[test]
    fn sampling_matches_its_pdf() {
        let b = Bsdf::CookTorrance { rho: Spectrum::splat(0.7), f0: 0.04, roughness: 0.35 };
        let wo = dir(40.0, 0.0);
        let mut r = KeyedRng::new(11);
        let n = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            if let Some((wi, pdf)) = b.sample(wo, r.next_f32(), r.next_f32(), r.next_f32()) {
                sum += f64::from(b.eval(wo, wi)[40] * wi.z / pdf);
            }
        }
        let estimate = sum / f64::from(n);
        let reference = f64::from(albedo(&b, wo));
        assert!((estimate / reference - 1.0).abs() < 0.01, "{estimate} vs {reference}");
    }
}
