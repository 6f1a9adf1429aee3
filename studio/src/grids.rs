//! The scene's calculation grids computed on the farm and read back as illuminance. The page
//! asks for a revision's grids to be computed: a job whose plan computes the grids instead of
//! the camera's image (`RenderOptions::grids`), submitted exactly as any job is. Once it is
//! done, its figures and false-colour maps come from `Farm::illuminance`, which reads the
//! result with the code `restauro illuminance` uses.

use super::Studio;
use super::api::{parse, scene_id};
use crate::error::{Result, StudioError};
use axum::Json;
use axum::body::{Body, Bytes};
use axum::extract::{Path, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use restauro_farm::error::FarmError;
use restauro_farm::ids::JobId;
use restauro_farm::job::JobStatus;
use restauro_image::illuminance::Document;
use restauro_scene::job::{JobName, JobSpec};
use restauro_scene::plan::RenderOptions;
use serde::Deserialize;
use std::sync::Arc;

/// What the page sends: the revision whose grids to compute (the latest when absent) and the
/// render's options (`samples_per_pixel`: the samples per sensor point; the scene's own when
/// absent), read as a job's options are.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComputeRequest {
    #[serde(default)]
    pub revision: Option<u32>,
    #[serde(default)]
    pub render: RenderOptions,
}

/// `POST /api/scenes/{id}/grids`: computes the revision's grids on the farm; the new job.
pub async fn compute(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Bytes,
) -> Result<Json<JobStatus>> {
    let id = scene_id(&id)?;
    let request: ComputeRequest = parse(&body, "the grids request")?;
    let farm = &studio.farm;
    let (_, manifest) = farm.scene_revision(id, request.revision)?;
    let stem =
        farm.scenes().into_iter().find(|s| s.id == id).map_or_else(|| "scene".into(), |s| s.name);
    // Named as `restauro illuminance` names its job.
    let name = match &request.render.variant {
        Some(v) => format!("{stem}-{v}-illuminance"),
        None => format!("{stem}-illuminance"),
    };
    let refuse = |field: &str, problem: String| StudioError::Request(format!("{field}: {problem}"));
    let spec = JobSpec {
        name: JobName::new(&name).map_err(|e| refuse("name", e.problem))?,
        render: RenderOptions { grids: true, ..request.render },
        ..JobSpec::default()
    }
    .checked()
    .map_err(|e| refuse(e.field, e.problem))?;
    Ok(Json(farm.submit(manifest, spec).await?))
}

/// `GET /api/jobs/{id}/illuminance`: a finished calculation's figures per grid (the document
/// `restauro illuminance` writes as `illuminance.json`).
pub async fn illuminance(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Json<Document>> {
    Ok(Json(studio.farm.illuminance(&JobId::parse(&id)?).await?))
}

/// `GET /api/jobs/{id}/illuminance/{name}`: a grid's map (`<grid>.png`) or table
/// (`<grid>.csv`), as `restauro illuminance` writes them.
pub async fn file(
    State(studio): State<Arc<Studio>>,
    Path((id, name)): Path<(String, String)>,
) -> Result<Response> {
    let path = studio.farm.illuminance_file(&JobId::parse(&id)?, &name).await?;
    let bytes = tokio::fs::read(&path).await.map_err(|e| FarmError::io(&path, e))?;
    let kind = if name.ends_with(".png") {
        "image/png"
    } else if name.ends_with(".csv") {
        "text/csv"
    } else {
        "application/json"
    };
    let mut response = (StatusCode::OK, Body::from(bytes)).into_response();
    response.headers_mut().insert(header::CONTENT_TYPE, HeaderValue::from_static(kind));
    Ok(response)
}
