//! Light sources in photometric units, turned into the spectral irradiance they give a point
//! (Rossi, Marini & Rizzi 2004, Eq. 8): for a luminaire of luminous intensity I_v(ω) (cd)
//! towards the point at distance r,
//!
//! ```text
//!   E⊥(λ) = I_v(ω) · S_e(λ) / (r² · Σ K(λ) S_e(λ) Δλ)     (W·m⁻²·nm⁻¹ on a surface facing it),
//! ```
//!
//! and cos α is applied by the integrator; for the sun, E⊥(λ) = E_v · S_e(λ) / Σ K S_e Δλ.
//! These are delta lights (a point or a direction), sampled exactly. The extended sources are
//! the sky, a dome of luminance L_v(ω) (cd/m²) above the horizon, whose spectral radiance is
//! L_v(ω) · S_e(λ) / Σ K(λ) S_e(λ) Δλ, sampled by the integrator over the hemisphere; and area
//! luminaires, Lambertian rectangles of one luminance, sampled by area far off — a point y drawn
//! uniformly on a panel of area A gives a point x the estimate
//!
//! ```text
//!   E⊥(λ) = L_v · A · cos θ_y / r² · S_e(λ) / Σ K S_e Δλ     (pdf 1/A; cos θ_x applied as above)
//! ```
//!
//! — and by solid angle close by, E⊥(λ) = L_v · Ω · S_e(λ)/Σ K S_e Δλ ([`crate::spherical_rectangle`]).

use crate::spherical_rectangle::SphericalRectangle;
use glam::Vec3A;
use restauro_scene::formats::photometric::Photometry;
use restauro_spectral::Spectrum;

/// The nearest distance at which a point light's inverse-square law is applied. A real
/// luminaire's far-field photometry holds only beyond about five times its size (the
/// photometric five-times rule); at 1 mm a light of the largest intensity a scene may give (10⁹ cd) gives 10¹⁵ lx, which keeps
/// every radiance the tracer makes far inside `restauro_image::radiometric_bound`.
pub const MIN_LIGHT_DISTANCE_M: f32 = 1e-3;

/// How a luminaire's intensity varies with direction.
#[derive(Clone, Debug)]
pub enum Distribution {
    Isotropic,
    /// A measured distribution, scaled so its peak is the luminaire's `intensity_cd`. The frame
    /// maps world directions to the photometric frame (γ = 0 along its −Z, C = 0 along its +X).
    Photometric {
        photometry: Photometry,
        to_local: [Vec3A; 3],
        scale: f64,
    },
    /// Full intensity within `cos_inner` of the axis, falling smoothly to zero at `cos_outer`.
    Cone {
        axis: Vec3A,
        cos_inner: f32,
        cos_outer: f32,
    },
}

#[derive(Clone, Debug)]
pub enum Light {
    /// A point luminaire: `per_cd` is S_e(λ)/Σ K S_e Δλ, the spectral radiant intensity of one
    /// candela (W·sr⁻¹·nm⁻¹).
    Point { position: Vec3A, intensity_cd: f32, per_cd: Spectrum, distribution: Distribution },
    /// A distant source: `direction` towards it, `irradiance` E⊥(λ) on a surface facing it,
    /// whose illuminance is `illuminance_lux`.
    Distant { direction: Vec3A, irradiance: Spectrum, illuminance_lux: f32 },
    /// An area luminaire, sampled by solid angle or by area ([`Panel::incident_from`]).
    Area(Panel),
}

/// A Lambertian emitting rectangle: `corner` + s·`u` + t·`v` for s, t in [0, 1], emitting
/// towards `normal` with luminance `luminance_cd_m2`.
#[derive(Clone, Debug)]
pub struct Panel {
    pub corner: Vec3A,
    pub u: Vec3A,
    pub v: Vec3A,
    pub normal: Vec3A,
    pub area_m2: f32,
    pub luminance_cd_m2: f32,
    /// S_e(λ)/Σ K S_e Δλ: the spectral radiance of one cd/m².
    pub per_nit: Spectrum,
}

impl Panel {
    /// One sample of the light reaching `p`, drawn with (s, t) ∈ [0, 1)²: by solid angle
    /// within two diagonals of the panel's centre, where sampling by area would be noisy (its
    /// 1/r² varies across the panel), and by area farther off, where it is as good and cheaper.
    /// Nothing when `p` is behind the panel or in its plane.
    #[inline]
    pub fn incident_from(&self, p: Vec3A, s: f32, t: f32) -> Option<Incident<'_>> {
        if (p - self.corner).dot(self.normal) <= 0.0 {
            return None;
        }
        let diagonal = self.u + self.v;
        let centre = self.corner + diagonal * 0.5;
        if (p - centre).length_squared() < 4.0 * diagonal.length_squared()
            && let Some(sr) = SphericalRectangle::new(self.corner, self.u, self.v, p)
        {
            let d = sr.sample(s, t) - p;
            let r = d.length();
            if r <= 0.0 {
                return None;
            }
            // Directions uniform over the solid angle Ω: E⊥ = L · Ω per sample.
            let e = self.luminance_cd_m2 * sr.solid_angle;
            let spectrum = &self.per_nit;
            return Some(Incident {
                direction: d / r,
                distance: r,
                scale: e,
                spectrum,
                illuminance_lux: e,
            });
        }
        self.incident_by_area(p, s, t)
    }

    /// The light reaching `p` from the point at (s, t) of the panel, as one sample of area
    /// sampling (pdf 1/A).
    #[inline]
    fn incident_by_area(&self, p: Vec3A, s: f32, t: f32) -> Option<Incident<'_>> {
        let y = self.corner + self.u * s + self.v * t;
        let d = y - p;
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            return None;
        }
        let r = r2.sqrt();
        let direction = d / r;
        let cos_y = -direction.dot(self.normal);
        if cos_y <= 0.0 {
            return None;
        }
        let e = self.luminance_cd_m2 * self.area_m2 * cos_y / r2;
        Some(Incident {
            direction,
            distance: r,
            scale: e,
            spectrum: &self.per_nit,
            illuminance_lux: e,
        })
    }

    /// Where the ray from `origin` along `direction` meets the panel before `tmax`, and
    /// whether it meets its emitting side.
    #[inline]
    pub fn intersect(&self, origin: Vec3A, direction: Vec3A, tmax: f32) -> Option<(f32, bool)> {
        let denom = direction.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.corner - origin).dot(self.normal) / denom;
        if !(t > 0.0 && t < tmax) {
            return None;
        }
        let q = origin + direction * t - self.corner;
        // u ⟂ v (the loader checks it), so each coordinate is a projection.
        let s = q.dot(self.u) / self.u.length_squared();
        let w = q.dot(self.v) / self.v.length_squared();
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&w)).then_some((t, denom < 0.0))
    }
}

/// A light's contribution at a point: the direction towards it, the distance (∞ for distant
/// lights) and the spectral irradiance on a surface facing it, `scale · spectrum` (kept apart so
/// that no spectrum is built per shadow ray), whose illuminance is `illuminance_lux`.
pub struct Incident<'a> {
    pub direction: Vec3A,
    pub distance: f32,
    pub scale: f32,
    pub spectrum: &'a Spectrum,
    pub illuminance_lux: f32,
}

impl Incident<'_> {
    /// E⊥(λ), the spectral irradiance on a surface facing the light.
    pub fn irradiance(&self) -> Spectrum {
        *self.spectrum * self.scale
    }

    /// How far a shadow ray towards the light looks for blockers: all the way to a distant
    /// light, and short of a near one by a relative 10⁻⁴, so that the light's own surface (an
    /// area luminaire's plane) does not block it.
    #[inline]
    pub fn shadow_reach(&self) -> f32 {
        if self.distance.is_finite() { self.distance * (1.0 - 1e-4) } else { f32::INFINITY }
    }
}

impl Distribution {
    /// The factor on the luminaire's intensity towards `direction` (unit, from the luminaire).
    pub fn factor(&self, direction: Vec3A) -> f32 {
        match self {
            Distribution::Isotropic => 1.0,
            Distribution::Photometric { photometry, to_local, scale } => {
                let d = [
                    f64::from(to_local[0].dot(direction)),
                    f64::from(to_local[1].dot(direction)),
                    f64::from(to_local[2].dot(direction)),
                ];
                (photometry.intensity_cd(d) * scale) as f32
            }
            Distribution::Cone { axis, cos_inner, cos_outer } => {
                let c = axis.dot(direction);
                if c >= *cos_inner {
                    1.0
                } else if c <= *cos_outer {
                    0.0
                } else {
                    // Smoothstep between the two cones.
                    let t = (c - cos_outer) / (cos_inner - cos_outer);
                    t * t * (3.0 - 2.0 * t)
                }
            }
        }
    }
}

impl Light {
    /// The memory the light holds, in bytes (its measured distribution's table included).
    pub fn memory_bytes(&self) -> usize {
        let table = match self {
            Light::Point {
                distribution: Distribution::Photometric { photometry: p, .. }, ..
            } => {
                (p.gamma_deg.len() + p.c_deg.len() + p.candela.iter().map(Vec::len).sum::<usize>())
                    * std::mem::size_of::<f64>()
            }
            _ => 0,
        };
        std::mem::size_of::<Self>() + table
    }

    /// One sample of the light reaching `p`: exact for a point or distant light (which draws
    /// nothing from `draw`), a point drawn on an area luminaire's panel.
    #[inline]
    pub fn sampled_incident(
        &self,
        p: Vec3A,
        draw: impl FnOnce() -> (f32, f32),
    ) -> Option<Incident<'_>> {
        match self {
            Light::Area(panel) => {
                let (s, t) = draw();
                panel.incident_from(p, s, t)
            }
            _ => self.incident(p),
        }
    }

    /// Whether the light is a point or a direction, the same at every sample.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Area(_))
    }

    /// The light reaching `p` from a point or distant light (`None` for an area luminaire,
    /// which is sampled: [`Light::sampled_incident`]).
    #[inline]
    pub fn incident(&self, p: Vec3A) -> Option<Incident<'_>> {
        match self {
            Light::Point { position, intensity_cd, per_cd, distribution } => {
                let d = *position - p;
                let r2 = d.length_squared();
                if r2 <= 0.0 {
                    return None;
                }
                let r = r2.sqrt();
                let direction = d / r;
                let intensity = intensity_cd * distribution.factor(-direction);
                // `per_cd` is normalised to one lumen per steradian, so E_v = I_v / r²; nearer
                // than MIN_LIGHT_DISTANCE_M the law no longer holds, and the irradiance is kept
                // at its value there (finite: the bound on tile data rests on it).
                let e = intensity / r2.max(MIN_LIGHT_DISTANCE_M * MIN_LIGHT_DISTANCE_M);
                (intensity > 0.0).then_some(Incident {
                    direction,
                    distance: r,
                    scale: e,
                    spectrum: per_cd,
                    illuminance_lux: e,
                })
            }
            Light::Distant { direction, irradiance, illuminance_lux } => Some(Incident {
                direction: *direction,
                distance: f32::INFINITY,
                scale: 1.0,
                spectrum: irradiance,
                illuminance_lux: *illuminance_lux,
            }),
            // Extended: sampled by [`Light::sampled_incident`].
            Light::Area(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = I/r² down to 1 mm, and the value at 1 mm nearer: a surface touching the largest
    /// light a scene may give gets a finite irradiance.
    #[test]
    fn a_point_light_lights_by_the_inverse_square_law_down_to_a_millimetre() {
        let light = Light::Point {
            position: Vec3A::ZERO,
            intensity_cd: 1e9,
            per_cd: Spectrum::splat(1.0),
            distribution: Distribution::Isotropic,
        };
        let lux = |r: f32| light.incident(Vec3A::new(0.0, 0.0, r)).unwrap().illuminance_lux;
        assert_eq!(lux(2.0), 1e9 / 4.0);
        let at_mm = lux(1e-3);
        assert!((at_mm / 1e15 - 1.0).abs() < 1e-4, "{at_mm}");
        for r in [5e-4, 1e-6, 1e-20] {
            assert_eq!(lux(r), at_mm, "at {r} m");
        }
    }
}
