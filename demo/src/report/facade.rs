//! The facade's two contact sheets: the hypotheses side by side under each light (as rendered
//! and as seen), and what cleaning changes — CIEDE2000 between as found and cleaned, pixel by
//! pixel, in CIELAB relative to a perfect white horizontal surface under the light (E_h/π).

use super::renders::Renders;
use super::{Image, write_sheet};
use crate::error::Result;
use crate::picture::{map_picture, picture};
use crate::plan::{FacadeLight, Size};
use crate::sheet::{Grid, Rgb8, beside_colour_bar, colour_bar};
use restauro_image::delta_e::{DeltaEMap, delta_e_map, scale_max};
use restauro_scene::load::{LoadedScene, ResolvedLight};
use restauro_spectral::appearance::d65_white;
use restauro_spectral::display::{Exposure, exposure_scale};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// How far cleaning moves the facade's colours under one light.
#[derive(Serialize)]
pub struct CleaningDifference {
    pub light: FacadeLight,
    /// The luminance of a perfect white horizontal surface under this light, the CIELAB white.
    pub white_cd_m2: f64,
    pub mean_delta_e00: f64,
    pub p95_delta_e00: f64,
    /// Pixels compared (the sky is left out).
    pub pixels: usize,
}

/// Sheet 1: the hypotheses side by side, each light's two renders at one exposure (that of the
/// cleaned render) so that their difference shows.
pub fn hypotheses_sheet(out: &Path, size: &Size, renders: &Renders) -> Result<Image> {
    let mut cells = Vec::new();
    let mut row_labels = Vec::new();
    for light in FacadeLight::ALL {
        let (found, _) = renders.facade(light, "as-found")?;
        let (cleaned, _) = renders.facade(light, "cleaned")?;
        let k = exposure_scale(&cleaned.rendered.pixels, Exposure::Automatic { key: 0.18 });
        let exposure = Exposure::Absolute { white_cd_m2: 1.0 / k };
        cells.push(vec![
            Some(picture(&found.rendered, exposure).resized_to_width(size.sheet_cell)),
            Some(picture(&cleaned.rendered, exposure).resized_to_width(size.sheet_cell)),
        ]);
        row_labels.push(format!("{}, as rendered", light.title()));
        cells.push(vec![
            Some(picture(&found.seen, Exposure::Relative).resized_to_width(size.sheet_cell)),
            Some(picture(&cleaned.seen, Exposure::Relative).resized_to_width(size.sheet_cell)),
        ]);
        row_labels.push(format!("{}, as seen", light.title()));
    }
    let (w, h) = size.facade;
    let sheet = Grid {
        title: "Roman theatre of Aosta, south facade: as found and cleaned",
        column_labels: vec!["as found".into(), "cleaned".into()],
        row_labels,
        cells,
        captions: Vec::new(),
        cell_width: size.sheet_cell,
        footer: vec![
            format!(
                "Rendered {w}x{h}, path tracing, {} samples per pixel, 81 bands 380-780 nm.",
                size.facade_spp
            ),
            "Summer afternoon: the sun at 15:30 CEST on 15 July at 45.74 N 7.32 E, and a clear sky of 15 000 lux.".into(),
            "Overcast: the CIE standard overcast sky, 10 000 lux. Each light's two renders share one exposure.".into(),
            "CIE clear sky: the same sun under the CIE standard clear sky (general sky type 12), 15 000 lux, over a ground of reflectance 0.2.".into(),
            "As found = a soot proxy where no sky or driving rain washes the stone, up to 70 % (derived, not measured).".into(),
            "As seen: adapted to the light measured at each surface (CAT16, CAM16's degree of adaptation, a blue bias); sun and shadow apart; lightness by Marini-Rizzi paths.".into(),
        ],
    }
    .render();
    write_sheet(
        out,
        "facade.png",
        &sheet,
        "contact sheet: the facade as found and cleaned, under sun and overcast sky, rendered and seen",
    )
}

/// Sheet 2: CIEDE2000 between the hypotheses, pixel by pixel, under each light; returns the
/// differences and the sheet.
pub fn cleaning(
    out: &Path,
    size: &Size,
    renders: &Renders,
    scenes: &BTreeMap<PathBuf, LoadedScene>,
) -> Result<(Vec<CleaningDifference>, Image)> {
    let mut maps = Vec::new();
    let mut cleaning = Vec::new();
    for light in FacadeLight::ALL {
        let (found, job) = renders.facade(light, "as-found")?;
        let (cleaned, _) = renders.facade(light, "cleaned")?;
        let scene = &scenes[&job.scene];
        let white_cd_m2 = horizontal_illuminance_lux(scene) / std::f64::consts::PI;
        let white = d65_white().scale(white_cd_m2);
        // The two share the scene's geometry, so their skies (left out) are the same pixels.
        let map = delta_e_map(&found.rendered, &cleaned.rendered, white, 2.0);
        cleaning.push(CleaningDifference {
            light,
            white_cd_m2,
            mean_delta_e00: map.stats.mean,
            p95_delta_e00: map.stats.p95,
            pixels: map.stats.pixels,
        });
        maps.push(map);
    }
    let sheet = cleaning_sheet(size, &maps, &cleaning);
    let image = write_sheet(
        out,
        "cleaning-delta-e.png",
        &sheet,
        "contact sheet: CIEDE2000 map between as found and cleaned, with its colour scale",
    )?;
    Ok((cleaning, image))
}

/// The maps side by side, one colour scale for all, with their statistics and the scale.
fn cleaning_sheet(size: &Size, maps: &[DeltaEMap], cleaning: &[CleaningDifference]) -> Rgb8 {
    let (w, h) = size.facade;
    let all: Vec<f32> = maps.iter().flat_map(|m| m.values.iter().copied()).collect();
    let scale_max = scale_max(&all);
    let cells = vec![
        maps.iter()
            .map(|map| {
                let picture = map_picture(map, w as usize, h as usize, scale_max);
                Some(picture.resized_to_width(size.sheet_cell))
            })
            .collect(),
    ];
    let captions = vec![
        cleaning
            .iter()
            .map(|c| {
                format!("mean {:.1}, 95th percentile {:.1}", c.mean_delta_e00, c.p95_delta_e00)
            })
            .collect(),
    ];
    let grid = Grid {
        title: "What cleaning changes: CIEDE2000 between as found and cleaned",
        column_labels: FacadeLight::ALL.iter().map(|l| l.title().to_owned()).collect(),
        row_labels: vec!["ΔE00 per pixel".into()],
        cells,
        captions,
        cell_width: size.sheet_cell,
        footer: vec![
            "CIELAB relative to a perfect white horizontal surface under each light (E_h/pi),"
                .into(),
            "D65 white; the sky in grey.".into(),
        ],
    }
    .render();
    let cell_h = (f64::from(size.sheet_cell) * f64::from(h) / f64::from(w)).round() as u32;
    let bar = colour_bar(scale_max, 6, 0, "ΔE00", cell_h);
    beside_colour_bar(&grid, &bar)
}

/// The horizontal illuminance of a scene's lights that light the whole ground alike (sun and
/// sky), lux.
fn horizontal_illuminance_lux(scene: &LoadedScene) -> f64 {
    scene
        .lights
        .iter()
        .map(|l| match l {
            ResolvedLight::Sun { illuminance_lux, elevation_deg, .. } => {
                illuminance_lux * elevation_deg.to_radians().sin()
            }
            ResolvedLight::Sky { illuminance_lux, .. } => *illuminance_lux,
            _ => 0.0,
        })
        .sum()
}
