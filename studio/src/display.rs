//! A snapshot shown as the lighting designer needs it: at a chosen exposure (the display
//! transform `restauro display` applies: `restauro_spectral::display`, the same tone curve and
//! gamut mapping), and in false colour by luminance, cd/m², on a logarithmic viridis scale whose
//! ends the page chooses.

use super::Studio;
use super::api::query_value;
use crate::error::{Result, StudioError};
use axum::Json;
use axum::extract::{Path, RawQuery, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use restauro_farm::ids::JobId;
use restauro_image::delta_e::viridis;
use restauro_image::false_colour;
use restauro_image::image_files::{MAX_PIXELS, PngPixels, XyzImage, encode_png, read_exr};
use restauro_spectral::display::{DisplayParams, Exposure, encode, exposure_scale, to_u8};
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::sync::Arc;

/// The rendered image (absolute XYZ, cd/m² in Y) of a finished job.
pub(super) fn rendered(studio: &Studio, id: &JobId) -> Result<(String, XyzImage)> {
    let job = studio.farm.job(id)?;
    let path = studio.farm.result_path(id, &format!("{}.exr", job.name))?;
    let image = read_exr(&path, MAX_PIXELS)
        .map_err(|e| StudioError::Internal(format!("{}: {e}", path.display())))?;
    Ok((job.name, image))
}

async fn image_of(studio: &Arc<Studio>, id: &str) -> Result<XyzImage> {
    let (studio, id) = (studio.clone(), JobId::parse(id)?);
    tokio::task::spawn_blocking(move || rendered(&studio, &id).map(|(_, image)| image)).await?
}

fn png(width: usize, height: usize, rgb: Vec<u8>) -> Result<Response> {
    let bytes = encode_png(width, height, &PngPixels::Eight(rgb), RgbSpace::Srgb)
        .map_err(|e| StudioError::Internal(format!("the PNG: {e}")))?;
    Ok(([(header::CONTENT_TYPE, "image/png")], bytes).into_response())
}

/// `GET /api/jobs/{id}/display.png?exposure=auto|auto:KEY|absolute:CD_M2|relative`: the
/// rendered image at that exposure, as `restauro display --exposure` shows it.
pub async fn display(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let text = query_value(query.as_deref(), "exposure").unwrap_or_else(|| "auto".into());
    let exposure: Exposure =
        text.parse().map_err(|e| StudioError::Request(format!("exposure: {e}")))?;
    let image = image_of(&studio, &id).await?;
    let encoded = encode(&image.pixels, &DisplayParams { space: RgbSpace::Srgb, exposure });
    png(image.width, image.height, to_u8(&encoded))
}

/// The luminances of an image, for the exposure and false-colour controls.
#[derive(Serialize)]
pub struct Luminance {
    /// The reference white `auto` exposure chooses, cd/m².
    pub auto_white_cd_m2: f64,
    /// The 1st, 50th and 99th percentiles of the luminances above zero, cd/m².
    pub p1_cd_m2: f64,
    pub p50_cd_m2: f64,
    pub p99_cd_m2: f64,
    /// A default scale for false colour: whole decades around the 1st and 99th percentiles.
    pub scale_min_cd_m2: f64,
    pub scale_max_cd_m2: f64,
}

/// `GET /api/jobs/{id}/luminance`
pub async fn luminance(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Json<Luminance>> {
    let image = image_of(&studio, &id).await?;
    let [p1, p50, p99] = false_colour::percentiles(&image.pixels);
    let scale = false_colour::Range::auto(&image.pixels, false_colour::Scale::Log);
    Ok(Json(Luminance {
        auto_white_cd_m2: 1.0 / exposure_scale(&image.pixels, Exposure::default()),
        p1_cd_m2: p1,
        p50_cd_m2: p50,
        p99_cd_m2: p99,
        scale_min_cd_m2: scale.min,
        scale_max_cd_m2: scale.max,
    }))
}

/// `GET /api/jobs/{id}/luminance.png?min_cd_m2=…&max_cd_m2=…`: each pixel's luminance in false
/// colour, viridis from `min` (and below) to `max` (and above) on a logarithmic scale.
pub async fn false_colour(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let bound = |name: &str| -> Result<f64> {
        let text = query_value(query.as_deref(), name)
            .ok_or_else(|| StudioError::Request(format!("{name}: missing from the query")))?;
        text.parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).ok_or_else(|| {
            StudioError::Request(format!("{name}: `{text}` is not a luminance above 0 cd/m²"))
        })
    };
    let (min, max) = (bound("min_cd_m2")?, bound("max_cd_m2")?);
    let scale = false_colour::Scale::Log;
    let range = false_colour::Range::new(min, max, scale)
        .map_err(|e| StudioError::Request(format!("min_cd_m2, max_cd_m2: {e}")))?;
    let image = image_of(&studio, &id).await?;
    let rgb = image
        .pixels
        .iter()
        .flat_map(|p| viridis(false_colour::position(f64::from(p[1]), scale, range)))
        .collect();
    png(image.width, image.height, rgb)
}
