//! One pixel of a finished snapshot, for the readout under the pointer: its luminance, cd/m²
//! (Y of the farm's absolute XYZ EXR); its CIELAB as rendered, relative to a D65 white at the
//! luminance the display's automatic exposure chooses for the image (the white `restauro
//! compare --white auto` takes for its A); its CIELAB as seen, from the Retinex EXR (relative
//! XYZ, Y = 1 the D65 reference white, so CIELAB relative to D65 at Y = 1); and, with another
//! snapshot, the ΔE00 at the pixel exactly as the compare map holds it (the same library call on
//! that one pixel: `restauro_image::delta_e::delta_e_map`, CIELAB relative to this snapshot's
//! white, light sources left out). CIELAB: CIE 15:2004 §8.2.1; CIEDE2000: CIE 142-2001.

use super::Studio;
use super::api::query_value;
use crate::error::{Result, StudioError};
use axum::Json;
use axum::extract::{Path, RawQuery, State};
use restauro_farm::ids::JobId;
use restauro_image::delta_e::{delta_e_map, white_luminance};
use restauro_image::image_files::{MAX_PIXELS, XyzImage, read_exr};
use restauro_spectral::appearance::d65_white;
use restauro_spectral::display::Exposure;
use restauro_spectral::{Lab, Xyz};
use serde::Serialize;
use std::sync::Arc;

/// The ΔE00 above which a pixel counts as changed (as the compare map's statistics count it;
/// it does not change the value at a pixel).
const THRESHOLD: f64 = 2.0;

#[derive(Serialize)]
pub struct PixelView {
    pub job: String,
    pub name: String,
    /// The pixel, from the image's top left corner.
    pub x: usize,
    pub y: usize,
    pub luminance_cd_m2: f64,
    /// Whether the pixel shows a light source (the sky): it has no surface colour to compare.
    pub light_source: bool,
    /// The reference white's luminance, cd/m², for `lab_rendered`.
    pub white_cd_m2: f64,
    /// CIE L*, a*, b* as rendered, relative to a D65 white of `white_cd_m2`.
    pub lab_rendered: [f64; 3],
    /// CIE L*, a*, b* as seen (the Retinex image), relative to D65; none when the job kept no
    /// Retinex image.
    pub lab_seen: Option<[f64; 3]>,
    /// The same pixel of the other snapshot, when one is named.
    pub compared: Option<ComparedPixel>,
}

#[derive(Serialize)]
pub struct ComparedPixel {
    pub job: String,
    pub name: String,
    pub luminance_cd_m2: f64,
    pub light_source: bool,
    /// CIE L*, a*, b* of the other snapshot's pixel relative to this one's white (the white
    /// the ΔE00 is computed in).
    pub lab_rendered: [f64; 3],
    /// ΔE00 of the other snapshot against this one at the pixel, as `/api/compare?a=THIS&b=
    /// OTHER` maps it; none where either shows a light source.
    pub delta_e00: Option<f64>,
}

/// A pixel coordinate of the query, checked against the image's size.
fn coordinate(query: Option<&str>, name: &str, size: usize) -> Result<usize> {
    let text = query_value(query, name).ok_or_else(|| {
        StudioError::Request(format!("{name}: missing from the query (?x=COLUMN&y=ROW)"))
    })?;
    let shown = text.chars().take(40).collect::<String>();
    let value = text.parse::<usize>().map_err(|_| {
        StudioError::Request(format!(
            "{name}: `{}` is not a pixel index (0, 1, 2, …)",
            shown.escape_debug()
        ))
    })?;
    if value >= size {
        return Err(StudioError::Request(format!(
            "{name}: {value} is outside the image (0 to {} px)",
            size - 1
        )));
    }
    Ok(value)
}

fn lab(p: [f32; 3], white: Xyz) -> [f64; 3] {
    let lab = Lab::from_xyz(Xyz::from_array(p.map(f64::from)), white);
    [lab.l, lab.a, lab.b]
}

fn one_pixel(image: &XyzImage, i: usize) -> XyzImage {
    let mut one = XyzImage::new(1, 1, vec![image.pixels[i]]);
    one.emitter = image.emitter.as_ref().map(|m| vec![m[i]]);
    one
}

fn is_light(image: &XyzImage, i: usize) -> bool {
    image.emitter.as_ref().is_some_and(|m| m[i])
}

/// The Retinex image of job `id`, when it kept one.
fn seen(studio: &Studio, id: &JobId, name: &str) -> Result<Option<XyzImage>> {
    let file = format!("{name}-retinex.exr");
    if !studio.farm.job(id)?.results.contains(&file) {
        return Ok(None);
    }
    let path = studio.farm.result_path(id, &file)?;
    let image = read_exr(&path, MAX_PIXELS)
        .map_err(|e| StudioError::Internal(format!("{}: {e}", path.display())))?;
    Ok(Some(image))
}

/// The readout of pixel (`x`, `y`) of job `id` (and of job `other`).
fn read(
    studio: &Studio,
    id: &JobId,
    query: Option<&str>,
    other: Option<JobId>,
) -> Result<PixelView> {
    let (name, image) = super::display::rendered(studio, id)?;
    let x = coordinate(query, "x", image.width)?;
    let y = coordinate(query, "y", image.height)?;
    let i = y * image.width + x;
    let white_cd_m2 = white_luminance(&image, Exposure::default());
    let white = d65_white().scale(white_cd_m2);
    let lab_seen = seen(studio, id, &name)?
        .filter(|s| (s.width, s.height) == (image.width, image.height))
        .map(|s| lab(s.pixels[i], d65_white()));
    let compared = match other {
        None => None,
        Some(other) => {
            let (other_name, b) = super::display::rendered(studio, &other)?;
            if (b.width, b.height) != (image.width, image.height) {
                return Err(StudioError::Request(format!(
                    "other: {other_name} is {}×{} px and {name} {}×{} px; compare snapshots of \
                     one size",
                    b.width, b.height, image.width, image.height
                )));
            }
            let map = delta_e_map(&one_pixel(&image, i), &one_pixel(&b, i), white, THRESHOLD);
            let value = f64::from(map.values[0]);
            Some(ComparedPixel {
                job: other.to_string(),
                name: other_name,
                luminance_cd_m2: f64::from(b.pixels[i][1]),
                light_source: is_light(&b, i),
                lab_rendered: lab(b.pixels[i], white),
                delta_e00: value.is_finite().then_some(value),
            })
        }
    };
    Ok(PixelView {
        job: id.to_string(),
        name,
        x,
        y,
        luminance_cd_m2: f64::from(image.pixels[i][1]),
        light_source: is_light(&image, i),
        white_cd_m2,
        lab_rendered: lab(image.pixels[i], white),
        lab_seen,
        compared,
    })
}

/// `GET /api/jobs/{id}/pixel?x=COLUMN&y=ROW[&other=JOB]`: the readout of one pixel.
pub async fn pixel(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Json<PixelView>> {
    let id = JobId::parse(&id)?;
    let other = match query_value(query.as_deref(), "other") {
        None => None,
        Some(text) => Some(JobId::parse(&text).map_err(|_| {
            StudioError::Request(format!(
                "other: `{}` is not a job id (the snapshot to compare with, as /api/jobs lists it)",
                text.chars().take(80).collect::<String>().escape_debug()
            ))
        })?),
    };
    tokio::task::spawn_blocking(move || read(&studio, &id, query.as_deref(), other))
        .await?
        .map(Json)
}
