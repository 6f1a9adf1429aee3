//! Degradation maps on the surface: a restorer's map of the forms of decay (black crust,
//! biological colonisation, efflorescence…), an image of flat class colours laid over a
//! rectangle of the building and projected onto the model square to it. Where a class is, the
//! surface reflects that class's spectrum; at a class's edge, and where a pixel's footprint
//! covers several classes, the spectra mix by the share of the surface each covers (an areal
//! mixture, as the soiled states are). Each class's coverage is a pyramid of 0/1 texels,
//! filtered by the ray's footprint as photo textures are ([`crate::texture`]).

use crate::texture::{LuminancePyramid, level_of_detail};
use glam::{Vec2, Vec3A};
use restauro_scene::scene_file::DegradationMap;
use restauro_scene::texture::Texture;
use restauro_spectral::Spectrum;
use std::sync::Arc;

/// The most classes a map may have (the loader refuses more).
pub const MAX_CLASSES: usize = restauro_scene::load::MAX_MAP_CLASSES;

/// A map as one material state shows it: the classes it lists, each with its coverage and
/// spectrum.
pub struct ClassMap {
    corner: Vec3A,
    /// u / |u|² and v / |v|²: a point's (u, v) on the rectangle is (p − corner)·these.
    u_axis: Vec3A,
    v_axis: Vec3A,
    /// The size of a texel on the rectangle (the smaller side).
    texel_m: f32,
    classes: Vec<(Arc<LuminancePyramid>, Spectrum)>,
}

/// One class's coverage: 1 where the image has the class's colour, 0 elsewhere.
pub fn coverage(image: &Texture, colour: [u8; 3]) -> LuminancePyramid {
    let target = colour.map(|c| u16::from(c) * 257);
    let values = image.texels.iter().map(|t| if *t == target { 1.0 } else { 0.0 }).collect();
    LuminancePyramid::from_values(image.width, image.height, values)
}

impl ClassMap {
    /// `map`'s rectangle with `classes`: each class's coverage pyramid and spectrum.
    pub fn new(
        map: &DegradationMap,
        size: (u32, u32),
        classes: Vec<(Arc<LuminancePyramid>, Spectrum)>,
    ) -> Self {
        let v3 = |p: [f64; 3]| Vec3A::from(p.map(|x| x as f32));
        let (u, v) = (v3(map.u), v3(map.v));
        let texel_m = (u.length() / size.0 as f32).min(v.length() / size.1 as f32);
        Self {
            corner: v3(map.corner),
            u_axis: u / u.length_squared(),
            v_axis: v / v.length_squared(),
            texel_m,
            classes,
        }
    }

    /// Bytes held (a coverage shared by several states is counted with each).
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.classes.iter().map(|(p, _)| p.memory_bytes()).sum::<usize>()
    }

    /// Mixes the classes at `point` into `rho` (the state's reflectance), the map filtered
    /// over `footprint_m`: ρ = (1 − Σ w_c)·ρ + Σ w_c·ρ_c.
    #[inline]
    pub fn mix(&self, point: Vec3A, footprint_m: f32, rho: &mut Spectrum) {
        let d = point - self.corner;
        let (u, v) = (d.dot(self.u_axis), d.dot(self.v_axis));
        if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
            return;
        }
        // The image's rows run from its top: v up the rectangle is 1 − v down the image.
        let at = Vec2::new(u, 1.0 - v);
        let lod = level_of_detail(footprint_m, self.texel_m);
        // The classes' shares first (they do not overlap: each texel is one class or none),
        // then the mixture.
        let mut shares = [0.0f32; MAX_CLASSES];
        for (share, (pyramid, _)) in shares.iter_mut().zip(&self.classes) {
            *share = pyramid.sample_clamped(at, lod);
        }
        let total: f32 = shares.iter().sum();
        if total <= 0.0 {
            return;
        }
        let rest = (1.0 - total).max(0.0);
        for r in &mut rho.0 {
            *r *= rest;
        }
        for (share, (_, class)) in shares.iter().zip(&self.classes) {
            if *share > 0.0 {
                for (r, c) in rho.0.iter_mut().zip(&class.0) {
                    *r += share * c;
                }
            }
        }
    }
}
