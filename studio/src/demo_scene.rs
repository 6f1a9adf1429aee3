//! The demo's facade, offered on a first visit: a studio opened on a coordinator that holds no
//! scene offers the procedural south facade of the Roman theatre of Aosta (restauro-demo, the
//! scene the quick start's demo renders), beside "open a folder". It is sent to the farm exactly
//! as a folder is (one tar of its scene file and mesh, bundled and checked as `restauro scene
//! check` does, a quick preview rendered), so it is a scene like any other: edited, downloaded,
//! rendered on the farm.

use crate::Studio;
use crate::edits::OpenedFolder;
use crate::error::{Result, StudioError};
use axum::Json;
use axum::extract::State;
use std::sync::Arc;

/// The name of the scene (and of its preview job), as the farm's jobs table lists it.
pub const NAME: &str = "aosta facade (demo)";
/// The scene file opened: a summer afternoon, the sun and the clear sky around it.
pub const SCENE_FILE: &str = "aosta.toml";
/// The camera's image, as the quick start's demo renders the facade at full size.
const WIDTH_PX: u32 = 1280;
const HEIGHT_PX: u32 = 720;
/// The blocks' variation: the demo's own seed, so the facade is the one the demo shows.
const SEED: u64 = 1;

/// `POST /api/scenes/demo`: the demo's facade opened as a folder sent from the page.
pub async fn open(State(studio): State<Arc<Studio>>) -> Result<Json<OpenedFolder>> {
    let archive = tokio::task::spawn_blocking(archive)
        .await
        .map_err(|e| StudioError::Internal(format!("writing the demo's facade: {e}")))??;
    let (job, scene) = studio.farm.open_folder(NAME, Some(SCENE_FILE.into()), archive).await?;
    Ok(Json(OpenedFolder { job, scene }))
}

/// The facade's folder as one tar: `aosta.toml` and `meshes/facade.obj`, the paths the scene
/// file names them by (restauro-demo's `write_aosta` writes the same files to disk).
fn archive() -> Result<Vec<u8>> {
    let generated = restauro_demo::scenes::aosta::generate(WIDTH_PX, HEIGHT_PX, SEED);
    let mut tar = tar::Builder::new(Vec::new());
    for (path, text) in
        [(SCENE_FILE, &generated.scene_toml), ("meshes/facade.obj", &generated.facade_obj)]
    {
        let mut header = tar::Header::new_ustar();
        header.set_size(text.len() as u64);
        header.set_mode(0o644);
        header.set_cksum();
        tar.append_data(&mut header, path, text.as_bytes())
            .map_err(|e| StudioError::Internal(format!("packing the demo's {path}: {e}")))?;
    }
    tar.into_inner().map_err(|e| StudioError::Internal(format!("packing the demo's facade: {e}")))
}

#[cfg(test)]
mod tests {
    /// The archive holds the scene file and the mesh it names, and nothing else.
    #[test]
    fn the_archive_holds_the_scene_and_its_mesh() {
        let bytes = super::archive().unwrap();
        let mut tar = tar::Archive::new(bytes.as_slice());
        let names: Vec<String> = tar
            .entries()
            .unwrap()
            .map(|e| e.unwrap().path().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["aosta.toml", "meshes/facade.obj"]);
    }
}
