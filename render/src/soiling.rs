//! Exposure-driven soiling (`restauro_scene::scene_file::Soiling`): a deposit covers the
//! surface where neither the open sky nor the driving rain reaches it. At each point it shades,
//! the tracer casts one ray to the sky (cosine-distributed about the normal; it counts if it
//! leaves above the horizon) and one into the driving rain (within 10° of its direction), and
//! takes the share washed, W = min(1, a·v_sky + b·v_rain·cos θ / max(sin θ_rain, 0.25)); the
//! deposit covers s = s_max·(1 − W). The pixel's samples average s, so a sheltered band under a
//! cornice darkens smoothly, without a map.

use crate::bsdf::cosine_sample;
use crate::frame::Frame;
use crate::sampler::PixelSampler;
use glam::Vec3A;
use restauro_scene::scene_file::Soiling as SoilingFile;
use restauro_spectral::Spectrum;

/// The spread of the driving rain about its mean direction (half-angle).
const RAIN_SPREAD_DEG: f32 = 10.0;

pub struct Soiling {
    deposit: Spectrum,
    max_fraction: f32,
    /// Unit vector towards where the rain comes from (up, and towards its azimuth).
    to_rain: Vec3A,
    /// The normaliser of a face's exposure to rain: sin θ_rain, at least 0.25.
    exposure_of_facing_wall: f32,
    sky_weight: f32,
    rain_weight: f32,
}

impl Soiling {
    pub fn new(s: &SoilingFile, deposit: Spectrum) -> Self {
        let azimuth =
            s.rain_azimuth_deg.unwrap_or(SoilingFile::DEFAULT_RAIN_AZIMUTH_DEG).to_radians();
        let angle = s.rain_angle_deg.unwrap_or(SoilingFile::DEFAULT_RAIN_ANGLE_DEG).to_radians();
        // Azimuth from north (+Y) towards east (+X).
        let to_rain = Vec3A::new(
            (angle.sin() * azimuth.sin()) as f32,
            (angle.sin() * azimuth.cos()) as f32,
            angle.cos() as f32,
        );
        Self {
            deposit,
            max_fraction: s.max_fraction as f32,
            to_rain,
            exposure_of_facing_wall: (angle.sin() as f32).max(0.25),
            sky_weight: s.sky_weight.unwrap_or(SoilingFile::DEFAULT_SKY_WEIGHT) as f32,
            rain_weight: s.rain_weight.unwrap_or(SoilingFile::DEFAULT_RAIN_WEIGHT) as f32,
        }
    }

    /// One estimate of the share the deposit covers at a point with shading normal `normal`,
    /// rays leaving from `origin`; `occluded(origin, direction)` is the scene's shadow ray to
    /// infinity ([`crate::prepared::PreparedScene::occluded`]).
    pub fn share(
        &self,
        occluded: impl Fn(Vec3A, Vec3A) -> bool,
        origin: Vec3A,
        normal: Vec3A,
        sampler: &mut PixelSampler,
        rays: &mut u64,
    ) -> f32 {
        let (u1, u2) = sampler.next2();
        let to_sky = Frame::new(normal).to_world(cosine_sample(u1, u2));
        *rays += 2;
        let v_sky = to_sky.z > 0.0 && !occluded(origin, to_sky);
        let (u1, u2) = sampler.next2();
        let to_rain = Frame::new(self.to_rain).to_world(cone_sample(u1, u2));
        let cos = normal.dot(to_rain);
        let v_rain = if cos > 0.0 && !occluded(origin, to_rain) {
            cos / self.exposure_of_facing_wall
        } else {
            0.0
        };
        let washed =
            (self.sky_weight * f32::from(u8::from(v_sky)) + self.rain_weight * v_rain).min(1.0);
        self.max_fraction * (1.0 - washed)
    }

    /// (1 − s)·ρ + s·ρ_deposit into `out`.
    #[inline]
    pub fn mix(&self, rho: &Spectrum, share: f32, out: &mut Spectrum) {
        for ((o, r), d) in out.0.iter_mut().zip(&rho.0).zip(&self.deposit.0) {
            *o = r + share * (d - r);
        }
    }
}

/// A direction uniform in solid angle within [`RAIN_SPREAD_DEG`] of +Z.
fn cone_sample(u1: f32, u2: f32) -> Vec3A {
    let cos_max = RAIN_SPREAD_DEG.to_radians().cos();
    let cos = 1.0 - u1 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u2;
    Vec3A::new(sin * phi.cos(), sin * phi.sin(), cos)
}
