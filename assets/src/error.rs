//! The one error type of restauro-assets: a scene error as the scene model words it, or a
//! refusal of this crate's own — a file named by URL that cannot be fetched or does not match
//! its pin, the environment's download settings, a bundle archive, a scene folder sent as one
//! archive, a bundle written out as a folder. Each own refusal is worded as the scene model
//! words an invalid file (`<file>: <place>: <problem>`), so the messages are those the scene
//! model gave when this crate returned its errors.

use restauro_scene::SceneError;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum AssetsError {
    /// The scene model's own error (a scene file, a mesh, a limit), unchanged.
    #[error(transparent)]
    Scene(#[from] SceneError),

    /// A file named by URL that cannot be fetched, has no pin, or does not match its pin
    /// (the download cache's trouble included): where the scene names it, and why.
    #[error("{}: {place}: {problem}", scene_file.display())]
    Fetch { scene_file: PathBuf, place: String, problem: String },

    /// A download setting in the environment (`RESTAURO_CACHE_MB`, …) that is not a number.
    #[error("the environment: {name}: `{value}` is not a whole number")]
    Setting { name: String, value: String },

    /// A bundle archive that is not one ([`crate::archive`]).
    #[error("{}: archive: {problem}", path.display())]
    Archive { path: PathBuf, problem: String },

    /// A scene folder sent as one zip or tar that cannot be taken ([`crate::folder`]).
    #[error("{SENT}: folder: {problem}")]
    Folder { problem: String },

    /// A bundle that cannot be written out as the folder `name` ([`crate::folder::folder_tar`]).
    #[error("{name}: scene folder: {problem}")]
    FolderTar { name: String, problem: String },
}

/// Where a scene folder sent is named in messages.
pub(crate) const SENT: &str = "the folder sent";

impl AssetsError {
    /// The scene model's error, when this is one.
    pub fn scene_error(&self) -> Option<&SceneError> {
        match self {
            AssetsError::Scene(e) => Some(e),
            _ => None,
        }
    }

    /// This error as the scene model's, with the same message: its own, or an own refusal as
    /// the invalid file it words itself as. For the scene model's `Fetch` trait (a fetch fails
    /// inside the scene's loader) and for callers that map scene errors to a status.
    pub fn into_scene_error(self) -> SceneError {
        match self {
            AssetsError::Scene(e) => e,
            AssetsError::Fetch { scene_file, place, problem } => {
                SceneError::invalid(scene_file, place, problem)
            }
            AssetsError::Setting { name, value } => SceneError::invalid(
                "the environment",
                name,
                format!("`{value}` is not a whole number"),
            ),
            AssetsError::Archive { path, problem } => SceneError::invalid(path, "archive", problem),
            AssetsError::Folder { problem } => {
                SceneError::invalid(Path::new(SENT), "folder", problem)
            }
            AssetsError::FolderTar { name, problem } => {
                SceneError::invalid(Path::new(&name), "scene folder", problem)
            }
        }
    }
}

pub type Result<T, E = AssetsError> = std::result::Result<T, E>;
