//! A bundle written back out as a scene folder, for a person: `scene.toml` (the scene as TOML,
//! the one source of truth) and `files/<hash>.<extension>` for every file it names, in one tar
//! to download. `restauro scene check` accepts the folder and `restauro render` renders it to
//! the image the bundle renders to: reading the folder back gives the same canonical scene, and
//! so the same identity (TOML writes each number in the shortest form that reads back exactly).

use crate::bundle::Bundle;
use crate::error::{Result, SceneError};
use std::path::Path;

/// The folder's scene file.
pub const SCENE_FILE: &str = "scene.toml";

/// `bundle` as a tar of the folder `name/`, with `comment` (lines without `#`) atop the TOML.
pub fn folder_tar(bundle: &Bundle, name: &str, comment: &str) -> Result<Vec<u8>> {
    let refuse = |problem: String| SceneError::invalid(Path::new(name), "scene folder", problem);
    let mut scene = bundle.scene.clone();
    let mut files = Vec::new();
    for reference in Bundle::references_mut(&mut scene) {
        let Some(file) = reference.strip_prefix("blake3:") else {
            return Err(refuse(format!("`{reference}` is not a bundle's reference")));
        };
        let hash = file.split('.').next().unwrap_or_default();
        let bytes = bundle.files.get(hash).ok_or_else(|| refuse(format!("no file {hash}")))?;
        let path = format!("files/{file}");
        files.push((path.clone(), bytes));
        *reference = path;
    }
    let toml = toml::to_string_pretty(&scene).map_err(|e| refuse(e.to_string()))?;
    let header: String = comment.lines().map(|l| format!("# {l}\n")).collect();
    let text = format!("{header}\n{toml}");
    files.sort_by(|a, b| a.0.cmp(&b.0));
    files.dedup_by(|a, b| a.0 == b.0);
    let mut builder = tar::Builder::new(Vec::new());
    let io = |e| SceneError::io(name, e);
    let mut add = |path: &str, bytes: &[u8]| {
        let mut header = tar::Header::new_ustar();
        header.set_size(bytes.len() as u64);
        header.set_mode(0o644);
        header.set_entry_type(tar::EntryType::Regular);
        builder.append_data(&mut header, format!("{name}/{path}"), bytes)
    };
    add(SCENE_FILE, text.as_bytes()).map_err(io)?;
    for (path, bytes) in files {
        add(&path, bytes).map_err(io)?;
    }
    builder.into_inner().map_err(io)
}

/// The most files a scene folder sent as a tar may hold.
pub const FOLDER_FILES: usize = 10_000;

/// The bundle of a scene folder sent as one tar (the studio's upload; the folder the studio
/// downloads is one): its files written to a temporary folder, then bundled as `restauro scene
/// bundle` bundles a folder on disk. The scene file is the one `.toml` nearest the top. A
/// bundle archive (`scene bundle --out`) is taken as it is. Nothing in it is trusted: every
/// entry a regular file (or a directory) below the top, within the file-size limit, at most
/// [`FOLDER_FILES`]. `scene`, when given, names the scene file (its path in the tar) among
/// several.
pub fn bundle_folder_tar(
    bytes: &[u8],
    scene: Option<&str>,
    limits: &crate::limits::Limits,
) -> Result<Bundle> {
    let place = Path::new("the folder sent");
    let refuse = |problem: String| SceneError::invalid(place, "folder", problem);
    // The tar reader is a third-party parser: a panic in it is an error naming the upload.
    let entries = crate::guard::catch(|| crate::archive::entries(bytes, limits.max_file_bytes))
        .map_err(|_| refuse("it is not a readable tar archive".into()))?
        .map_err(refuse)?;
    if entries.len() > FOLDER_FILES {
        return Err(refuse(format!(
            "{} files; a scene folder may have {FOLDER_FILES}",
            entries.len()
        )));
    }
    let dir = tempfile::tempdir().map_err(|e| SceneError::io(place, e))?;
    if entries.iter().any(|(name, _)| name == "bundle.json") {
        let path = dir.path().join("bundle.tar");
        std::fs::write(&path, bytes).map_err(|e| SceneError::io(&path, e))?;
        return crate::archive::read_archive(&path, limits);
    }
    let mut scenes: Vec<(usize, String)> = Vec::new();
    for (name, data) in &entries {
        let relative = Path::new(name);
        let plain = relative.components().all(|c| matches!(c, std::path::Component::Normal(_)));
        if !plain {
            return Err(refuse(format!("`{name}` is not a path inside the folder")));
        }
        let path = dir.path().join(relative);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| SceneError::io(parent, e))?;
        }
        std::fs::write(&path, data).map_err(|e| SceneError::io(&path, e))?;
        if name.ends_with(".toml") {
            scenes.push((relative.components().count(), name.clone()));
        }
    }
    if let Some(chosen) = scene {
        if !scenes.iter().any(|s| s.1 == chosen) {
            let all: Vec<&str> = scenes.iter().map(|s| s.1.as_str()).collect();
            return Err(refuse(format!(
                "it has no scene file `{chosen}`; it has {}",
                all.join(", ")
            )));
        }
        return crate::bundle::bundle_scene(&dir.path().join(chosen), limits);
    }
    scenes.sort();
    let top: Vec<&String> = scenes.iter().filter(|s| s.0 == scenes[0].0).map(|s| &s.1).collect();
    match top.as_slice() {
        [one] => crate::bundle::bundle_scene(&dir.path().join(one), limits),
        [] => Err(refuse(format!("it has no scene file ({SCENE_FILE} or another .toml)"))),
        many => Err(refuse(format!(
            "it has {} scene files at the same level ({}); choose one",
            many.len(),
            many.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        ))),
    }
}
