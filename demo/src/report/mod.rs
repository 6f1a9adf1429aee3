//! The demo's analysis and report. From the renders fetched (as rendered and as seen) it writes
//! labelled contact sheets, a CIEDE2000 map between the two hypotheses, and a report (Markdown
//! and JSON) of every image, its scene, light, parameters and render time, and the mean colour
//! of each stone under each light as rendered and as seen.
//!
//! **How colours are compared.** A stone's colour in a render is the mean absolute XYZ over the
//! inner 60 % of its square, made relative to the white tile of the same render (Y = 1 for the
//! tile) and expressed in CIELAB with the D65 display white: what a camera balanced for daylight
//! and exposed for the white card shows. The seen image is already relative XYZ with a D65
//! white. The reference is the D65 render; the paper's claim is that, under another light, the
//! seen image comes closer to it than the unfiltered render does. The seen image is also
//! compared with the D65 render's own seen image: what an observer sees under the light
//! against what they see in daylight (under A, a warmth people keep).
//!
//! The facade's CIEDE2000 map compares the as-found and cleaned renders pixel by pixel in CIELAB
//! relative to the luminance of a perfect white horizontal surface under the same light (E_h/π)
//! with a D65 white; pixels that see the sky are left out.
//!
//! The sheets: the facade's hypotheses ([`facade`]), what cleaning changes ([`facade`]), the
//! stone experiment and its boards ([`stones`]), the photo block ([`block`]); the report's
//! Markdown form is [`markdown`]. The floodlit grid's numbers come from the caller, which
//! computes them as `restauro illuminance` does ([`Floodlighting`]).

mod block;
mod facade;
mod markdown;
mod renders;
mod stones;
mod sun_study;

pub use facade::CleaningDifference;
pub use stones::{INNER_FRACTION, Measured, StoneColour};

use crate::error::{DemoError, Result};
use crate::plan::{Job, Kind, Size};
use crate::scenes::samples::{self, PixelRect, SAMPLES, WHITE_REFLECTANCE};
use crate::sheet::Rgb8;
use restauro_image::image_files::{PngPixels, write_png};
use restauro_scene::load::LoadedScene;
use restauro_scene::scene_file::Integrator;
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A finished render, as the report lists it.
#[derive(Serialize)]
pub struct RenderRecord {
    pub job: String,
    pub scene: String,
    pub variant: Option<String>,
    pub lights: Vec<String>,
    /// The scene file's keyword (`path`, `whitted`); the Markdown shows its name.
    pub integrator: Integrator,
    pub width: u32,
    pub height: u32,
    /// With a noise target, the most a pixel takes.
    pub samples_per_pixel: u32,
    /// Adaptive sampling's noise target, when the render had one.
    pub noise_target: Option<f32>,
    pub max_depth: u32,
    /// How the seen image was made ([`seen_method`]).
    pub retinex: String,
    /// From the job's first tile to its results written (s).
    pub render_s: f64,
    pub files: Vec<String>,
}

/// A render fetched from the cluster: its record, and the folder its files are in.
pub struct Finished {
    pub record: RenderRecord,
    pub dir: PathBuf,
}

/// One image the demo wrote, relative to the output folder, and what it shows.
#[derive(Serialize)]
pub struct Image {
    pub file: String,
    pub what: String,
}

#[derive(Serialize)]
pub struct SampleRegion {
    pub label: &'static str,
    pub stone: &'static str,
    pub state: &'static str,
    /// The averaged pixels of the sample renders.
    pub rect: PixelRect,
}

/// The floodlit facade's calculation grid, as a lighting designer reads it.
#[derive(Serialize)]
pub struct Floodlighting {
    pub scene: String,
    pub grid: String,
    pub points: usize,
    pub samples_per_point: u32,
    pub min_lux: f64,
    pub mean_lux: f64,
    pub max_lux: f64,
    /// E_min / E_mean.
    pub uniformity: f64,
    /// The false-colour map, the points' table and the document (`restauro.illuminance/1`).
    pub map: String,
    pub table: String,
    pub document: String,
}

impl Floodlighting {
    /// The false-colour map, as the report lists it among the images.
    fn map_image(&self) -> Image {
        Image {
            file: self.map.clone(),
            what: format!(
                "the floodlit bay ({}): illuminance in false colour, isolines, lux scale",
                self.grid
            ),
        }
    }
}

#[derive(Serialize)]
pub struct Report {
    pub schema: &'static str,
    pub quick: bool,
    pub workers: usize,
    pub total_s: f64,
    pub soot_fraction: f64,
    pub white_reflectance: f64,
    /// Every image written, relative to the output folder.
    pub images: Vec<Image>,
    pub renders: Vec<RenderRecord>,
    pub samples: Vec<SampleRegion>,
    pub stones: Vec<StoneColour>,
    pub cleaning: Vec<CleaningDifference>,
    pub floodlighting: Floodlighting,
}

/// The run as a whole: how it was asked for and how long it took.
pub struct Run {
    pub quick: bool,
    pub workers: usize,
    /// From the start of the command to the end of the analysis (s).
    pub total_s: f64,
}

impl Report {
    /// The report of a run: the analysis's images (then the floodlit map), the renders, the
    /// averaged squares of the sample board, the stones, the cleaning and the floodlighting.
    pub fn new(
        run: Run,
        size: &Size,
        analysis: Analysis,
        finished: Vec<Finished>,
        floodlighting: Floodlighting,
    ) -> Report {
        let mut images = analysis.images;
        images.push(floodlighting.map_image());
        Report {
            schema: "restauro.demo/1",
            quick: run.quick,
            workers: run.workers,
            total_s: run.total_s,
            soot_fraction: 0.3,
            white_reflectance: WHITE_REFLECTANCE,
            images,
            renders: finished.into_iter().map(|f| f.record).collect(),
            samples: sample_regions(size),
            stones: analysis.stones,
            cleaning: analysis.cleaning,
            floodlighting,
        }
    }

    /// Writes `report.md` and `report.json` into `out`; returns the Markdown's path.
    pub fn write(&self, out: &Path) -> Result<PathBuf> {
        let md_path = out.join("report.md");
        let json_path = out.join("report.json");
        crate::plan::write_file(&md_path, markdown::markdown(self).as_bytes())?;
        let json = serde_json::to_string_pretty(self)? + "\n";
        crate::plan::write_file(&json_path, json.as_bytes())?;
        Ok(md_path)
    }
}

/// The squares of the sample board whose pixels are averaged, in the sample renders.
fn sample_regions(size: &Size) -> Vec<SampleRegion> {
    SAMPLES
        .iter()
        .map(|s| SampleRegion {
            label: s.label,
            stone: s.stone,
            state: s.state,
            rect: samples::pixel_rect(s, size.samples.0, size.samples.1, INNER_FRACTION),
        })
        .collect()
}

/// How the seen images were made, as each render's record says.
pub fn seen_method() -> String {
    format!(
        "adapted to the light each render measured: CAT16 with CAM16's degree of adaptation and \
         a blue bias, mesopic below 5 cd/m², sunlit and shadowed surfaces adapted apart \
         (framework weight {}, plane weight {}); lightness by Brownian paths from the known \
         white, 20 per pixel, the white an area, the sky passed over, seed 0",
        restauro_spectral::retinex::DEFAULT_FRAMEWORK_WEIGHT,
        restauro_spectral::seen::DEFAULT_PLANE_WEIGHT,
    )
}

/// `path` relative to the output folder, as the report names files.
pub fn relative(out: &Path, path: &Path) -> String {
    path.strip_prefix(out).unwrap_or(path).display().to_string()
}

/// What the analysis found: the images it listed and wrote, the stones' colours and what
/// cleaning changes on the facade.
pub struct Analysis {
    pub images: Vec<Image>,
    pub stones: Vec<StoneColour>,
    pub cleaning: Vec<CleaningDifference>,
}

/// Reads the renders back and writes the contact sheets into `out/sheets/`: the facade as found
/// and cleaned, the CIEDE2000 map between them, the stone experiment, the boards and the photo
/// block. `scenes` are the jobs' scenes, loaded.
pub fn analyse(
    out: &Path,
    size: &Size,
    jobs: &[Job],
    finished: &[Finished],
    scenes: &BTreeMap<PathBuf, LoadedScene>,
) -> Result<Analysis> {
    let mut images = render_files(jobs, finished);
    let renders = renders::Renders::read(jobs, finished)?;
    images.push(facade::hypotheses_sheet(out, size, &renders)?);
    let (cleaning, sheet) = facade::cleaning(out, size, &renders, scenes)?;
    images.push(sheet);
    let (stones, sheet) = stones::experiment(out, size, &renders)?;
    images.push(sheet);
    images.push(stones::boards_sheet(out, size, &renders)?);
    let block = renders.block.as_ref().ok_or(DemoError::MissingBlock)?;
    images.push(block::photo_block_sheet(out, size, block)?);
    images.push(sun_study::sun_study_sheet(out, jobs, finished)?);
    Ok(Analysis { images, stones, cleaning })
}

/// Every file the renders wrote, with what it holds.
fn render_files(jobs: &[Job], finished: &[Finished]) -> Vec<Image> {
    let mut images = Vec::new();
    for (job, f) in jobs.iter().zip(finished) {
        for file in &f.record.files {
            let what = if matches!(job.kind, Kind::Grid) {
                "the floodlit bay's grid: illuminance (Y in lux), row 0 direct, row 1 indirect, \
                 OpenEXR"
            } else if file.ends_with("-retinex.exr") {
                "as seen, adapted to its light: XYZ relative to a D65 white (Y = 1), OpenEXR"
            } else if file.ends_with("-retinex.png") {
                "as seen, adapted to its light, sRGB"
            } else if file.ends_with(".exr") {
                "as rendered: absolute XYZ (Y in cd/m²), OpenEXR"
            } else {
                "as rendered, sRGB (automatic exposure)"
            };
            images.push(Image { file: file.clone(), what: what.to_owned() });
        }
    }
    images
}

/// Writes a contact sheet as `out/sheets/<name>` (sRGB PNG); returns it as the report lists it.
fn write_sheet(out: &Path, name: &str, image: &Rgb8, what: &str) -> Result<Image> {
    let path = out.join("sheets").join(name);
    write_png(
        &path,
        image.width as usize,
        image.height as usize,
        &PngPixels::Eight(image.data.clone()),
        RgbSpace::Srgb,
    )
    .map_err(|source| DemoError::WriteImage { path: path.clone(), source })?;
    Ok(Image { file: relative(out, &path), what: what.to_owned() })
}
