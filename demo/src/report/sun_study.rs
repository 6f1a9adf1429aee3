//! The sun study's contact sheet: the facade as found and cleaned at every hour of the summer
//! day, as a person there sees it (each frame adapted to its own light).

use super::{Image, write_sheet};
use crate::error::{DemoError, Result};
use crate::picture::picture;
use crate::plan::{Job, Kind};
use crate::report::Finished;
use crate::sheet::Grid;
use restauro_image::image_files::read_exr;
use restauro_spectral::display::Exposure;
use std::path::Path;

/// The width of a frame on the sheet.
const CELL_WIDTH: u32 = 192;

/// The sheet of the sun study's renders among `jobs`: a row per hypothesis, a column per hour.
pub fn sun_study_sheet(out: &Path, jobs: &[Job], finished: &[Finished]) -> Result<Image> {
    let mut cells = Vec::new();
    let mut row_labels = Vec::new();
    let mut column_labels = Vec::new();
    for (job, f) in jobs.iter().zip(finished) {
        let Kind::SunStudy { variant } = job.kind else { continue };
        let mut row = Vec::new();
        for index in 0..job.frames.len() {
            let path = f.dir.join(format!("{}-{index:04}-retinex.exr", f.record.job));
            let seen = read_exr(&path, usize::MAX)
                .map_err(|source| DemoError::ReadImage { path: path.clone(), source })?;
            row.push(Some(picture(&seen, Exposure::Relative)));
        }
        if column_labels.is_empty() {
            column_labels = job.frames.iter().map(|frame| frame.label.clone()).collect();
        }
        row_labels.push(variant.replace('-', " "));
        cells.push(row);
    }
    let sheet = Grid {
        title: "A summer day at the theatre, as seen: the facade as found and cleaned, hour by hour",
        column_labels,
        row_labels,
        cells,
        captions: Vec::new(),
        cell_width: CELL_WIDTH,
        footer: vec![
            "15 July at 45.7371 N, 7.3228 E (CEST): the sun by NREL's SPA, 100 000 lux, and a clear sky".into(),
            "of 15 000 lux. Each frame is seen adapted to its own light. As found: derived soiling.".into(),
        ],
    }
    .render();
    write_sheet(
        out,
        "sun-study.png",
        &sheet,
        "contact sheet: the facade as found and cleaned at every hour of the summer day, as seen",
    )
}
