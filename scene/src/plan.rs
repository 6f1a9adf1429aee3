//! A render plan: a loaded scene and the options of one render (variant, integrator, samples,
//! size, tiles) resolved and checked once, the same way in every process — the client that
//! renders in-process, the coordinator that splits a job into tiles, and every worker that renders
//! them. Sharing this one function is what lets a tile render identically wherever it runs.

use crate::error::{Result, SceneError};
use crate::load::{Limits, LoadedScene};
use crate::scene_file::Integrator;
use std::path::Path;

/// A rectangle of pixels, from the top-left corner of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// What a render may change of the scene's own settings; `None` keeps the scene's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderOptions {
    pub variant: Option<String>,
    pub integrator: Option<Integrator>,
    pub samples_per_pixel: Option<u32>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Keep the 81-band spectral radiance of every pixel.
    pub spectral: bool,
    /// The tile edge in pixels; `None` chooses one (see [`auto_tile`]).
    pub tile: Option<u32>,
}

/// The resolved render.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub width: u32,
    pub height: u32,
    pub variant: Option<String>,
    pub integrator: Integrator,
    pub samples_per_pixel: u32,
    pub max_depth: u32,
    pub seed: u64,
    pub spectral: bool,
    /// Whether the scene has a sky. Its tiles then carry each pixel's sky coverage (the fraction
    /// of its camera samples that saw the sky), so the Retinex can keep the sky from becoming
    /// the white.
    pub sky: bool,
    pub tile: u32,
    /// The tiles in row-major order; a tile's index is its place here.
    pub tiles: Vec<Rect>,
}

/// A tile edge that gives an image of `width × height` about 48 tiles or more (so each of
/// several workers gets several, and a lost worker costs little), a multiple of 16 between 16
/// and 256.
pub fn auto_tile(width: u32, height: u32) -> u32 {
    let edge = ((f64::from(width) * f64::from(height) / 48.0).sqrt() as u32) / 16 * 16;
    edge.clamp(16, 256)
}

/// How many tiles of edge `tile` cover `width × height`.
pub fn tile_count(width: u32, height: u32, tile: u32) -> u32 {
    let tile = tile.max(1);
    width.div_ceil(tile) * height.div_ceil(tile)
}

/// Tile `index` of `tiles(width, height, tile)`, computed directly.
pub fn tile_rect(width: u32, height: u32, tile: u32, index: u32) -> Option<Rect> {
    let edge = tile.max(1);
    let across = width.div_ceil(edge);
    if index >= tile_count(width, height, tile) {
        return None;
    }
    let (x, y) = ((index % across) * edge, (index / across) * edge);
    Some(Rect { x, y, width: edge.min(width - x), height: edge.min(height - y) })
}

/// The tiles of edge `tile` covering `width × height`, row-major.
pub fn tiles(width: u32, height: u32, tile: u32) -> Vec<Rect> {
    let tile = tile.max(1);
    (0..height)
        .step_by(tile as usize)
        .flat_map(|y| {
            (0..width).step_by(tile as usize).map(move |x| Rect {
                x,
                y,
                width: tile.min(width - x),
                height: tile.min(height - y),
            })
        })
        .collect()
}

impl Plan {
    /// Resolves `options` against `scene` (whose file is `path`, for messages), within `limits`.
    pub fn new(
        scene: &LoadedScene,
        options: &RenderOptions,
        limits: &Limits,
        path: &Path,
    ) -> Result<Plan> {
        let invalid = |place: &str, problem: String| SceneError::Invalid {
            path: path.to_owned(),
            place: place.to_owned(),
            problem,
        };
        let width = options.width.unwrap_or(scene.camera.width);
        let height = options.height.unwrap_or(scene.camera.height);
        let pixels = u64::from(width) * u64::from(height);
        if width == 0 || height == 0 {
            return Err(invalid(
                "width/height",
                format!("{width}×{height} pixels; an image needs at least 1×1"),
            ));
        }
        if pixels > limits.max_pixels {
            return Err(SceneError::Limit {
                path: path.to_owned(),
                what: format!("the image ({width}×{height})"),
                value: pixels,
                limit: limits.max_pixels,
                fix: "render a smaller image, or raise the pixel limit (--max-pixels)".into(),
            });
        }
        let render = &scene.file.render;
        let samples_per_pixel = options.samples_per_pixel.unwrap_or(render.samples_per_pixel);
        if samples_per_pixel == 0 {
            return Err(invalid("samples_per_pixel", "0 samples per pixel; use at least 1".into()));
        }
        if samples_per_pixel > limits.max_samples_per_pixel {
            return Err(SceneError::Limit {
                path: path.to_owned(),
                what: "samples_per_pixel".into(),
                value: samples_per_pixel.into(),
                limit: limits.max_samples_per_pixel.into(),
                fix: "use fewer samples per pixel, or raise the limit (--max-spp)".into(),
            });
        }
        if let Some(v) = &options.variant
            && !scene.file.variants.contains_key(v)
        {
            let known: Vec<&str> = scene.file.variants.keys().map(String::as_str).collect();
            let known = if known.is_empty() { "none".to_owned() } else { known.join(", ") };
            return Err(invalid(
                "variant",
                format!("unknown variant `{v}`; the scene defines {known}"),
            ));
        }
        let tile = match options.tile {
            Some(0) => return Err(invalid("tile", "a tile of 0 pixels; use at least 1".into())),
            Some(t) => t,
            None => auto_tile(width, height),
        };
        Ok(Plan {
            width,
            height,
            variant: options.variant.clone(),
            integrator: options.integrator.unwrap_or(render.integrator),
            samples_per_pixel,
            max_depth: render.max_depth,
            seed: render.seed,
            spectral: options.spectral,
            sky: scene.lights.iter().any(|l| matches!(l, crate::load::ResolvedLight::Sky { .. })),
            tile,
            tiles: tiles(width, height, tile),
        })
    }

    /// The scene with the plan's image size on its camera.
    pub fn apply(&self, scene: &mut LoadedScene) {
        scene.camera.width = self.width;
        scene.camera.height = self.height;
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_tile_computed_directly_is_the_listed_one() {
        for (w, h, t) in [(960, 540, 64), (17, 5, 16), (1, 1, 16), (256, 256, 16)] {
            let listed = super::tiles(w, h, t);
            assert_eq!(super::tile_count(w, h, t) as usize, listed.len());
            for (i, r) in listed.iter().enumerate() {
                assert_eq!(super::tile_rect(w, h, t, i as u32), Some(*r));
            }
            assert_eq!(super::tile_rect(w, h, t, listed.len() as u32), None);
        }
    }

    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        for (w, h, t) in [(100, 37, 16), (64, 64, 64), (1, 1, 256), (960, 540, 96)] {
            let mut seen = vec![0u8; (w * h) as usize];
            for r in tiles(w, h, t) {
                assert!(r.width >= 1 && r.height >= 1 && r.width <= t && r.height <= t);
                for y in r.y..r.y + r.height {
                    for x in r.x..r.x + r.width {
                        seen[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}×{h} by {t}");
        }
    }

    #[test]
    fn automatic_tiles_give_several_per_worker() {
        for (w, h) in [(960, 540), (1920, 1080), (320, 180), (4096, 4096)] {
            let t = auto_tile(w, h);
            assert!(t.is_multiple_of(16) && (16..=256).contains(&t));
            let n = tiles(w, h, t).len();
            assert!(n >= 40 || t == 16, "{w}×{h}: {n} tiles of {t}");
        }
    }
}
