//! A snapshot as it renders: the tiles the store holds so far, drawn into one picture the size
//! of the image, each at the display transform `restauro display` applies (tone curve, sRGB),
//! exposed automatically over the pixels rendered so far; the pixels of tiles still to come
//! are transparent, so that the page shows its real-time view through them.

use super::Studio;
use crate::error::{Result, StudioError};
use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use restauro_farm::error::FarmError;
use restauro_farm::farm::Farm;
use restauro_farm::ids::JobId;
use restauro_image::framebuffer::{Framebuffer, TileLayout};
use restauro_image::image_files::{PngPixels, encode_png};
use restauro_spectral::display::{DisplayParams, Exposure, encode, exposure_scale, to_u8};
use restauro_spectral::rgb_space::RgbSpace;
use std::sync::Arc;

/// `GET /api/jobs/{id}/painting.png`: the tiles rendered so far (RGBA; none yet: all
/// transparent). A job whose tiles have gone (done and assembled, or cancelled) paints nothing.
pub async fn painting(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Response> {
    let (farm, id) = (studio.farm.clone(), JobId::parse(&id)?);
    let bytes = tokio::task::spawn_blocking(move || paint(&farm, &id)).await??;
    let headers = [(header::CONTENT_TYPE, "image/png"), (header::CACHE_CONTROL, "no-store")];
    Ok((headers, bytes).into_response())
}

/// The PNG of job `id`'s tiles in the store.
fn paint(farm: &Farm, id: &JobId) -> Result<Vec<u8>> {
    let record = farm.jobs_record(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
    let plan = &record.plan;
    let mut frame = Framebuffer::new(plan.width, plan.height, TileLayout::from(plan));
    let mut rendered = vec![false; frame.xyz.len()];
    for (index, rect) in plan.tiles().enumerate() {
        let Some(data) = farm.stored_tile(id, index as u32)? else { continue };
        frame
            .place(index as u32, &rect, &data)
            .map_err(|e| StudioError::Internal(e.to_string()))?;
        for y in rect.y..rect.y + rect.height {
            let row = (y * plan.width) as usize;
            rendered[row + rect.x as usize..row + (rect.x + rect.width) as usize].fill(true);
        }
    }
    let so_far: Vec<[f32; 3]> =
        frame.xyz.iter().zip(&rendered).filter(|(_, r)| **r).map(|(p, _)| *p).collect();
    // The automatic exposure of the pixels there are, held as an absolute white for them all.
    let white_cd_m2 = 1.0 / exposure_scale(&so_far, Exposure::default());
    let exposure = if white_cd_m2.is_finite() && white_cd_m2 > 0.0 {
        Exposure::Absolute { white_cd_m2 }
    } else {
        Exposure::default()
    };
    let rgb = to_u8(&encode(&frame.xyz, &DisplayParams { space: RgbSpace::Srgb, exposure }));
    let rgba = rgb
        .chunks_exact(3)
        .zip(&rendered)
        .flat_map(|(p, r)| [p[0], p[1], p[2], if *r { 255 } else { 0 }])
        .collect();
    let (w, h) = (plan.width as usize, plan.height as usize);
    encode_png(w, h, &PngPixels::EightWithAlpha(rgba), RgbSpace::Srgb)
        .map_err(|e| StudioError::Internal(format!("the PNG: {e}")))
}
