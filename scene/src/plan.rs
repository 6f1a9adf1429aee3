//! A render plan: a loaded scene and the options of one render (variant, integrator, samples,
//! size, tiles) resolved and checked once, the same way in every process — the client that
//! renders in-process, the coordinator that splits a job into tiles, and every worker that renders
//! them. Sharing this one function is what lets a tile render identically wherever it runs.

use crate::error::{Result, SceneError};
use crate::load::{Limits, LoadedScene};
use crate::scene_file::Integrator;
use serde::{Deserialize, Serialize};
use std::num::NonZeroU32;
use std::path::Path;

/// A rectangle of pixels, from the top-left corner of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// What a render may change of the scene's own settings; `None` keeps the scene's. The counts
/// cannot be zero: each edge that makes one (the command line, the wire, the studio's request
/// as JSON) refuses a zero there, naming its own field, so that past it they are checked values.
/// Any field may be left out; an unknown one is refused (a misspelt option would otherwise be
/// silently the scene's).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderOptions {
    pub variant: Option<String>,
    pub integrator: Option<Integrator>,
    #[serde(deserialize_with = "count")]
    pub samples_per_pixel: Option<NonZeroU32>,
    #[serde(deserialize_with = "count")]
    pub width: Option<NonZeroU32>,
    #[serde(deserialize_with = "count")]
    pub height: Option<NonZeroU32>,
    /// Keep the 81-band spectral radiance of every pixel.
    pub spectral: bool,
    /// The tile edge in pixels; `None` chooses one (see [`auto_tile`]).
    #[serde(deserialize_with = "count")]
    pub tile: Option<NonZeroU32>,
    /// Compute the illuminance at the scene's calculation grids instead of the camera's image
    /// (see [`Plan::grids`]). Absent in jobs stored before grids existed.
    pub grids: bool,
    /// The adaptive sampling's noise target ([`Plan::noise_target`]); `Some(0.0)` renders every
    /// pixel at the full count whatever the scene says.
    pub noise_target: Option<f32>,
}

/// Why a count of [`RenderOptions`] cannot be 0, and what to give instead.
pub const ZERO_COUNT: &str = "0; use at least 1, or leave it out for the scene's";

/// A count of [`RenderOptions`] read from JSON: a zero is refused in [`ZERO_COUNT`]'s words, as
/// every other edge refuses it (the reader names the field).
fn count<'de, D>(d: D) -> std::result::Result<Option<NonZeroU32>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    let value: Option<u32> = Option::deserialize(d)?;
    value
        .map(|v| NonZeroU32::new(v).ok_or_else(|| serde::de::Error::custom(ZERO_COUNT)))
        .transpose()
}

impl RenderOptions {
    /// The quick render a scene opened in the studio gets first (160 × 90 px, 1 sample per
    /// pixel), so that the studio holds it and shows it at once.
    pub fn quick_preview() -> Self {
        Self {
            samples_per_pixel: Some(NonZeroU32::MIN),
            width: NonZeroU32::new(160),
            height: NonZeroU32::new(90),
            ..Self::default()
        }
    }
}

/// The resolved render.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub width: u32,
    pub height: u32,
    pub variant: Option<String>,
    pub integrator: Integrator,
    pub samples_per_pixel: u32,
    pub max_depth: u32,
    pub seed: u64,
    pub spectral: bool,
    /// Whether the scene has a sky or an area luminaire, a light source the camera can see. Its
    /// tiles then carry each pixel's sky coverage (the fraction of its camera samples that saw
    /// a light source), so the Retinex can keep the sky or a lamp from becoming the white.
    pub sky: bool,
    /// Whether the scene has point or distant lights. Its tiles then carry which of them light
    /// each pixel (a mask of [`LIT_BITS`] bits), so the Retinex can adapt to each framework of
    /// illumination (the sunlit stone, the sky-lit shadow) apart. Absent in plans stored
    /// before it existed: their images are adapted as one framework.
    #[serde(default)]
    pub lit: bool,
    /// Whether the tiles carry each pixel's adapting white: what a perfect white diffuser at
    /// its surface would send back under all the scene's light (X, Y, Z and the scotopic
    /// luminance), the light the seen image adapts to. Every image has it; a grid has none.
    /// Absent in plans stored before it existed: their images are seen by the Retinex alone.
    #[serde(default)]
    pub white: bool,
    /// The tile edge in pixels; the tiles follow from it and the image size ([`Plan::tile`]).
    pub tile: u32,
    /// The "image" is the scene's calculation grids: one column per sensor point (all the
    /// grids' points in file order), row 0 its direct and row 1 its indirect spectral
    /// irradiance, whose Y is illuminance in lux. Tiles of sensors run on the farm as tiles of
    /// pixels do, so the grids compute identically in-process and on any cluster.
    #[serde(default)]
    pub grids: bool,
    /// Adaptive sampling: each pixel stops once the standard error of its mean is below this
    /// fraction of its luminance, `samples_per_pixel` being the cap; 0 takes every sample.
    /// Never for a grid. Absent in plans stored before it existed: 0.
    #[serde(default)]
    pub noise_target: f32,
}

/// The lights with a bit of their own in a pixel's mask of the lights that light it (in the
/// scene's order, the sky not counted); lights beyond the last share its bit. 24, so that a
/// mask is an exact integer in an f32 image channel.
pub const LIT_BITS: usize = 24;

/// The rows of a grids plan: the direct irradiance, then the indirect.
pub const SENSOR_ROWS: u32 = 2;

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
    let count = u64::from(width.div_ceil(tile)) * u64::from(height.div_ceil(tile));
    u32::try_from(count).unwrap_or(u32::MAX)
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
    /// Whether pixels stop early by their own noise, so that tiles carry each pixel's count:
    /// never for a grid, whatever a plan from the wire says (as `Settings::adaptive` renders it).
    pub fn adaptive(&self) -> bool {
        self.noise_target > 0.0 && !self.grids
    }

    /// Resolves `options` against `scene` (whose file is `path`, for messages), within `limits`.
    pub fn new(
        scene: &LoadedScene,
        options: &RenderOptions,
        limits: &Limits,
        path: &Path,
    ) -> Result<Plan> {
        if let Some(v) = &options.variant
            && !scene.file.variants.contains_key(v)
        {
            let known: Vec<&str> = scene.file.variants.keys().map(String::as_str).collect();
            let known = if known.is_empty() { "none".to_owned() } else { known.join(", ") };
            return Err(SceneError::invalid(
                path,
                "variant",
                format!("unknown variant `{v}`; the scene defines {known}"),
            ));
        }
        let render = &scene.file.render;
        let (width, height) = if options.grids {
            let points: usize = scene.grids.iter().map(|g| g.points.len()).sum();
            if points == 0 {
                return Err(SceneError::invalid(
                    path,
                    "grids",
                    "the scene has no calculation grid; add a [[grids]] table (see \
                     docs/scene-format.md)",
                ));
            }
            (u32::try_from(points).unwrap_or(u32::MAX), SENSOR_ROWS)
        } else {
            (
                options.width.map_or(scene.camera.width, NonZeroU32::get),
                options.height.map_or(scene.camera.height, NonZeroU32::get),
            )
        };
        let plan = Plan {
            width,
            height,
            variant: options.variant.clone(),
            integrator: options.integrator.unwrap_or(render.integrator),
            samples_per_pixel: options
                .samples_per_pixel
                .map_or(render.samples_per_pixel, NonZeroU32::get),
            max_depth: render.max_depth,
            seed: render.seed,
            spectral: options.spectral,
            // A sensor sees no sky and has no frameworks of illumination.
            sky: !options.grids
                && scene.lights.iter().any(|l| {
                    matches!(
                        l,
                        crate::load::ResolvedLight::Sky { .. }
                            | crate::load::ResolvedLight::Area { .. }
                    )
                }),
            lit: !options.grids
                && scene
                    .lights
                    .iter()
                    .any(|l| !matches!(l, crate::load::ResolvedLight::Sky { .. })),
            white: !options.grids,
            tile: options.tile.map(NonZeroU32::get).unwrap_or_else(|| match options.grids {
                // A strip two sensors high: about 48 tiles along it.
                true => width.div_ceil(48).next_multiple_of(16).clamp(16, 4096),
                false => auto_tile(width, height),
            }),
            grids: options.grids,
            // A sensor's estimate is not a pixel's: grids always take every sample.
            noise_target: match options.grids {
                true => 0.0,
                false => options.noise_target.unwrap_or(render.noise_target),
            },
        };
        plan.check(limits, path)?;
        Ok(plan)
    }

    /// Checks the plan against `limits`: what [`Plan::new`] refuses, and what a worker checks of
    /// a plan it is sent.
    pub fn check(&self, limits: &Limits, path: &Path) -> Result<()> {
        let (width, height, tile) = (self.width, self.height, self.tile);
        let invalid = |place: &str, problem: String| SceneError::invalid(path, place, problem);
        let limit = |what: String, value: u64, limit: u64, fix: &str| SceneError::Limit {
            path: path.to_owned(),
            what,
            value,
            limit,
            fix: fix.to_owned(),
        };
        let pixels = u64::from(width) * u64::from(height);
        if width == 0 || height == 0 {
            return Err(invalid(
                "width/height",
                format!("{width}×{height} pixels; an image needs at least 1×1"),
            ));
        }
        if pixels > limits.max_pixels {
            let fix = "render a smaller image, or raise the pixel limit (--max-pixels)";
            return Err(limit(
                format!("the image ({width}×{height})"),
                pixels,
                limits.max_pixels,
                fix,
            ));
        }
        if self.spectral && pixels > limits.max_spectral_pixels {
            let fix = "render a smaller image with --spectral, or raise the limit \
                       (--max-spectral-pixels)";
            let what = format!("the spectral image ({width}×{height})");
            return Err(limit(what, pixels, limits.max_spectral_pixels, fix));
        }
        if self.samples_per_pixel == 0 {
            return Err(invalid("samples_per_pixel", "0 samples per pixel; use at least 1".into()));
        }
        if self.samples_per_pixel > limits.max_samples_per_pixel {
            let fix = "use fewer samples per pixel, or raise the limit (--max-spp)";
            let (value, max) = (self.samples_per_pixel.into(), limits.max_samples_per_pixel.into());
            return Err(limit("samples_per_pixel".into(), value, max, fix));
        }
        if let Err(problem) = crate::scene_file::check_noise_target(self.noise_target) {
            return Err(invalid("noise_target", problem));
        }
        if self.max_depth > limits.max_depth {
            let fix = "use fewer bounces (render.max_depth), or raise the limit (--max-depth)";
            let (value, max) = (self.max_depth.into(), limits.max_depth.into());
            return Err(limit("max_depth".into(), value, max, fix));
        }
        if tile < limits.min_tile.max(1) {
            return Err(invalid(
                "tile",
                format!(
                    "a tile of {tile} px is smaller than the smallest tile edge, {} px; use a \
                     larger tile, or lower the limit (--min-tile)",
                    limits.min_tile.max(1)
                ),
            ));
        }
        let tiles = u64::from(width.div_ceil(tile)) * u64::from(height.div_ceil(tile));
        if tiles > u64::from(limits.max_tiles) {
            let fix = "use a larger tile (--tile), or raise the limit (--max-tiles)";
            let what = format!("the number of tiles ({width}×{height} in tiles of {tile} px)");
            return Err(limit(what, tiles, limits.max_tiles.into(), fix));
        }
        Ok(())
    }

    /// How many tiles the image has.
    pub fn tile_count(&self) -> u32 {
        tile_count(self.width, self.height, self.tile)
    }

    /// Tile `index`, computed directly (a plan never lists its tiles).
    pub fn tile_rect(&self, index: u32) -> Option<Rect> {
        tile_rect(self.width, self.height, self.tile, index)
    }

    /// The tiles in row-major order, computed as they are read.
    pub fn tiles(&self) -> impl Iterator<Item = Rect> + '_ {
        (0..self.tile_count()).filter_map(|i| self.tile_rect(i))
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
