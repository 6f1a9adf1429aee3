//! The paper's stone experiment (Rossi, Marini & Rizzi 2004, Fig. 12): each sample of the board
//! under CIE A, B, C and D65, measured as rendered and as seen against the D65 render (the
//! table of [`StoneColour`]s and its contact sheet), and the whole boards on a sheet of their
//! own.

use super::renders::{Pair, Renders};
use super::{Image, write_sheet};
use crate::error::Result;
use crate::picture::{crop_picture, picture};
use crate::plan::{ILLUMINANTS, Size};
use crate::scenes::samples::{self, PixelRect, SAMPLES, Sample};
use crate::sheet::{Grid, Rgb8};
use restauro_image::image_files::XyzImage;
use restauro_spectral::Lab;
use restauro_spectral::appearance::d65_white;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::Xyz;
use restauro_spectral::display::Exposure;
use serde::Serialize;
use std::path::Path;

/// The share of a sample square (per side) whose pixels are averaged: its edges, antialiased
/// against the board, are left out.
pub const INNER_FRACTION: f64 = 0.6;

/// The width of a sample's square on the stones' sheet.
const CROP: u32 = 96;

#[derive(Clone, Serialize)]
pub struct Measured {
    /// Mean XYZ over the square: absolute (cd/m²) as rendered, relative to a D65 white
    /// of Y = 1 after it.
    pub xyz: [f64; 3],
    /// CIELAB as described in the module documentation of [`crate::report`].
    pub lab: [f64; 3],
    /// The colour shown on an sRGB display.
    pub srgb_hex: String,
    /// ΔE00 to the same square of the D65 render as rendered (unfiltered).
    pub delta_e00_to_d65: f64,
    /// As seen only: ΔE00 to the same square of the D65 render as seen (its seen image
    /// output) — how far what an observer sees under this light is from what they see under
    /// daylight.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_e00_to_d65_seen: Option<f64>,
}

#[derive(Serialize)]
pub struct StoneColour {
    pub stone: &'static str,
    pub state: &'static str,
    pub illuminant: &'static str,
    pub before_retinex: Measured,
    pub after_retinex: Measured,
}

/// How the sample renders are measured: where the squares are, and the white tile's.
struct Board {
    size: (u32, u32),
    white: &'static Sample,
}

impl Board {
    fn new(size: &Size) -> Self {
        Board { size: size.samples, white: &SAMPLES[SAMPLES.len() - 1] }
    }

    /// The averaged pixels of a sample.
    fn rect(&self, s: &Sample) -> PixelRect {
        samples::pixel_rect(s, self.size.0, self.size.1, INNER_FRACTION)
    }

    /// The white tile's mean luminance in a render (cd/m²).
    fn white_y(&self, image: &XyzImage) -> f64 {
        mean(image, self.rect(self.white)).y
    }

    /// A sample's mean as rendered, and its CIELAB relative to the render's white tile.
    fn lab_rendered(&self, pair: &Pair, s: &Sample) -> (Xyz, Lab) {
        let white_y = self.white_y(&pair.rendered);
        let m = mean(&pair.rendered, self.rect(s));
        (m, Lab::from_xyz(m.scale(1.0 / white_y.max(1e-12)), d65_white()))
    }

    /// A sample's mean as seen (relative already), and its CIELAB.
    fn lab_seen(&self, pair: &Pair, s: &Sample) -> (Xyz, Lab) {
        let m = mean(&pair.seen, self.rect(s));
        (m, Lab::from_xyz(m, d65_white()))
    }
}

/// The mean XYZ over the pixels of `r`.
fn mean(image: &XyzImage, r: PixelRect) -> Xyz {
    let mut sum = [0.0f64; 3];
    let mut n = 0.0f64;
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            let p = image.pixels[y as usize * image.width + x as usize];
            for k in 0..3 {
                sum[k] += f64::from(p[k]);
            }
            n += 1.0;
        }
    }
    Xyz::from_array(sum.map(|v| v / n.max(1.0)))
}

/// A CIELAB colour (D65 white) as `#rrggbb` on an sRGB display.
fn hex(lab: Lab) -> String {
    let xyz = lab.to_xyz(d65_white());
    let image = XyzImage::new(1, 1, vec![[xyz.x as f32, xyz.y as f32, xyz.z as f32]]);
    let p = picture(&image, Exposure::Relative);
    format!("#{:02x}{:02x}{:02x}", p.data[0], p.data[1], p.data[2])
}

/// The colour of a square, measured against the D65 render's `reference` (as rendered) and,
/// for the seen image, also its `seen` reference.
fn measured(xyz: Xyz, lab: Lab, reference: Lab, seen: Option<Lab>) -> Measured {
    Measured {
        xyz: xyz.to_array(),
        lab: [lab.l, lab.a, lab.b],
        srgb_hex: hex(lab),
        delta_e00_to_d65: ciede2000(reference, lab),
        delta_e00_to_d65_seen: seen.map(|seen| ciede2000(seen, lab)),
    }
}

/// The table of every sample under every illuminant, and its contact sheet: each sample's
/// square as rendered (exposed for the white tile) and as seen, with its ΔE00 to D65.
pub fn experiment(out: &Path, size: &Size, renders: &Renders) -> Result<(Vec<StoneColour>, Image)> {
    let board = Board::new(size);
    let d65 = renders.stones("D65")?;
    let mut table = Vec::new();
    let mut cells: Vec<Vec<Option<Rgb8>>> = vec![Vec::new(); SAMPLES.len()];
    let mut captions: Vec<Vec<String>> = vec![Vec::new(); SAMPLES.len()];
    for illuminant in ILLUMINANTS {
        let pair = renders.stones(illuminant)?;
        let white_y = board.white_y(&pair.rendered);
        for (row, s) in SAMPLES.iter().enumerate() {
            let reference = board.lab_rendered(d65, s).1;
            let reference_seen = board.lab_seen(d65, s).1;
            let (before_xyz, before) = board.lab_rendered(pair, s);
            let (after_xyz, after) = board.lab_seen(pair, s);
            let before_m = measured(before_xyz, before, reference, None);
            let after_m = measured(after_xyz, after, reference, Some(reference_seen));
            // The squares as shown: the render exposed for the white tile, and the seen image.
            let r = samples::pixel_rect(s, size.samples.0, size.samples.1, 0.9);
            let exposure = Exposure::Absolute { white_cd_m2: white_y.max(1e-12) };
            cells[row].push(Some(crop_picture(&pair.rendered, r, exposure).resized_to_width(CROP)));
            cells[row]
                .push(Some(crop_picture(&pair.seen, r, Exposure::Relative).resized_to_width(CROP)));
            captions[row].push(format!("dE {:.1}", before_m.delta_e00_to_d65));
            captions[row].push(format!("dE {:.1}", after_m.delta_e00_to_d65));
            table.push(StoneColour {
                stone: s.stone,
                state: s.state,
                illuminant,
                before_retinex: before_m,
                after_retinex: after_m,
            });
        }
    }
    let image = write_sheet(
        out,
        "stones.png",
        &stones_sheet(cells, captions),
        "contact sheet: the stone experiment, each sample under A, B, C and D65, rendered and seen",
    )?;
    Ok((table, image))
}

/// The samples (rows) under each illuminant, rendered and seen (columns).
fn stones_sheet(cells: Vec<Vec<Option<Rgb8>>>, captions: Vec<Vec<String>>) -> Rgb8 {
    Grid {
        title: "Stone samples under CIE A, B, C and D65 (after Rossi, Marini & Rizzi 2004, Fig. 12)",
        column_labels: ILLUMINANTS.iter().flat_map(|i| [i.to_string(), format!("{i} seen")]).collect(),
        row_labels: SAMPLES.iter().map(|s| s.label.to_owned()).collect(),
        cells,
        captions,
        cell_width: CROP,
        footer: vec![
            "Each light gives the board 1000 lux from above. Rendered: the white tile is the reference".into(),
            "white (70 % of the display's), on a D65 display without adaptation. Seen: adapted to the light, as a person there sees it.".into(),
            "dE: CIEDE2000 to the same sample in the D65 render (Lab relative to the white tile, D65 white).".into(),
            "As found = stone + 30 % soot-proxy mixture (derived, not measured).".into(),
        ],
    }
    .render()
}

/// The boards themselves, whole, for the report: under each illuminant, rendered (exposed for
/// the white tile) and seen.
pub fn boards_sheet(out: &Path, size: &Size, renders: &Renders) -> Result<Image> {
    let board = Board::new(size);
    let mut boards = Vec::new();
    for illuminant in ILLUMINANTS {
        let pair = renders.stones(illuminant)?;
        let white_y = board.white_y(&pair.rendered);
        let exposure = Exposure::Absolute { white_cd_m2: white_y.max(1e-12) };
        boards.push(Some(picture(&pair.rendered, exposure).resized_to_width(300)));
        boards.push(Some(picture(&pair.seen, Exposure::Relative).resized_to_width(300)));
    }
    let grid = Grid {
        title: "The sample board under each illuminant: rendered and seen",
        column_labels: vec!["rendered".into(), "seen".into()],
        row_labels: ILLUMINANTS.iter().map(|i| format!("CIE {i}")).collect(),
        cells: boards.chunks(2).map(<[Option<Rgb8>]>::to_vec).collect(),
        captions: Vec::new(),
        cell_width: 300,
        footer: vec![
            "Top: travertine as found, cleaned; bottom: pudding stone as found, cleaned;".into(),
            "right: the white tile (90 %); the board: grey (30 %).".into(),
        ],
    }
    .render();
    write_sheet(
        out,
        "boards.png",
        &grid,
        "contact sheet: the whole sample board under each illuminant, rendered and seen",
    )
}
