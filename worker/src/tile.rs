//! Rendering a rectangle of the image: every pixel the mean spectral radiance of its samples,
//! reduced to absolute CIE XYZ (Y in cd/m², K_m = 683 lm/W). Rows run in parallel (rayon); each
//! pixel's sum runs in a fixed order from samples keyed by (seed, pixel, sample), so the result
//! is bit-identical whatever the tile size, the thread count or the worker.

use crate::integrator::radiance;
use crate::prepared::PreparedScene;
use crate::sampler::{PixelSampler, stratified};
use glam::Vec3A;
use rayon::prelude::*;
use restauro_spectral::Spectrum;
use restauro_spectral::colorimetry::{K_M_LM_PER_W, Observer};
use restauro_spectral::grid::STEP_NM;
use std::sync::LazyLock;

/// K_m · Δλ · x̄, ȳ, z̄ (CIE 1931 2°) as f32 spectra: the film's X, Y, Z are one fast dot product
/// each (X = K_m Σ L_e(λ) x̄(λ) Δλ, paper §2.2).
static FILM_WEIGHTS: LazyLock<[Spectrum; 3]> =
    LazyLock::new(|| Observer::Cie1931TwoDegree.cmf().map(|c| c * (K_M_LM_PER_W * STEP_NM) as f32));

/// Absolute XYZ (Y in cd/m²) of a spectral radiance.
#[inline]
pub fn film_xyz(radiance: &Spectrum) -> [f32; 3] {
    let w = &*FILM_WEIGHTS;
    [radiance.dot_f32(&w[0]), radiance.dot_f32(&w[1]), radiance.dot_f32(&w[2])]
}

/// A rectangle of pixels, from the top-left corner of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// A rendered rectangle: row-major within the rectangle.
pub struct TileResult {
    pub rect: Rect,
    pub xyz: Vec<[f32; 3]>,
    /// The spectral radiance of each pixel, when asked for.
    pub spectral: Option<Vec<Spectrum>>,
    /// The rays traced for the tile.
    pub rays: u64,
}

/// The mean spectral radiance of pixel (x, y).
pub fn pixel(scene: &PreparedScene, x: u32, y: u32) -> Spectrum {
    pixel_counted(scene, x, y, &mut 0)
}

/// The camera ray of sample `s` of pixel (x, y): its direction (from the camera's origin) and
/// the sampler, advanced past the two numbers that placed it in the pixel, for the rest of the
/// sample.
pub fn camera_ray(scene: &PreparedScene, x: u32, y: u32, s: u32) -> (Vec3A, PixelSampler) {
    let spp = scene.settings.samples_per_pixel.max(1);
    let mut sampler = PixelSampler::new(scene.settings.seed, x, y, s);
    let (u, v) = sampler.next2();
    let (dx, dy) = stratified(s, spp, u, v);
    (scene.camera.direction(x as f32 + dx, y as f32 + dy), sampler)
}

/// [`pixel`], counting the rays traced.
pub fn pixel_counted(scene: &PreparedScene, x: u32, y: u32, rays: &mut u64) -> Spectrum {
    let spp = scene.settings.samples_per_pixel.max(1);
    let mut sum = Spectrum::ZERO;
    for s in 0..spp {
        let (direction, mut sampler) = camera_ray(scene, x, y, s);
        sum += radiance(scene, scene.camera.origin, direction, &mut sampler, rays);
    }
    sum * (1.0 / spp as f32)
}

pub fn render_tile(scene: &PreparedScene, rect: Rect, spectral: bool) -> TileResult {
    let rows: Vec<(Vec<Spectrum>, u64)> = (rect.y..rect.y + rect.height)
        .into_par_iter()
        .map(|y| {
            let mut rays = 0;
            let row = (rect.x..rect.x + rect.width)
                .map(|x| pixel_counted(scene, x, y, &mut rays))
                .collect();
            (row, rays)
        })
        .collect();
    let rays = rows.iter().map(|(_, r)| r).sum();
    let rows: Vec<Vec<Spectrum>> = rows.into_iter().map(|(row, _)| row).collect();
    let xyz = rows.iter().flatten().map(film_xyz).collect();
    TileResult { rect, xyz, spectral: spectral.then(|| rows.into_iter().flatten().collect()), rays }
}
