//! Two snapshots compared in the studio: the CIEDE2000 map between their rendered images, as
//! `restauro compare A.exr B.exr` computes it (`restauro_image::delta_e`, in CIELAB relative to
//! the white the display chooses for A, light sources left out, a ΔE00 of 2 as the threshold),
//! served as statistics and as a viridis picture with its scale's top.

use super::Studio;
use super::api::query_value;
use crate::error::{Result, StudioError};
use axum::Json;
use axum::extract::{RawQuery, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use restauro_farm::ids::JobId;
use restauro_image::delta_e::{
    DeltaEMap, DeltaEStats, delta_e_map, map_rgb, scale_max, white_luminance,
};
use restauro_image::image_files::{PngPixels, encode_png};
use restauro_spectral::appearance::d65_white;
use restauro_spectral::display::Exposure;
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::sync::Arc;

/// The ΔE00 above which a pixel counts as changed: `restauro compare`'s default, about twice
/// a just noticeable difference.
const THRESHOLD: f64 = 2.0;

#[derive(Serialize)]
pub struct CompareView {
    pub a: String,
    pub b: String,
    pub width: usize,
    pub height: usize,
    /// The reference white's luminance, cd/m².
    pub white_luminance: f64,
    /// The top of the picture's colour scale (ΔE00).
    pub scale_max: f64,
    pub delta_e00: DeltaEStats,
}

struct Compared {
    view: CompareView,
    map: DeltaEMap,
}

/// The jobs `a` and `b` of the query.
fn pair(query: Option<&str>) -> Result<(JobId, JobId)> {
    let job = |name: &str| -> Result<JobId> {
        let text = query_value(query, name).ok_or_else(|| {
            StudioError::Request(format!("{name}: give the job to compare (?a=JOB&b=JOB)"))
        })?;
        Ok(JobId::parse(&text)?)
    };
    Ok((job("a")?, job("b")?))
}

async fn compared(studio: &Arc<Studio>, query: Option<&str>) -> Result<Compared> {
    let (a, b) = pair(query)?;
    let studio = studio.clone();
    tokio::task::spawn_blocking(move || -> Result<Compared> {
        let ((a_name, a), (b_name, b)) =
            (super::display::rendered(&studio, &a)?, super::display::rendered(&studio, &b)?);
        if (a.width, a.height) != (b.width, b.height) {
            return Err(StudioError::Request(format!(
                "b: {b_name} is {}×{} px and {a_name} {}×{} px; compare snapshots of one size",
                b.width, b.height, a.width, a.height
            )));
        }
        let white = white_luminance(&a, Exposure::default());
        let map = delta_e_map(&a, &b, d65_white().scale(white), THRESHOLD);
        let view = CompareView {
            a: a_name,
            b: b_name,
            width: a.width,
            height: a.height,
            white_luminance: white,
            scale_max: scale_max(&map.values),
            delta_e00: map.stats.clone(),
        };
        Ok(Compared { view, map })
    })
    .await?
}

/// `GET /api/compare?a=JOB&b=JOB`: the ΔE00 statistics of B against A.
pub async fn compare(
    State(studio): State<Arc<Studio>>,
    RawQuery(query): RawQuery,
) -> Result<Json<CompareView>> {
    Ok(Json(compared(&studio, query.as_deref()).await?.view))
}

/// `GET /api/compare/delta-e.png?a=JOB&b=JOB`: the ΔE00 map, viridis from 0 to the scale's
/// top, light sources grey.
pub async fn picture(
    State(studio): State<Arc<Studio>>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let Compared { view, map } = compared(&studio, query.as_deref()).await?;
    let pixels = PngPixels::Eight(map_rgb(&map, view.scale_max));
    let png = encode_png(view.width, view.height, &pixels, RgbSpace::Srgb)
        .map_err(|e| StudioError::Internal(format!("the ΔE00 picture: {e}")))?;
    Ok(([(header::CONTENT_TYPE, "image/png")], png).into_response())
}
