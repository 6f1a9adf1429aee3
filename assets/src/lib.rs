//! restauro-assets: where a scene's files come from. A scene folder on disk, whose files named
//! by URL are fetched, checked against their pins and cached ([`remote`]); a bundle archive
//! ([`archive`]); a scene folder sent to the studio as one zip or tar ([`folder`]). Each becomes
//! the scene model's own forms: a loaded scene, or the content-addressed bundle a worker renders.
//!
//! The scene model (restauro-scene) reads every file through its `Assets` trait and knows no
//! network, so that it and the tracer build without tokio, hyper or rustls; this crate gives a
//! folder its fetcher. Its errors are [`AssetsError`]s: the scene model's, or its own.

pub mod archive;
pub mod error;
pub mod folder;
pub mod remote;

pub use error::{AssetsError, Result};
use restauro_scene::assets::FolderAssets;
use restauro_scene::bundle::{Bundle, bundle_files};
use restauro_scene::limits::Limits;
use restauro_scene::load::{LoadedScene, load, read_scene_file};
use restauro_scene::scene_file::SceneFile;
use std::path::Path;

/// The files of the scene folder of the scene file at `path`, its files named by URL fetched
/// as its `[pins]` say.
pub fn folder_assets(path: &Path, scene: &SceneFile, limits: &Limits) -> Result<FolderAssets> {
    let remote = remote::Remote::new(path, &scene.pins)?;
    Ok(FolderAssets::new(path, limits.max_file_bytes)?.with_fetch(Box::new(remote)))
}

/// Load and check the scene at `path`: a scene file with its folder (and the files it names by
/// URL), or a bundle archive.
pub fn load_scene(path: &Path, limits: &Limits) -> Result<LoadedScene> {
    if archive::is_archive(path) {
        return Ok(archive::read_archive(path, limits)?.load(limits)?);
    }
    let file = read_scene_file(path, limits)?;
    let assets = folder_assets(path, &file, limits)?;
    Ok(load(file, &assets, limits)?)
}

/// Bundle the scene file at `path` and everything it refers to (or read the bundle an archive
/// at `path` holds, see [`archive`]).
pub fn bundle_scene(path: &Path, limits: &Limits) -> Result<Bundle> {
    if archive::is_archive(path) {
        return archive::read_archive(path, limits);
    }
    let scene = read_scene_file(path, limits)?;
    let assets = folder_assets(path, &scene, limits)?;
    Ok(bundle_files(scene, &assets, limits)?)
}
