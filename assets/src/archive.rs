//! A bundle as one file to share: `restauro scene bundle SCENE --out NAME.tar` writes it, and
//! `scene check`, `render` and `submit` take it wherever they take a scene file.
//!
//! It is a plain POSIX tar (so `tar tf` lists it) of:
//! * `bundle.json` — `{"schema": "restauro.bundle/1", "id": …, "scene": …}`: the bundle's
//!   identity and its canonical scene (every file named by its BLAKE3 hash, see `bundle`);
//! * `files/<hash>` — each file the scene names, under its own hash.
//!
//! Reading trusts nothing in it: the archive must be a regular file within
//! [`ARCHIVE_FILES`] × the file-size limit, every entry a regular file named as above and
//! within the file-size limit, no name twice, every file the scene names present and hashing to
//! its name, nothing else, and the identity the one its contents give.

use crate::error::{AssetsError, Result};
use restauro_scene::SceneError;
use restauro_scene::bundle::Bundle;
use restauro_scene::limits::Limits;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// The schema of `bundle.json`.
pub const SCHEMA: &str = "restauro.bundle/1";
/// An archive may hold at most this many files' worth of the file-size limit.
pub const ARCHIVE_FILES: u64 = 64;
const MANIFEST: &str = "bundle.json";

/// Whether `path` names a bundle archive (by its extension, `.tar`).
pub fn is_archive(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tar"))
}

#[derive(serde::Serialize, serde::Deserialize)]
struct Manifest {
    schema: String,
    id: String,
    scene: serde_json::Value,
}

/// Writes `bundle` to `path` as an archive: under a temporary name, then renamed, so no reader
/// sees half of one.
pub fn write_archive(bundle: &Bundle, path: &Path) -> Result<()> {
    let io = |e| SceneError::io(path, e);
    let scene: serde_json::Value =
        serde_json::from_str(&bundle.canonical_json()).expect("a canonical scene is JSON");
    let manifest = Manifest { schema: SCHEMA.to_owned(), id: bundle.id(), scene };
    let manifest = serde_json::to_vec_pretty(&manifest).expect("a manifest serialises");
    let mut builder = tar::Builder::new(Vec::new());
    let mut add = |name: &str, bytes: &[u8]| {
        let mut header = tar::Header::new_ustar();
        header.set_size(bytes.len() as u64);
        header.set_mode(0o644);
        header.set_entry_type(tar::EntryType::Regular);
        builder.append_data(&mut header, name, bytes)
    };
    add(MANIFEST, &manifest).map_err(io)?;
    for (hash, bytes) in &bundle.files {
        add(&format!("files/{hash}"), bytes).map_err(io)?;
    }
    let bytes = builder.into_inner().map_err(io)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let temporary = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&temporary, &bytes).map_err(|e| SceneError::io(&temporary, e))?;
    std::fs::rename(&temporary, path).map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        SceneError::io(path, e).into()
    })
}

/// Reads the archive at `path` back into the bundle it holds (see the module comment for what
/// is checked).
pub fn read_archive(path: &Path, limits: &Limits) -> Result<Bundle> {
    let refuse = |problem: String| AssetsError::Archive { path: path.to_owned(), problem };
    let most = limits.max_file_bytes.saturating_mul(ARCHIVE_FILES);
    let bytes = restauro_scene::assets::read_regular_file(
        path,
        most,
        "the archive is larger than the limit allows; raise --max-file-mb",
    )?;
    // The tar reader is a third-party parser: a panic in it is an error naming the file.
    let entries = restauro_scene::guard::catch(|| entries(&bytes, limits.max_file_bytes))
        .map_err(|_| refuse("it is not a readable tar archive".into()))?
        .map_err(|e| refuse(e.to_string()))?;
    let mut files = BTreeMap::new();
    let mut manifest = None;
    for (name, data) in entries {
        if name == MANIFEST {
            manifest = Some(data);
        } else if let Some(hash) = name.strip_prefix("files/")
            && hash.len() == 64
            && hash.bytes().all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase())
        {
            files.insert(hash.to_owned(), data);
        } else {
            return Err(refuse(format!(
                "it holds `{name}`; a bundle archive holds only {MANIFEST} and files/<hash>"
            )));
        }
    }
    let manifest = manifest.ok_or_else(|| {
        refuse(format!(
            "it has no {MANIFEST}; write one with `restauro scene bundle SCENE --out FILE.tar`"
        ))
    })?;
    let manifest: Manifest = serde_json::from_slice(&manifest)
        .map_err(|e| refuse(format!("its {MANIFEST} is not a bundle manifest: {e}")))?;
    if manifest.schema != SCHEMA {
        return Err(refuse(format!(
            "its schema is `{}`; this restauro reads {SCHEMA}",
            manifest.schema
        )));
    }
    let bundle = Bundle::from_parts(&manifest.scene.to_string(), files)
        .map_err(|e| refuse(e.to_string()))?;
    let named: std::collections::BTreeSet<String> = bundle
        .references()
        .iter()
        .filter_map(|r| r.strip_prefix("blake3:").and_then(|h| h.split('.').next()))
        .map(str::to_owned)
        .collect();
    if let Some(extra) = bundle.files.keys().find(|h| !named.contains(*h)) {
        return Err(refuse(format!("it holds files/{extra}, which the scene does not name")));
    }
    if bundle.id() != manifest.id {
        return Err(refuse(format!(
            "it says it is bundle {} but its contents are bundle {}: it was changed after it \
             was written",
            manifest.id,
            bundle.id()
        )));
    }
    Ok(bundle)
}

/// Why a tar's entries cannot be taken; each message says which entry and what to do.
#[derive(Debug, thiserror::Error)]
pub(crate) enum EntryProblem {
    #[error("it is not a tar archive: {0}")]
    NotTar(std::io::Error),
    #[error("a damaged entry: {0}")]
    Damaged(std::io::Error),
    #[error("an entry with an unreadable name: {0}")]
    UnreadableName(std::io::Error),
    #[error("`{0}` is not a regular file")]
    NotRegular(String),
    #[error("`{name}` is {size} bytes, above the file-size limit; raise --max-file-mb")]
    TooBig { name: String, size: u64 },
    #[error("`{0}` is in it twice")]
    Twice(String),
    #[error("`{name}`: {source}")]
    Unreadable { name: String, source: std::io::Error },
}

/// The regular files of the tar `bytes` (directory entries skipped; anything else, or a file
/// above `max_bytes`, or a name twice, refused), each with its name.
pub(crate) fn entries(
    bytes: &[u8],
    max_bytes: u64,
) -> std::result::Result<Vec<(String, Vec<u8>)>, EntryProblem> {
    let mut archive = tar::Archive::new(bytes);
    let mut out: Vec<(String, Vec<u8>)> = Vec::new();
    for entry in archive.entries().map_err(EntryProblem::NotTar)? {
        let mut entry = entry.map_err(EntryProblem::Damaged)?;
        let name =
            entry.path().map_err(EntryProblem::UnreadableName)?.to_string_lossy().into_owned();
        let unreadable = |source| EntryProblem::Unreadable { name: name.clone(), source };
        match entry.header().entry_type() {
            tar::EntryType::Regular => {}
            tar::EntryType::Directory => continue,
            _ => return Err(EntryProblem::NotRegular(name)),
        }
        let size = entry.header().size().map_err(unreadable)?;
        if size > max_bytes {
            return Err(EntryProblem::TooBig { name, size });
        }
        if out.iter().any(|(n, _)| *n == name) {
            return Err(EntryProblem::Twice(name));
        }
        let mut data = Vec::with_capacity(size as usize);
        entry.read_to_end(&mut data).map_err(unreadable)?;
        out.push((name, data));
    }
    Ok(out)
}
