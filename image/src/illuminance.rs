//! A calculation of the scene's grids read as a lighting designer reads it: the grids' EXR
//! (one column per sensor point, row 0 direct and row 1 indirect, Y in lux; see
//! [`crate::results::write_grid_results`]) turned into per-grid points and their minimum, mean,
//! maximum and uniformity U₀ = E_min/E_mean (EN 12464-1), and written as
//!
//! * `illuminance.json` (schema [`SCHEMA`]): per grid its name, its points (`position`,
//!   `normal`, `lux`, `direct_lux`, `indirect_lux`) and `min_lux`, `mean_lux`, `max_lux` and
//!   `uniformity`, and for a rectangle its `divisions` and `cell_area_m2`;
//! * `<grid>.csv`: the same points, one per row;
//! * `<grid>.png`: the illuminance in false colour with isolines and a lux scale (a rectangle's
//!   cells with `u` to the right and `v` up; a list of points as a strip in its order).
//!
//! `restauro illuminance` and the studio both read a calculation with this module, so their
//! figures are the same by construction.

use crate::atomic_file;
use crate::error::ImageError;
use crate::false_colour::{FalseColour, LEGEND_PX, Range, Scale, Unit, nice_above, picture};
use crate::image_files::{PngPixels, XyzImage, write_png};
use restauro_scene::load::LoadedScene;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The JSON document's schema.
pub const SCHEMA: &str = "restauro.illuminance/1";

/// The name of the JSON document in the folder [`write_documents`] writes.
pub const DOCUMENT: &str = "illuminance.json";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Document {
    pub schema: String,
    pub scene: String,
    pub variant: Option<String>,
    pub grids: Vec<GridResult>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridResult {
    pub name: String,
    /// For a rectangle: its cells along u and along v.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub divisions: Option<[u32; 2]>,
    /// For a rectangle: the area of each cell (m²), so that Σ E·A is the flux it receives.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_area_m2: Option<f64>,
    pub min_lux: f64,
    pub mean_lux: f64,
    pub max_lux: f64,
    /// E_min / E_mean (0 when the mean is 0).
    pub uniformity: f64,
    pub points: Vec<PointResult>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    pub position: [f64; 3],
    pub normal: [f64; 3],
    pub lux: f32,
    pub direct_lux: f32,
    pub indirect_lux: f32,
}

/// The files [`write_documents`] wrote: per grid its CSV and its map, and the JSON document.
pub struct Written {
    pub per_grid: Vec<[PathBuf; 2]>,
    pub json: PathBuf,
}

/// Writes `document` (whose JSON text is `json`) into `dir`: [`DOCUMENT`], and per grid
/// `<grid>.csv` and its false-colour map `<grid>.png`.
pub fn write_documents(dir: &Path, document: &Document, json: &str) -> Result<Written, ImageError> {
    std::fs::create_dir_all(dir).map_err(|e| ImageError::Io { path: dir.into(), error: e })?;
    let mut per_grid = Vec::with_capacity(document.grids.len());
    for grid in &document.grids {
        let csv = dir.join(format!("{}.csv", grid.name));
        atomic_file::write(&csv, csv_text(grid).as_bytes())
            .map_err(|e| ImageError::Io { path: csv.clone(), error: e })?;
        let png = dir.join(format!("{}.png", grid.name));
        write_map(&png, grid)?;
        per_grid.push([csv, png]);
    }
    // Last, so that a reader who finds the document finds the maps it names.
    let json_path = dir.join(DOCUMENT);
    atomic_file::write(&json_path, json.as_bytes())
        .map_err(|e| ImageError::Io { path: json_path.clone(), error: e })?;
    Ok(Written { per_grid, json: json_path })
}

/// Each grid's points from the EXR's columns (row 0 direct, row 1 indirect; Y is lux), placed
/// in the scene file's coordinates (a georeferenced scene's `origin` added back). `exr` names
/// the file in a refusal.
pub fn grid_results(
    scene: &LoadedScene,
    image: &XyzImage,
    exr: &Path,
) -> Result<Vec<GridResult>, ImageError> {
    let grids = &scene.grids;
    let total: usize = grids.iter().map(|g| g.points.len()).sum();
    if image.width != total || image.height != 2 {
        return Err(ImageError::GridsMismatch {
            path: exr.into(),
            width: image.width,
            height: image.height,
            points: total,
        });
    }
    let mut column = 0;
    let mut out = Vec::with_capacity(grids.len());
    for g in grids {
        let points: Vec<PointResult> = g
            .points
            .iter()
            .map(|&position| {
                let direct_lux = image.pixels[column][1];
                let indirect_lux = image.pixels[total + column][1];
                column += 1;
                PointResult {
                    position: restauro_scene::origin::to_file(position, scene.origin_m),
                    normal: g.normal,
                    lux: direct_lux + indirect_lux,
                    direct_lux,
                    indirect_lux,
                }
            })
            .collect();
        let lux = || points.iter().map(|p| f64::from(p.lux));
        let min_lux = lux().fold(f64::INFINITY, f64::min);
        let max_lux = lux().fold(f64::NEG_INFINITY, f64::max);
        let mean_lux = lux().sum::<f64>() / points.len() as f64;
        let uniformity = if mean_lux > 0.0 { min_lux / mean_lux } else { 0.0 };
        out.push(GridResult {
            name: g.name.clone(),
            divisions: g.divisions,
            cell_area_m2: g.cell_area_m2,
            min_lux,
            mean_lux,
            max_lux,
            uniformity,
            points,
        });
    }
    Ok(out)
}

/// The grid's table: a header, then a row per point.
pub fn csv_text(grid: &GridResult) -> String {
    let mut s =
        String::from("index,x_m,y_m,z_m,normal_x,normal_y,normal_z,lux,direct_lux,indirect_lux\n");
    for (i, p) in grid.points.iter().enumerate() {
        let [x, y, z] = p.position;
        let [nx, ny, nz] = p.normal;
        let _ = writeln!(
            s,
            "{i},{x},{y},{z},{nx},{ny},{nz},{},{},{}",
            p.lux, p.direct_lux, p.indirect_lux
        );
    }
    s
}

/// A grid's false-colour map as 8-bit sRGB: its width, its height with the legend, the pixels.
pub struct Map {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

/// The false-colour map: the points' illuminance interpolated bilinearly between them (their
/// cells' centres), on a linear scale from 0 to a round value above the maximum, in ten bands,
/// with the lux scale ([`LEGEND_PX`] rows) below.
pub fn map(grid: &GridResult) -> Map {
    let [n_u, n_v] = grid.divisions.unwrap_or([grid.points.len() as u32, 1]).map(|n| n as usize);
    // Cells big enough that the map is about 400 px wide (and the legend fits).
    let cell = 400usize.div_ceil(n_u).clamp(1, 64).max(if n_v > 1 { 1 } else { 8 });
    let (width, height) = (n_u * cell, n_v * cell);
    let value = |i: usize, j: usize| f64::from(grid.points[j * n_u + i].lux);
    let mut pixels = Vec::with_capacity(width * height);
    for py in 0..height {
        // v runs up the picture.
        let fy = ((height - 1 - py) as f64 + 0.5) / cell as f64 - 0.5;
        let (j0, ty) = split(fy, n_v);
        for px in 0..width {
            let (i0, tx) = split((px as f64 + 0.5) / cell as f64 - 0.5, n_u);
            let (i1, j1) = ((i0 + 1).min(n_u - 1), (j0 + 1).min(n_v - 1));
            let lux = (value(i0, j0) * (1.0 - tx) + value(i1, j0) * tx) * (1.0 - ty)
                + (value(i0, j1) * (1.0 - tx) + value(i1, j1) * tx) * ty;
            pixels.push([0.0, lux as f32, 0.0]);
        }
    }
    let fc = FalseColour {
        scale: Scale::Linear,
        range: Range { min: 0.0, max: scale_top_lux(grid.max_lux) },
        bands: 10,
        unit: Unit::Lux,
    };
    Map { width, height: height + LEGEND_PX, rgb: picture(&pixels, width, &fc) }
}

/// The top of a map's scale: the maximum rounded up to a whole step of 1, 2 or 5 times a power
/// of ten, about a tenth of it (1 lx when all is dark).
pub fn scale_top_lux(max_lux: f64) -> f64 {
    if max_lux > 0.0 {
        let step = nice_above(max_lux / 10.0);
        (max_lux / step).ceil() * step
    } else {
        1.0
    }
}

fn write_map(path: &Path, grid: &GridResult) -> Result<(), ImageError> {
    let Map { width, height, rgb } = map(grid);
    write_png(
        path,
        width,
        height,
        &PngPixels::Eight(rgb),
        restauro_spectral::rgb_space::RgbSpace::Srgb,
    )
}

/// The cell below `f` (clamped to the grid of `n`) and the fraction of the way to the next.
fn split(f: f64, n: usize) -> (usize, f64) {
    let f = f.clamp(0.0, (n - 1) as f64);
    let i = (f.floor() as usize).min(n.saturating_sub(2));
    (i, (f - i as f64).clamp(0.0, 1.0))
}
