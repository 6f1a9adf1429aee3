//! A snapshot taken in the studio: the view the page shows, rendered on the farm. The page sends
//! its camera (in the preview's coordinates) and the render's options; the scene's manifest gets
//! that camera, and the job is submitted exactly as the gRPC door submits one, so it is checked
//! by the same code and refused with the same messages.

use super::preview::{ScenePreview, pose_to_world};
use crate::error::{Result, StudioError};
use restauro_farm::farm::Farm;
use restauro_farm::job::JobStatus;
use restauro_scene::bundle::Bundle;
use restauro_scene::job::{JobName, JobSpec};
use restauro_scene::plan::RenderOptions;
use restauro_scene::scene_file::{Pose, SceneFile};
use restauro_scene::sequence::Frame;
use serde::Deserialize;
use std::sync::Arc;

/// A snapshot as the page asks for it: its camera (Y up, relative to the preview's offset) and
/// the render's options, read as a job's options are, so that a zero count or an unknown option
/// is refused naming its field (`render.samples_per_pixel`, …).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnapshotRequest {
    pub camera: Pose,
    pub render: RenderOptions,
    #[serde(default)]
    pub name: Option<String>,
    /// The scene's revision the page shows (the latest when absent).
    #[serde(default)]
    pub revision: Option<u32>,
}

pub(super) fn refuse(field: &str, problem: impl std::fmt::Display) -> StudioError {
    StudioError::Request(format!("{field}: {problem}"))
}

/// Submits the snapshot `request` of scene `id`; the job's first status.
pub async fn take(
    farm: &Arc<Farm>,
    id: &str,
    preview: &ScenePreview,
    request: SnapshotRequest,
) -> Result<JobStatus> {
    let scene = scene_seen_from(farm, id, preview, Some(&request.camera))?;
    let stem = scene_name(farm, id);
    let name = request.name.unwrap_or_else(|| match &request.render.variant {
        Some(v) => format!("{stem}-{v}"),
        None => stem,
    });
    let spec = job_spec(&name, request.render, Vec::new())?;
    Ok(farm.submit(manifest_json(&scene)?, spec).await?)
}

/// The scene of the revision `preview` shows, seen from the page's `camera` (in the preview's
/// coordinates) when one is given.
pub(super) fn scene_seen_from(
    farm: &Farm,
    id: &str,
    preview: &ScenePreview,
    camera: Option<&Pose>,
) -> Result<SceneFile> {
    let mut scene =
        Bundle::parse_manifest(&farm.scene_revision(id, Some(preview.view.revision))?.1)?;
    let Some(camera) = camera else { return Ok(scene) };
    let c = pose_to_world(camera, preview.view.offset_m);
    let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
    if !(finite(&c.position) && finite(&c.target) && finite(&c.up)) {
        return Err(refuse("camera", "every coordinate must be a finite number"));
    }
    scene.camera.position = Some(c.position);
    scene.camera.target = Some(c.target);
    scene.camera.up = c.up;
    scene.camera.vertical_fov_deg = c.vertical_fov_deg;
    scene.camera.viewpoint = None;
    Ok(scene)
}

/// A job named `name` of `render` (and a sequence's `frames`), checked as the gRPC door checks
/// one, refused naming its field.
pub(super) fn job_spec(name: &str, render: RenderOptions, frames: Vec<Frame>) -> Result<JobSpec> {
    JobSpec {
        name: JobName::new(name).map_err(|e| refuse("name", e.problem))?,
        render,
        frames,
        ..JobSpec::default()
    }
    .checked()
    .map_err(|e| refuse(e.field, e.problem))
}

/// The manifest the farm is sent.
pub(super) fn manifest_json(scene: &SceneFile) -> Result<String> {
    serde_json::to_string(scene)
        .map_err(|e| StudioError::Internal(format!("the scene does not serialise: {e}")))
}

/// The name of the scene's latest job.
pub(super) fn scene_name(farm: &Farm, id: &str) -> String {
    farm.scenes().into_iter().find(|s| s.id == id).map_or_else(|| "snapshot".into(), |s| s.name)
}
