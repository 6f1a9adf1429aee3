//! Calculation grids: the spectral irradiance E(λ) (W·m⁻²·nm⁻¹) at a virtual sensor, a point
//! with a facing direction that casts no shadow and that no ray meets. Its Y,
//! K_m Σ E(λ) ȳ(λ) Δλ, is the illuminance in lux, computed from all 81 bands.
//!
//! * **Direct**: every point or distant light exactly, E⊥(λ) cos θ behind a shadow ray (the
//!   same terms the integrators use, Rossi et al. Eq. 8), plus one sample per sample of the sky:
//!   a cosine-weighted direction (pdf cos θ/π), so E = π · L_sky(ω) when the sky is open there;
//!   and of each area luminaire: a point of its panel, stratified over the samples.
//! * **Indirect** (the path integrator only): a cosine-weighted direction, and π times the
//!   radiance the surfaces it meets reflect back along it, followed as the path integrator
//!   follows a camera ray (`render.max_depth` surfaces, 0 for no cap). Whitted has no diffuse
//!   inter-reflection (the paper's ray tracing), so its indirect illuminance is zero.
//!
//! The first direction of each sample is stratified over the samples as a pixel's position is.
//! Each of a sensor's two rows has its own keyed random sequence, so the grids are bit-identical
//! wherever their tiles are computed.

use crate::frame::{Frame, lift_along};
use crate::glass::Transmission;
use crate::integrator::{Escape, trace};
use crate::light::Light;
use crate::prepared::PreparedScene;
use crate::sampler::PixelKey;
use glam::Vec3A;
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::f32::consts::PI;

/// The sensors themselves are part of the prepared scene ([`PreparedScene::sensors`]).
pub use crate::prepared::Sensor;

/// What a sensor's row holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    Direct,
    Indirect,
}

impl Component {
    /// The component of row `row` of a grids plan (see `Plan::grids`).
    pub fn of_row(row: u32) -> Self {
        if row == 0 { Self::Direct } else { Self::Indirect }
    }
}

/// The sum over the plan's samples of the `component` of sensor `index`'s spectral irradiance
/// (divide by the samples for the mean); `rays` counts the rays traced.
pub fn irradiance_sum(
    scene: &PreparedScene,
    index: u32,
    component: Component,
    rays: &mut u64,
) -> Spectrum {
    let mut sum = Spectrum::ZERO;
    let Some(sensor) = scene.sensors.get(index as usize) else { return sum };
    let samples = scene.settings.samples_per_pixel.max(1);
    let origin = lift_along(sensor.point, sensor.normal);
    let frame = Frame::new(sensor.normal);
    let extended = scene.lights.iter().any(|l| !l.is_delta());
    match component {
        Component::Direct => {
            // Point and distant lights are the same each sample: added once for all of them.
            add_lights(scene, sensor, origin, (samples as f32, None), rays, &mut sum);
            if scene.sky.is_none() && !extended {
                return sum;
            }
        }
        Component::Indirect if scene.settings.integrator == Integrator::Whitted => return sum,
        Component::Indirect => {}
    }
    let key = PixelKey::new(scene.settings.seed, index, component as u32);
    for s in 0..samples {
        let mut sampler = key.sampler(s);
        let (u, v) = sampler.next2();
        let (u1, u2) = scene.strata.position(s, u, v);
        let direction = frame.to_world(crate::bsdf::cosine_sample(u1, u2));
        match component {
            Component::Direct => {
                // The sky's own sample, if it has one, is stratified too: its first pair of
                // numbers picks the cell.
                let mut first = Some((u1, u2));
                let draw = || first.take().unwrap_or_else(|| sampler.next2());
                add_sky(scene, (origin, sensor.normal), direction, draw, rays, &mut sum);
                if extended {
                    // A point of each panel, stratified over the samples as the direction is.
                    let (u, v) = sampler.next2();
                    let at = scene.strata.position(s, u, v);
                    add_lights(scene, sensor, origin, (1.0, Some(at)), rays, &mut sum);
                }
            }
            Component::Indirect => {
                let mut radiance = Spectrum::ZERO;
                let ray = (origin, direction);
                trace(scene, ray, Escape::Nothing, &mut sampler, rays, &mut radiance);
                sum.add_scaled(&radiance, PI);
            }
        }
    }
    sum
}

/// `weight` times the irradiance that reaches the sensor: from every point and distant light
/// when `panel_point` is `None`, else from the point (s, t) of every area luminaire.
fn add_lights(
    scene: &PreparedScene,
    sensor: &Sensor,
    origin: Vec3A,
    (weight, panel_point): (f32, Option<(f32, f32)>),
    rays: &mut u64,
    out: &mut Spectrum,
) {
    for light in &scene.lights {
        let incident = match (panel_point, light) {
            (None, _) => light.incident(sensor.point),
            (Some((s, t)), Light::Area(panel)) => panel.incident_from(sensor.point, s, t),
            (Some(_), _) => None,
        };
        let Some(inc) = incident else { continue };
        let cos = inc.direction.dot(sensor.normal);
        if cos <= 0.0 {
            continue;
        }
        *rays += 1;
        let through = scene.visibility(origin, inc.direction, inc.shadow_reach());
        add_through(out, inc.spectrum, inc.scale * cos * weight, &through);
    }
}

/// One sample of the sky's irradiance at the sensor from the cosine-weighted `direction` (and,
/// for a sky sampled by its luminance, one more drawn with `draw`): L · weight each, the
/// weight π for the cosine sample alone.
fn add_sky(
    scene: &PreparedScene,
    (origin, normal): (Vec3A, Vec3A),
    direction: Vec3A,
    draw: impl FnMut() -> (f32, f32),
    rays: &mut u64,
    out: &mut Spectrum,
) {
    let Some(sky) = &scene.sky else { return };
    for sample in sky.samples(normal, direction, draw).into_iter().flatten() {
        if sample.luminance_cd_m2 <= 0.0 {
            continue;
        }
        *rays += 1;
        let through = scene.visibility(origin, sample.direction, f32::INFINITY);
        add_through(out, &sky.per_nit, sample.luminance_cd_m2 * sample.weight, &through);
    }
}

/// `out += k · light` as it arrives through `through`.
#[inline]
fn add_through(out: &mut Spectrum, light: &Spectrum, k: f32, through: &Transmission) {
    match through {
        Transmission::Neutral(t) if *t > 0.0 => out.add_scaled(light, k * t),
        Transmission::Neutral(_) => {}
        Transmission::Tinted(t) => out.add_reflected(light, t, k, 0.0),
    }
}
