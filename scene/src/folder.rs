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
