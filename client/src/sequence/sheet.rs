//! The contact sheet of a sequence: its frames as seen, small, in rows, each with its label
//! (the time of day, the date, the walk's second) under it, as a lighting designer lays out a
//! sun study. A long sequence shows evenly spaced frames, the first and the last among them.

use super::video::read_rgb_png;
use anyhow::Result;
use restauro_demo::sheet::{Grid, Rgb8};
use restauro_image::image_files::{PngPixels, write_png};
use restauro_spectral::rgb_space::RgbSpace;
use std::path::{Path, PathBuf};

/// The most frames a sheet shows.
const MOST: usize = 48;
/// Frames a row.
const COLUMNS: usize = 6;
/// The width of a frame on the sheet, pixels.
const CELL_WIDTH: u32 = 240;

/// Which of `count` frames the sheet shows: all of them, or `MOST` spread evenly.
fn shown(count: usize) -> Vec<usize> {
    if count <= MOST {
        return (0..count).collect();
    }
    (0..MOST).map(|k| (k * (count - 1) + (MOST - 1) / 2) / (MOST - 1)).collect()
}

/// Writes the sheet of `frames` (PNG paths with their labels) titled `title` to `path`.
pub fn write_sheet(path: &Path, title: &str, frames: &[(PathBuf, String)]) -> Result<()> {
    let chosen = shown(frames.len());
    let mut cells = Vec::new();
    let mut captions = Vec::new();
    for row in chosen.chunks(COLUMNS) {
        let mut cell_row = Vec::new();
        let mut caption_row = Vec::new();
        for &index in row {
            let (png, label) = &frames[index];
            let frame = read_rgb_png(png)?;
            cell_row.push(Some(Rgb8 {
                width: frame.width,
                height: frame.height,
                data: frame.data,
            }));
            caption_row.push(format!("{index:04}  {label}"));
        }
        cells.push(cell_row);
        captions.push(caption_row);
    }
    let footer = match chosen.len() < frames.len() {
        true => vec![format!("{} of {} frames, evenly spaced", chosen.len(), frames.len())],
        false => Vec::new(),
    };
    let sheet = Grid {
        title,
        column_labels: Vec::new(),
        row_labels: vec![String::new(); cells.len()],
        cells,
        captions,
        cell_width: CELL_WIDTH,
        footer,
    }
    .render();
    let (width, height) = (sheet.width as usize, sheet.height as usize);
    write_png(path, width, height, &PngPixels::Eight(sheet.data), RgbSpace::Srgb)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_sequence_shows_its_first_and_last_frames_evenly_spaced() {
        assert_eq!(shown(3), vec![0, 1, 2]);
        let many = shown(901);
        assert_eq!(many.len(), MOST);
        assert_eq!((many[0], many[MOST - 1]), (0, 900));
        assert!(many.windows(2).all(|w| (18..=21).contains(&(w[1] - w[0]))), "{many:?}");
    }
}
