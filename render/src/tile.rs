//! Rendering a rectangle of the image: every pixel the mean spectral radiance of its samples,
//! reduced to absolute CIE XYZ (Y in cd/m², K_m = 683 lm/W). Rows run in parallel (rayon); each
//! pixel's sum runs in a fixed order from samples keyed by (seed, pixel, sample), so the result
//! is bit-identical whatever the tile size, the thread count or the worker.

use crate::adaptive::{BATCH, NoiseEstimate};
use crate::integrator::{LIT_BITS, add_radiance};
use crate::prepared::PreparedScene;
use crate::sampler::{PixelKey, PixelSampler};
use crate::sensor::{self, Component};
use glam::Vec3A;
use rayon::prelude::*;
use restauro_spectral::Spectrum;
use restauro_spectral::cie::scotopic_efficacy_lm_per_w;
use restauro_spectral::colorimetry::{K_M_LM_PER_W, Observer};
use restauro_spectral::grid::STEP_NM;
use std::sync::LazyLock;

/// K_m · Δλ · x̄, ȳ, z̄ (CIE 1931 2°) as f32 spectra: the film's X, Y, Z are one fast dot product
/// each (X = K_m Σ L_e(λ) x̄(λ) Δλ, paper §2.2).
static FILM_WEIGHTS: LazyLock<[Spectrum; 3]> =
    LazyLock::new(|| Observer::Cie1931TwoDegree.cmf().map(|c| c * (K_M_LM_PER_W * STEP_NM) as f32));
/// K′_m · Δλ · V′(λ): the scotopic luminance (scotopic cd/m²) of a spectral radiance (CIE 191).
static SCOTOPIC_WEIGHTS: LazyLock<Spectrum> = LazyLock::new(|| {
    *restauro_spectral::cie::scotopic_v() * (scotopic_efficacy_lm_per_w() * STEP_NM) as f32
});

/// Absolute XYZ (Y in cd/m²) of a spectral radiance.
#[inline]
pub fn film_xyz(radiance: &Spectrum) -> [f32; 3] {
    let w = &*FILM_WEIGHTS;
    [radiance.dot_f32(&w[0]), radiance.dot_f32(&w[1]), radiance.dot_f32(&w[2])]
}

/// The adapting white of a pixel: X, Y, Z (Y in cd/m²) and the scotopic luminance (scotopic
/// cd/m²) of what a perfect white diffuser at its surface would send back.
#[inline]
pub fn white_of(radiance: &Spectrum) -> [f32; 4] {
    let [x, y, z] = film_xyz(radiance);
    [x, y, z, radiance.dot_f32(&SCOTOPIC_WEIGHTS)]
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
    /// For an image (not a grid): each pixel's adapting white ([`white_of`]), the mean over
    /// its camera samples that met a surface; zero where none did.
    pub white: Option<Vec<[f32; 4]>>,
    /// With adaptive sampling: the samples each pixel took ([`crate::adaptive`]).
    pub samples: Option<Vec<u32>>,
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
    // A pixel that may stop after any batch takes its positions from a net that is even after
    // every batch; one that takes every sample, from the strata of its count.
    let (dx, dy) = match scene.settings.adaptive() {
        true => key.subpixel_net(s),
        false => scene.strata.position(s, u, v),
    };
    (scene.camera.direction(x as f32 + dx, y as f32 + dy), sampler)
}

/// What a pixel's samples add up to.
struct PixelSum {
    radiance: Spectrum,
    /// The samples taken: the render's count, or fewer where [`crate::adaptive`] stopped.
    samples: u32,
    /// The samples that saw the sky.
    sky: u32,
    /// The lights that light the first hits of more than half of the samples.
    lit_by: u32,
    /// The mean white diffuser's radiance of the samples that met a surface.
    white: Spectrum,
}

/// The sum of the spectral radiance of pixel (x, y)'s samples, how many saw the sky, the
/// lights that light the first hits of more than half of them, and their white. With adaptive
/// sampling the pixel takes its samples in batches until its own estimate of its noise is
/// within the target ([`crate::adaptive`]).
#[inline]
fn pixel_sum(scene: &PreparedScene, x: u32, y: u32, rays: &mut u64) -> PixelSum {
    if scene.settings.grids {
        // Sensor x's direct (row 0) or indirect (row 1) irradiance.
        let radiance = sensor::irradiance_sum(scene, x, Component::of_row(y), rays);
        let samples = scene.settings.samples_per_pixel.max(1);
        return PixelSum { radiance, samples, sky: 0, lit_by: 0, white: Spectrum::ZERO };
    }
    let key = PixelKey::new(scene.settings.seed, x, y);
    let mut acc = Accumulated::default();
    let cap = scene.settings.samples_per_pixel.max(1);
    if !scene.settings.adaptive() {
        for s in 0..cap {
            acc.add_sample(scene, key, (x, y), s, rays);
        }
        return acc.finish(cap);
    }
    let mut noise = NoiseEstimate::default();
    let mut seen = [0.0f32; 3];
    let mut taken = 0;
    while taken < cap {
        for s in taken..(taken + BATCH).min(cap) {
            acc.add_sample(scene, key, (x, y), s, rays);
            // This sample's own X, Y, Z: the film is linear, so the sums' difference.
            let now = film_xyz(&acc.radiance);
            noise.add([now[0] - seen[0], now[1] - seen[1], now[2] - seen[2]]);
            seen = now;
        }
        taken = noise.count();
        if noise.converged(scene.settings.noise_target) {
            break;
        }
    }
    acc.finish(taken)
}

/// A pixel's samples summed so far.
#[derive(Default)]
struct Accumulated {
    radiance: Spectrum,
    white: Spectrum,
    sky: u32,
    surfaces: u32,
    lit: [u32; LIT_BITS],
}

impl Accumulated {
    /// Sample `s` of pixel (x, y), added.
    #[inline]
    fn add_sample(
        &mut self,
        scene: &PreparedScene,
        key: PixelKey,
        (x, y): (u32, u32),
        s: u32,
        rays: &mut u64,
    ) {
        let (direction, mut sampler) = keyed_camera_ray(scene, key, x, y, s);
        let origin = scene.camera.origin;
        let seen = add_radiance(
            scene,
            origin,
            direction,
            &mut sampler,
            rays,
            &mut self.radiance,
            &mut self.white,
        );
        self.sky += u32::from(seen.sky);
        self.surfaces += u32::from(seen.surface);
        let mut bits = seen.lit_by;
        while bits != 0 {
            self.lit[bits.trailing_zeros() as usize] += 1;
            bits &= bits - 1;
        }
    }

    /// The pixel's sum after `samples` samples.
    fn finish(mut self, samples: u32) -> PixelSum {
        let lit = &self.lit;
        let lit_by = (0..LIT_BITS).filter(|&k| 2 * lit[k] > samples).fold(0, |m, k| m | 1 << k);
        if self.surfaces > 0 {
            self.white *= 1.0 / self.surfaces as f32;
        }
        PixelSum { radiance: self.radiance, samples, sky: self.sky, lit_by, white: self.white }
    }
}

/// [`pixel`], counting the rays traced.
pub fn pixel_counted(scene: &PreparedScene, x: u32, y: u32, rays: &mut u64) -> Spectrum {
    let sum = pixel_sum(scene, x, y, rays);
    sum.radiance * (1.0 / sum.samples as f32)
}

/// The per-pixel layers a tile carries besides XYZ.
#[derive(Clone, Copy)]
struct Layers {
    spectral: bool,
    sky: bool,
    lit: bool,
    white: bool,
    samples: bool,
}

/// The pixels of one row of a tile, or of a whole tile once the rows are joined.
#[derive(Default)]
struct Pixels {
    xyz: Vec<[f32; 3]>,
    spectra: Option<Vec<Spectrum>>,
    sky: Option<Vec<f32>>,
    lit_by: Option<Vec<u32>>,
    white: Option<Vec<[f32; 4]>>,
    samples: Option<Vec<u32>>,
    rays: u64,
}

impl Pixels {
    /// Room for `n` pixels, with the layers asked for.
    fn with_capacity(n: usize, layers: Layers) -> Self {
        fn layer<T>(on: bool, n: usize) -> Option<Vec<T>> {
            on.then(|| Vec::with_capacity(n))
        }
        Pixels {
            xyz: Vec::with_capacity(n),
            spectra: layer(layers.spectral, n),
            sky: layer(layers.sky, n),
            lit_by: layer(layers.lit, n),
            white: layer(layers.white, n),
            samples: layer(layers.samples, n),
            rays: 0,
        }
    }

    /// A pixel from its samples' sum.
    fn push(&mut self, sum: &PixelSum) {
        let mean = 1.0 / sum.samples as f32;
        // The film is linear: the XYZ of the sum, scaled, is the XYZ of the mean.
        self.xyz.push(film_xyz(&sum.radiance).map(|v| v * mean));
        if let Some(s) = &mut self.spectra {
            s.push(sum.radiance * mean);
        }
        if let Some(s) = &mut self.sky {
            s.push(sum.sky as f32 * mean);
        }
        if let Some(l) = &mut self.lit_by {
            l.push(sum.lit_by);
        }
        if let Some(w) = &mut self.white {
            w.push(white_of(&sum.white));
        }
        if let Some(n) = &mut self.samples {
            n.push(sum.samples);
        }
    }

    /// `row` appended.
    fn extend(&mut self, row: Pixels) {
        fn join<T>(all: &mut Option<Vec<T>>, row: Option<Vec<T>>) {
            if let (Some(all), Some(row)) = (all, row) {
                all.extend(row);
            }
        }
        self.xyz.extend(row.xyz);
        join(&mut self.spectra, row.spectra);
        join(&mut self.sky, row.sky);
        join(&mut self.lit_by, row.lit_by);
        join(&mut self.white, row.white);
        join(&mut self.samples, row.samples);
        self.rays += row.rays;
    }
}

/// Renders `rect`: absolute XYZ per pixel, and the spectral radiance too when `spectral` is set
/// (kept only then: a row of spectra is 81 times the size of its XYZ).
pub fn render_tile(scene: &PreparedScene, rect: Rect, spectral: bool) -> TileResult {
    // A grid's sensors see no sky, have no frameworks of illumination and no white (`Plan::new`).
    let image = !scene.settings.grids;
    let has_sky = scene.has_visible_sources() && image;
    let has_lights = !scene.lights.is_empty() && image;
    let layers = Layers {
        spectral,
        sky: has_sky,
        lit: has_lights,
        white: image,
        samples: scene.settings.adaptive(),
    };
    let layers = |n| Pixels::with_capacity(n, layers);
    let rows: Vec<Pixels> = (rect.y..rect.y + rect.height)
        .into_par_iter()
        .map(|y| {
            let mut row = layers(rect.width as usize);
            let xs = rect.x..rect.x + rect.width;
            if scene.settings.grids {
                // A grid's tile is two rows of sensors, each costly: its sensors run in parallel.
                let sums: Vec<(PixelSum, u64)> = xs
                    .into_par_iter()
                    .map(|x| {
                        let mut rays = 0;
                        (pixel_sum(scene, x, y, &mut rays), rays)
                    })
                    .collect();
                for (sum, rays) in &sums {
                    row.rays += rays;
                    row.push(sum);
                }
            } else {
                for x in xs {
                    let sum = pixel_sum(scene, x, y, &mut row.rays);
                    row.push(&sum);
                }
            }
            row
        })
        .collect();
    let mut all = layers(rect.width as usize * rect.height as usize);
    for row in rows {
        all.extend(row);
    }
    TileResult {
        rect,
        xyz: all.xyz,
        spectral: all.spectra,
        sky: all.sky,
        lit_by: all.lit_by,
        white: all.white,
        samples: all.samples,
        rays: all.rays,
    }
}
