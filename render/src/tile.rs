//! Rendering a rectangle of the image: every pixel the mean spectral radiance of its samples,
//! reduced to absolute CIE XYZ (Y in cd/m², K_m = 683 lm/W). Rows run in parallel (rayon); each
//! pixel's sum runs in a fixed order from samples keyed by (seed, pixel, sample), so the result
//! is bit-identical whatever the tile size, the thread count or the worker.

use crate::integrator::{LIT_BITS, add_radiance};
use crate::prepared::PreparedScene;
use crate::sampler::{PixelKey, PixelSampler};
use crate::sensor::{self, Component};
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

pub use restauro_scene::plan::Rect;

/// A rendered rectangle: row-major within the rectangle.
pub struct TileResult {
    pub rect: Rect,
    pub xyz: Vec<[f32; 3]>,
    /// The spectral radiance of each pixel, when asked for.
    pub spectral: Option<Vec<Spectrum>>,
    /// When the scene has a sky: the fraction of each pixel's camera samples that saw it.
    pub sky: Option<Vec<f32>>,
    /// When the scene has point or distant lights: which light each pixel's first hits, for
    /// most of its samples (a bit per light, as [`crate::integrator::Seen::lit_by`]).
    pub lit_by: Option<Vec<u32>>,
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
    keyed_camera_ray(scene, PixelKey::new(scene.settings.seed, x, y), x, y, s)
}

#[inline]
fn keyed_camera_ray(
    scene: &PreparedScene,
    key: PixelKey,
    x: u32,
    y: u32,
    s: u32,
) -> (Vec3A, PixelSampler) {
    let mut sampler = key.sampler(s);
    let (u, v) = sampler.next2();
    let (dx, dy) = scene.strata.position(s, u, v);
    (scene.camera.direction(x as f32 + dx, y as f32 + dy), sampler)
}

/// The sum of the spectral radiance of pixel (x, y)'s samples, how many saw the sky, and the
/// lights that light the first hits of more than half of them.
#[inline]
fn pixel_sum(scene: &PreparedScene, x: u32, y: u32, rays: &mut u64) -> (Spectrum, u32, u32) {
    if scene.settings.grids {
        // Sensor x's direct (row 0) or indirect (row 1) irradiance.
        return (sensor::irradiance_sum(scene, x, Component::of_row(y), rays), 0, 0);
    }
    let key = PixelKey::new(scene.settings.seed, x, y);
    let mut sum = Spectrum::ZERO;
    let mut sky = 0;
    let mut lit = [0u32; LIT_BITS];
    let samples = scene.settings.samples_per_pixel.max(1);
    for s in 0..samples {
        let (direction, mut sampler) = keyed_camera_ray(scene, key, x, y, s);
        let seen =
            add_radiance(scene, scene.camera.origin, direction, &mut sampler, rays, &mut sum);
        sky += u32::from(seen.sky);
        let mut bits = seen.lit_by;
        while bits != 0 {
            lit[bits.trailing_zeros() as usize] += 1;
            bits &= bits - 1;
        }
    }
    let lit_by = (0..LIT_BITS).filter(|&k| 2 * lit[k] > samples).fold(0, |m, k| m | 1 << k);
    (sum, sky, lit_by)
}

/// [`pixel`], counting the rays traced.
pub fn pixel_counted(scene: &PreparedScene, x: u32, y: u32, rays: &mut u64) -> Spectrum {
    pixel_sum(scene, x, y, rays).0 * (1.0 / scene.settings.samples_per_pixel.max(1) as f32)
}

/// Renders `rect`: absolute XYZ per pixel, and the spectral radiance too when `spectral` is set
/// (kept only then: a row of spectra is 81 times the size of its XYZ).
pub fn render_tile(scene: &PreparedScene, rect: Rect, spectral: bool) -> TileResult {
    type Row = (Vec<[f32; 3]>, Option<Vec<Spectrum>>, Option<Vec<f32>>, Option<Vec<u32>>, u64);
    // A grid's sensors see no sky and have no frameworks of illumination (`Plan::new`).
    let has_sky = scene.has_visible_sources() && !scene.settings.grids;
    let has_lights = !scene.lights.is_empty() && !scene.settings.grids;
    let rows: Vec<Row> = (rect.y..rect.y + rect.height)
        .into_par_iter()
        .map(|y| {
            let mut rays = 0;
            let width = rect.width as usize;
            let mut xyz = Vec::with_capacity(width);
            let mut spectra = spectral.then(|| Vec::with_capacity(width));
            let mut sky = has_sky.then(|| Vec::with_capacity(width));
            let mut lit = has_lights.then(|| Vec::with_capacity(width));
            let mean = 1.0 / scene.settings.samples_per_pixel.max(1) as f32;
            // A grid's tile is two rows of sensors, each costly: its sensors run in parallel.
            let sums: Vec<(Spectrum, u32, u32, u64)> = if scene.settings.grids {
                (rect.x..rect.x + rect.width)
                    .into_par_iter()
                    .map(|x| {
                        let mut rays = 0;
                        let (sum, sky, lit) = pixel_sum(scene, x, y, &mut rays);
                        (sum, sky, lit, rays)
                    })
                    .collect()
            } else {
                Vec::new()
            };
            for x in rect.x..rect.x + rect.width {
                // The film is linear: the XYZ of the sum, scaled, is the XYZ of the mean.
                let (sum, saw_sky, lit_by) = match sums.get((x - rect.x) as usize) {
                    Some(&(sum, sky, lit, sensor_rays)) => {
                        rays += sensor_rays;
                        (sum, sky, lit)
                    }
                    None => pixel_sum(scene, x, y, &mut rays),
                };
                xyz.push(film_xyz(&sum).map(|v| v * mean));
                if let Some(s) = &mut spectra {
                    s.push(sum * mean);
                }
                if let Some(s) = &mut sky {
                    s.push(saw_sky as f32 * mean);
                }
                if let Some(l) = &mut lit {
                    l.push(lit_by);
                }
            }
            (xyz, spectra, sky, lit, rays)
        })
        .collect();
    let rays = rows.iter().map(|r| r.4).sum();
    let pixels = rect.width as usize * rect.height as usize;
    let mut xyz = Vec::with_capacity(pixels);
    let mut spectra = spectral.then(|| Vec::with_capacity(pixels));
    let mut sky = has_sky.then(|| Vec::with_capacity(pixels));
    let mut lit_by = has_lights.then(|| Vec::with_capacity(pixels));
    for (row_xyz, row_spectra, row_sky, row_lit, _) in rows {
        xyz.extend(row_xyz);
        if let (Some(all), Some(row)) = (&mut spectra, row_spectra) {
            all.extend(row);
        }
        if let (Some(all), Some(row)) = (&mut sky, row_sky) {
            all.extend(row);
        }
        if let (Some(all), Some(row)) = (&mut lit_by, row_lit) {
            all.extend(row);
        }
    }
    TileResult { rect, xyz, spectral: spectra, sky, lit_by, rays }
}
