//! The images kept with notes: sent by the page (`POST /api/scenes/{id}/images`), checked to be
//! the PNG or JPEG their names say and kept among the assets, then named in a note's `images`;
//! and served back to the page (`GET /api/images/{reference}`) under their own media type, never
//! sniffed, never run (`nosniff`, and a policy that lets nothing in them load or execute).

use super::Studio;
use super::api::{query_value, scene_id};
use crate::error::{Result, StudioError};
use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{Path, RawQuery, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use restauro_farm::asset_store::asset_hash;
use restauro_scene::assets::extension;
use restauro_scene::note_image;
use serde::Serialize;
use std::sync::Arc;

/// An image the studio was sent: its reference (for a note's `images`).
#[derive(Serialize)]
pub struct ImageInfo {
    /// `blake3:<hash>.png` (or `.jpg`, `.jpeg`).
    pub reference: String,
    pub file_name: String,
    pub media_type: &'static str,
    pub bytes: usize,
}

/// `POST /api/scenes/{id}/images?name=FILE.png` (or `.jpg`, `.jpeg`), the image as the body:
/// checked and kept; its reference.
pub async fn upload(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
    body: std::result::Result<Bytes, BytesRejection>,
) -> Result<Json<ImageInfo>> {
    studio.farm.scene_revision(scene_id(&id)?, None)?;
    let name = query_value(query.as_deref(), "name").unwrap_or_default();
    // A body over the route's limit is cut off before it is read: said in the studio's words.
    let body = body.map_err(|e| {
        StudioError::Request(format!(
            "{name}: {}; a note's image may have at most {} bytes, send a smaller copy",
            e.body_text(),
            note_image::MAX_BYTES
        ))
    })?;
    let kind = restauro_farm::farm::sent_file(
        &name,
        &body,
        &note_image::EXTENSIONS,
        note_image::MAX_BYTES,
    )?;
    let media_type = note_image::media_type(&kind, &body).ok_or_else(|| {
        StudioError::Request(format!("{name}: {}", note_image::not_an_image(&kind)))
    })?;
    let farm = studio.farm.clone();
    let file_name = name.clone();
    let bytes = body.len();
    let reference =
        tokio::task::spawn_blocking(move || farm.keep_file(&name, &body, &kind)).await??;
    Ok(Json(ImageInfo { reference, file_name, media_type, bytes }))
}

/// `GET /api/images/{reference}`: a note's image, as it was sent. Its bytes are checked again
/// against the media type its name gives; anything else the coordinator holds is not served
/// here. Content-addressed, so a browser may keep it.
pub async fn image(
    State(studio): State<Arc<Studio>>,
    Path(reference): Path<String>,
) -> Result<Response> {
    let hash = asset_hash(&reference)?.to_owned();
    let kind = extension(&reference);
    let missing = || StudioError::NoSuchImage(reference.chars().take(120).collect());
    if !note_image::EXTENSIONS.contains(&kind.as_str()) {
        return Err(missing());
    }
    let farm = studio.farm.clone();
    let bytes =
        tokio::task::spawn_blocking(move || farm.read_asset(&hash)).await??.ok_or_else(missing)?;
    let media_type = note_image::media_type(&kind, &bytes).ok_or_else(missing)?;
    Ok((
        [
            (header::CONTENT_TYPE, media_type),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
            (header::CONTENT_SECURITY_POLICY, "default-src 'none'; sandbox"),
            (header::CACHE_CONTROL, "private, max-age=31536000, immutable"),
        ],
        bytes,
    )
        .into_response())
}
