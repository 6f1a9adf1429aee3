//! Where a scene's files come from: the scene's folder on disk, or an asset bundle held in
//! memory (by content hash). The loader reads every file through [`Assets`], so a worker loads
//! a bundle exactly as the client loaded the folder.

use crate::error::{Result, SceneError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A source of the files a scene refers to (shared with the thread that reads a VRML97
/// world, hence `Sync`).
pub trait Assets: Sync {
    /// The bytes of the file the scene calls `reference`; `place` says where the scene refers
    /// to it (e.g. `objects[2].mesh`), for messages.
    fn read(&self, reference: &str, place: &str) -> Result<Vec<u8>>;
    /// The scene file, for messages.
    fn scene_path(&self) -> &Path;
    /// How messages name the file the scene calls `reference`: its path, so that the user can
    /// find it (the scene's folder joined with the reference, for a folder).
    fn display_path(&self, reference: &str) -> PathBuf {
        PathBuf::from(reference)
    }
}

/// The reference of a file that the file `reference` names by the relative path `relative`
/// (a glTF's buffer `model.bin` beside `meshes/model.gltf` is `meshes/model.bin`; beside
/// `https://x.org/scan/model.gltf` it is `https://x.org/scan/model.bin`).
pub fn sibling(reference: &str, relative: &str) -> Result<String, crate::web_url::UrlError> {
    if crate::web_url::is_url(relative) {
        return Ok(relative.to_owned());
    }
    if crate::web_url::is_url(reference) {
        let base = crate::web_url::WebUrl::parse(reference)?;
        return base.join(relative).map(|url| url.to_string());
    }
    let joined = match Path::new(reference).parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(folder) => folder.join(relative),
        None => PathBuf::from(relative),
    };
    // `parts/../world.wrl` is `world.wrl`: one file, one reference (an Inline's cycle is
    // found by its reference). What climbs above the scene's folder keeps its `..`, and the
    // folder refuses it.
    let mut parts: Vec<String> = Vec::new();
    for component in joined.components() {
        use std::path::Component;
        match component {
            Component::CurDir => {}
            Component::ParentDir if parts.last().is_some_and(|p| p != "..") => {
                parts.pop();
            }
            Component::ParentDir => parts.push("..".into()),
            Component::RootDir => parts.push(String::new()),
            other => parts.push(other.as_os_str().to_string_lossy().into_owned()),
        }
    }
    Ok(parts.join("/"))
}

/// How to raise [`crate::limits::Limits::max_file_bytes`].
pub const MAX_FILE_FIX: &str = "simplify the file or raise the limit with --max-file-mb";

/// Read the whole of the regular file at `path` (symbolic links followed), at most `max_bytes`;
/// `fix` says how to raise that limit.
///
/// Anything else is refused before it is opened: opening a FIFO blocks until something writes
/// to it, and a device such as `/dev/zero` never ends. The size is checked again while reading,
/// so a file that grows after the check cannot exceed the limit either.
pub fn read_regular_file(path: &Path, max_bytes: u64, fix: &str) -> Result<Vec<u8>> {
    use std::io::Read;
    let io = |error| SceneError::io(path, error);
    let not_regular = || {
        SceneError::invalid(
            path,
            "file type",
            "not a regular file (a FIFO, a device or a folder); give the path of an ordinary \
             file",
        )
    };
    let too_big = |size: u64| SceneError::Limit {
        path: path.to_owned(),
        what: "the file size (bytes)".into(),
        value: size,
        limit: max_bytes,
        fix: fix.into(),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > max_bytes {
        return Err(too_big(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    // The file opened may not be the one looked at (it was replaced in between).
    if !file.metadata().map_err(io)?.is_file() {
        return Err(not_regular());
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(max_bytes.saturating_add(1)).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The bytes of a text file as a string; where they are not UTF-8, the refusal gives the line,
/// the column and the byte offset of the first bad byte.
pub fn utf8_text(bytes: Vec<u8>, path: &Path) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let before = &bytes[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        // Characters, as editors count columns; the prefix is valid UTF-8 by construction.
        let column = String::from_utf8_lossy(&before[line_start..]).chars().count() + 1;
        SceneError::syntax(
            path,
            line,
            column,
            format!(
                "byte {at} (0x{:02x}) is not UTF-8 text; save the file as UTF-8 (or check that \
                 it is the right file)",
                bytes[at]
            ),
        )
    })
}

/// Fetches the files a scene names by URL: restauro-assets's `Remote` (over the network, into
/// a cache, each checked against its pin). The scene model reads through it and knows no network.
pub trait Fetch: Sync {
    /// The bytes at `url`, at most `max_bytes`; `place` says where the scene names it.
    fn fetch(&self, url: &str, place: &str, max_bytes: u64) -> Result<Vec<u8>>;
}

/// The files of a scene folder. References are relative to the scene file and may not leave
/// its folder (symbolic links are followed before the check), nor name the scene file itself.
/// A reference may also be a URL, read through the folder's [`Fetch`] if it has one.
pub struct FolderAssets {
    scene_file: PathBuf,
    dir: PathBuf,
    max_file_bytes: u64,
    fetch: Option<Box<dyn Fetch>>,
}

impl FolderAssets {
    pub fn new(scene_file: &Path, max_file_bytes: u64) -> Result<Self> {
        let scene_file =
            scene_file.canonicalize().map_err(|error| SceneError::io(scene_file, error))?;
        let dir = scene_file.parent().map(Path::to_owned).unwrap_or_else(|| PathBuf::from("/"));
        Ok(Self { scene_file, dir, max_file_bytes, fetch: None })
    }

    /// Reads the files named by URL through `fetch`.
    pub fn with_fetch(mut self, fetch: Box<dyn Fetch>) -> Self {
        self.fetch = Some(fetch);
        self
    }

    /// The checked path of `reference`.
    pub fn resolve(&self, reference: &str, place: &str) -> Result<PathBuf> {
        let invalid = |problem: String| SceneError::invalid(&self.scene_file, place, problem);
        if reference.trim().is_empty() {
            return Err(invalid("the file name is empty".into()));
        }
        let candidate = self.dir.join(reference);
        let resolved = candidate.canonicalize().map_err(|e| {
            invalid(format!(
                "`{reference}` cannot be opened: looked for {}, and {}",
                candidate.display(),
                crate::error::io_problem(&e)
            ))
        })?;
        if !resolved.starts_with(&self.dir) {
            return Err(invalid(format!(
                "`{reference}` leaves the scene's folder ({}); copy the file into {} and refer \
                 to it by a relative path, so that the scene travels whole",
                resolved.display(),
                self.dir.display()
            )));
        }
        if resolved == self.scene_file {
            return Err(invalid(format!("`{reference}` is the scene file itself")));
        }
        if !resolved.is_file() {
            return Err(invalid(format!("`{reference}` is not a file")));
        }
        Ok(resolved)
    }
}

impl Assets for FolderAssets {
    fn read(&self, reference: &str, place: &str) -> Result<Vec<u8>> {
        if crate::web_url::is_url(reference) {
            return match &self.fetch {
                Some(fetch) => fetch.fetch(reference, place, self.max_file_bytes),
                None => Err(SceneError::invalid(
                    &self.scene_file,
                    place,
                    format!(
                        "`{reference}` is a URL, and this reader of the folder fetches nothing; \
                         load the scene with restauro_assets::load_scene, which fetches files \
                         named by URL"
                    ),
                )),
            };
        }
        let path = self.resolve(reference, place)?;
        read_regular_file(&path, self.max_file_bytes, MAX_FILE_FIX)
    }

    fn scene_path(&self) -> &Path {
        &self.scene_file
    }

    fn display_path(&self, reference: &str) -> PathBuf {
        if crate::web_url::is_url(reference) {
            return PathBuf::from(reference);
        }
        self.dir.join(reference)
    }
}

/// The files of an asset bundle: references are `blake3:<hex>.<extension>`.
pub struct BundleAssets<'a> {
    pub name: PathBuf,
    pub files: &'a BTreeMap<String, Vec<u8>>,
}

impl Assets for BundleAssets<'_> {
    fn read(&self, reference: &str, place: &str) -> Result<Vec<u8>> {
        let hash = reference
            .strip_prefix("blake3:")
            .map(|r| r.split('.').next().unwrap_or(r))
            .ok_or_else(|| {
                SceneError::invalid(
                    &self.name,
                    place,
                    format!("`{reference}` is not a bundle reference"),
                )
            })?;
        let bytes = self.files.get(hash).ok_or_else(|| {
            SceneError::invalid(&self.name, place, format!("the bundle has no file {hash}"))
        })?;
        // Content addressing is only as good as this check.
        let actual = blake3::hash(bytes).to_hex().to_string();
        if actual != hash {
            return Err(SceneError::invalid(
                &self.name,
                place,
                format!("the file stored as {hash} hashes to {actual}; the bundle is corrupt"),
            ));
        }
        Ok(bytes.clone())
    }

    fn scene_path(&self) -> &Path {
        &self.name
    }

    fn display_path(&self, reference: &str) -> PathBuf {
        self.name.join(reference)
    }
}

/// The extension of a reference (folder path or bundle reference), lower case.
pub fn extension(reference: &str) -> String {
    // A URL's query and fragment are not part of its file name.
    let reference = match crate::web_url::is_url(reference) {
        true => reference.split(['?', '#']).next().unwrap_or(reference),
        false => reference,
    };
    Path::new(reference).extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}
