//! The photo block's contact sheet: pudding-stone blocks, flat and with a photograph as detail
//! over the measured spectrum, as rendered and as a person sees them.

use super::renders::Pair;
use super::{Image, write_sheet};
use crate::error::Result;
use crate::picture::picture;
use crate::plan::Size;
use crate::scenes::photo_block;
use crate::sheet::Grid;
use restauro_spectral::display::Exposure;
use std::path::Path;

/// The photo block's contact sheet: the render and what a person sees.
pub fn photo_block_sheet(out: &Path, size: &Size, block: &Pair) -> Result<Image> {
    let exposure = Exposure::Automatic { key: 0.18 };
    let width = 2 * size.sheet_cell;
    let labels: Vec<&str> = photo_block::BLOCKS.iter().map(|b| b.3).collect();
    let sheet = Grid {
        title: "Pudding stone: a photograph as detail over the measured spectrum",
        column_labels: vec![labels.join(" | ")],
        row_labels: vec!["as rendered".into(), "as seen".into()],
        cells: vec![
            vec![Some(picture(&block.rendered, exposure).resized_to_width(width))],
            vec![Some(picture(&block.seen, Exposure::Relative).resized_to_width(width))],
        ],
        captions: Vec::new(),
        cell_width: width,
        footer: vec![
            "Each block reflects the conglomerate's measured spectrum (USGS/ECOSTRESS), as found with".into(),
            "30 % soot proxy (derived). The photo blocks vary it by a photograph's relative luminance,".into(),
            "rho(lambda, x) = rho_m(lambda) Y(x)/mean Y: the same colour, the stones' detail. Photo: Gravel04,".into(),
            "CC0Textures (ambientCG), CC0, via scikit-image. Summer afternoon sun and clear sky.".into(),
        ],
    }
    .render();
    write_sheet(
        out,
        "block.png",
        &sheet,
        "contact sheet: pudding-stone blocks, flat and with a photograph as detail, as found and cleaned",
    )
}
