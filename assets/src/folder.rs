//! A bundle written back out as a scene folder, for a person: `scene.toml` (the scene as TOML,
//! the one source of truth) and `files/<hash>.<extension>` for every file it names, in one tar
//! to download. `restauro scene check` accepts the folder and `restauro render` renders it to
//! the image the bundle renders to: reading the folder back gives the same canonical scene, and
//! so the same identity (TOML writes each number in the shortest form that reads back exactly).

use crate::error::{AssetsError, Result, SENT};
use restauro_scene::SceneError;
use restauro_scene::bundle::Bundle;
use std::path::Path;

/// The folder's scene file.
pub const SCENE_FILE: &str = "scene.toml";

/// `bundle` as a tar of the folder `name/`, with `comment` (lines without `#`) atop the TOML.
pub fn folder_tar(bundle: &Bundle, name: &str, comment: &str) -> Result<Vec<u8>> {
    let refuse = |problem: String| AssetsError::FolderTar { name: name.to_owned(), problem };
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
    Ok(builder.into_inner().map_err(io)?)
}

/// The most files a scene folder sent as a tar may hold.
pub const FOLDER_FILES: usize = 10_000;

/// The most bytes a scene folder sent as a zip may unpack to, all files together (a zip's
/// entries may be compressed far below their size: the cap keeps a hostile one off the disk).
pub const ZIP_UNPACKED_BYTES: u64 = 4 << 30;

/// Whether `bytes` are a zip archive (its first local file header, or the end record of an
/// empty one: APPNOTE 6.3.10 §4.3.7, §4.3.16).
pub fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

/// The bundle of a scene folder sent as one archive, a tar or a zip (the studio's upload; the
/// folder the studio downloads is one): its files written to a temporary folder, then bundled
/// as `restauro scene bundle` bundles a folder on disk. The scene file is the one `.toml`
/// nearest the top. A bundle archive (`scene bundle --out`) is taken as it is. Nothing in it is
/// trusted: every entry a regular file (or a directory) below the top, within the file-size
/// limit, at most [`FOLDER_FILES`], a zip's at most [`ZIP_UNPACKED_BYTES`] in all. `scene`,
/// when given, names the scene file (its path in the archive) among several.
pub fn bundle_folder_archive(
    bytes: &[u8],
    scene: Option<&str>,
    limits: &restauro_scene::limits::Limits,
) -> Result<Bundle> {
    let dir = tempfile::tempdir().map_err(|e| SceneError::io(SENT, e))?;
    let names = if is_zip(bytes) {
        unpack_zip(bytes, dir.path(), limits.max_file_bytes)?
    } else {
        let entries = tar_entries(bytes, limits)?;
        if entries.iter().any(|(name, _)| name == "bundle.json") {
            let path = dir.path().join("bundle.tar");
            std::fs::write(&path, bytes).map_err(|e| SceneError::io(&path, e))?;
            return crate::archive::read_archive(&path, limits);
        }
        let mut names = Vec::new();
        for (name, data) in &entries {
            let path = inside(dir.path(), name)?;
            std::fs::write(&path, data).map_err(|e| SceneError::io(&path, e))?;
            names.push(name.clone());
        }
        names
    };
    bundle_unpacked(dir.path(), &names, scene, limits)
}

fn refuse(problem: String) -> AssetsError {
    AssetsError::Folder { problem }
}

/// The entries of a tar sent, each checked against the limits.
fn tar_entries(
    bytes: &[u8],
    limits: &restauro_scene::limits::Limits,
) -> Result<Vec<(String, Vec<u8>)>> {
    // The tar reader is a third-party parser: a panic in it is an error naming the upload.
    let entries =
        restauro_scene::guard::catch(|| crate::archive::entries(bytes, limits.max_file_bytes))
            .map_err(|_| refuse("it is not a readable tar archive".into()))?
            .map_err(|e| refuse(e.to_string()))?;
    if entries.len() > FOLDER_FILES {
        return Err(refuse(format!(
            "{} files; a scene folder may have {FOLDER_FILES}",
            entries.len()
        )));
    }
    Ok(entries)
}

/// The path in `dir` of the entry `name`, its folders made; refused unless `name` is a plain
/// relative path (no `..`, no root, no drive).
fn inside(dir: &Path, name: &str) -> Result<std::path::PathBuf> {
    let relative = Path::new(name);
    let plain = relative.components().all(|c| matches!(c, std::path::Component::Normal(_)));
    if !plain || name.is_empty() {
        return Err(refuse(format!("`{name}` is not a path inside the folder")));
    }
    let path = dir.join(relative);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| SceneError::io(parent, e))?;
    }
    Ok(path)
}

/// Unpacks a zip sent into `dir`, file by file, never holding more than one entry's buffer:
/// the names of its files. Stored and deflated entries are read; anything else (encrypted,
/// another compression, a link) is refused by name.
fn unpack_zip(bytes: &[u8], dir: &Path, max_file_bytes: u64) -> Result<Vec<String>> {
    // The zip reader is a third-party parser: a panic in it is an error naming the upload.
    restauro_scene::guard::catch(|| unpack_zip_entries(bytes, dir, max_file_bytes))
        .map_err(|_| refuse("it is not a readable zip archive".into()))?
}

fn unpack_zip_entries(bytes: &[u8], dir: &Path, max_file_bytes: u64) -> Result<Vec<String>> {
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| refuse(format!("it is not a readable zip archive: {e}")))?;
    if archive.len() > FOLDER_FILES {
        return Err(refuse(format!(
            "{} entries; a scene folder may have {FOLDER_FILES} files",
            archive.len()
        )));
    }
    let mut names = Vec::new();
    let mut total = 0u64;
    for i in 0..archive.len() {
        let mut entry = archive
            .by_index(i)
            .map_err(|e| refuse(format!("entry {i} cannot be read: {e}; send the folder as a plain zip (stored or deflated) or a tar")))?;
        let name = entry
            .name()
            .map_err(|e| refuse(format!("entry {i} has an unreadable name: {e}")))?
            .into_owned();
        if entry.is_dir() {
            continue;
        }
        if entry.is_symlink() {
            return Err(refuse(format!("`{name}` is a link, not a file")));
        }
        let path = inside(dir, &name)?;
        let mut file = std::fs::File::create(&path).map_err(|e| SceneError::io(&path, e))?;
        let room = max_file_bytes.min(ZIP_UNPACKED_BYTES - total);
        let written = std::io::copy(&mut std::io::Read::take(&mut entry, room + 1), &mut file)
            .map_err(|e| refuse(format!("`{name}` cannot be unpacked: {e}")))?;
        if written > room {
            return Err(refuse(if room < max_file_bytes {
                format!(
                    "it unpacks to more than {ZIP_UNPACKED_BYTES} bytes; send the files it needs"
                )
            } else {
                format!(
                    "`{name}` is more than {max_file_bytes} bytes, above the file-size limit; raise --max-file-mb"
                )
            }));
        }
        total += written;
        names.push(name);
    }
    Ok(names)
}

/// The bundle of the scene file among `names` (unpacked in `dir`): `scene` when given, else the
/// one `.toml` nearest the top.
fn bundle_unpacked(
    dir: &Path,
    names: &[String],
    scene: Option<&str>,
    limits: &restauro_scene::limits::Limits,
) -> Result<Bundle> {
    let mut scenes: Vec<(usize, &str)> = names
        .iter()
        .filter(|n| n.ends_with(".toml"))
        .map(|n| (Path::new(n).components().count(), n.as_str()))
        .collect();
    if let Some(chosen) = scene {
        if !scenes.iter().any(|s| s.1 == chosen) {
            let all: Vec<&str> = scenes.iter().map(|s| s.1).collect();
            return Err(refuse(format!(
                "it has no scene file `{chosen}`; it has {}",
                all.join(", ")
            )));
        }
        return crate::bundle_scene(&dir.join(chosen), limits);
    }
    scenes.sort();
    let top: Vec<&str> = scenes.iter().filter(|s| s.0 == scenes[0].0).map(|s| s.1).collect();
    match top.as_slice() {
        [one] => crate::bundle_scene(&dir.join(one), limits),
        [] => Err(refuse(format!("it has no scene file ({SCENE_FILE} or another .toml)"))),
        many => Err(refuse(format!(
            "it has {} scene files at the same level ({}); choose one",
            many.len(),
            many.join(", ")
        ))),
    }
}
