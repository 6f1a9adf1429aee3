//! A snapshot taken in the studio: the view the page shows, rendered on the farm. The page sends
//! its camera (in the preview's coordinates) and the render's options; the scene's manifest gets
//! that camera, and the job is submitted exactly as the gRPC door submits one, so it is checked
//! by the same code and refused with the same messages.

use super::preview::{ScenePreview, to_world};
use crate::error::{Result, StudioError};
use restauro_farm::farm::Farm;
use restauro_farm::job::JobStatus;
use restauro_scene::bundle::Bundle;
use restauro_scene::job::{JobName, JobSpec, option_count};
use restauro_scene::plan::RenderOptions;
use restauro_scene::scene_file::Integrator;
use serde::Deserialize;
use std::sync::Arc;

/// The camera as the page holds it: Y up, relative to the preview's offset.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewCamera {
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub vertical_fov_deg: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnapshotRequest {
    pub camera: ViewCamera,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    /// `path` or `whitted`.
    pub integrator: String,
    #[serde(default)]
    pub variant: Option<String>,
    #[serde(default)]
    pub name: Option<String>,
    /// The scene's revision the page shows (the latest when absent).
    #[serde(default)]
    pub revision: Option<u32>,
}

fn refuse(field: &str, problem: impl std::fmt::Display) -> StudioError {
    StudioError::Request(format!("{field}: {problem}"))
}

/// Submits the snapshot `request` of scene `id`; the job's first status.
pub async fn take(
    farm: &Arc<Farm>,
    id: &str,
    preview: &ScenePreview,
    request: SnapshotRequest,
) -> Result<JobStatus> {
    let mut scene =
        Bundle::parse_manifest(&farm.scene_revision(id, Some(preview.view.revision))?.1)?;
    let offset = preview.view.offset_m;
    let c = &request.camera;
    let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
    if !(finite(&c.position) && finite(&c.target) && finite(&c.up)) {
        return Err(refuse("camera", "every coordinate must be a finite number"));
    }
    scene.camera.position = Some(to_world(c.position, offset));
    scene.camera.target = Some(to_world(c.target, offset));
    scene.camera.up = to_world(c.up, [0.0; 3]);
    scene.camera.vertical_fov_deg = c.vertical_fov_deg;
    scene.camera.viewpoint = None;
    let integrator = match request.integrator.as_str() {
        "path" => Integrator::Path,
        "whitted" => Integrator::Whitted,
        other => {
            return Err(refuse(
                "integrator",
                format!("`{}`: use path or whitted", other.escape_debug()),
            ));
        }
    };
    let stem = scene_name(farm, id);
    let name = request.name.unwrap_or_else(|| match &request.variant {
        Some(v) => format!("{stem}-{v}"),
        None => stem,
    });
    let count = |field, value| option_count(field, value).map_err(|e| refuse(e.field, e.problem));
    let spec = JobSpec {
        name: JobName::new(&name).map_err(|e| refuse("name", e.problem))?,
        render: RenderOptions {
            variant: request.variant,
            integrator: Some(integrator),
            samples_per_pixel: Some(count("render.samples_per_pixel", request.samples_per_pixel)?),
            width: Some(count("render.width", request.width)?),
            height: Some(count("render.height", request.height)?),
            spectral: false,
            tile: None,
            grids: false,
        },
        ..JobSpec::default()
    }
    .checked()
    .map_err(|e| refuse(e.field, e.problem))?;
    let manifest = serde_json::to_string(&scene)
        .map_err(|e| StudioError::Internal(format!("the scene does not serialise: {e}")))?;
    Ok(farm.submit(manifest, spec).await?)
}

/// The name of the scene's latest job.
fn scene_name(farm: &Farm, id: &str) -> String {
    farm.scenes().into_iter().find(|s| s.id == id).map_or_else(|| "snapshot".into(), |s| s.name)
}
