//! Where a scene's files come from: the scene's folder on disk, or an asset bundle held in
//! memory (by content hash). The loader reads every file through [`Assets`], so a worker loads
//! a bundle exactly as the client loaded the folder.

use crate::error::{Result, SceneError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A source of the files a scene refers to.
pub trait Assets {
    /// The bytes of the file the scene calls `reference`; `place` says where the scene refers
    /// to it (e.g. `objects[2].mesh`), for messages.
    fn read(&self, reference: &str, place: &str) -> Result<Vec<u8>>;
    /// The scene file, for messages.
    fn scene_path(&self) -> &Path;
}

/// The files of a scene folder. References are relative to the scene file and may not leave
/// its folder (symbolic links are followed before the check), nor name the scene file itself.
pub struct FolderAssets {
    scene_file: PathBuf,
    dir: PathBuf,
    max_file_bytes: u64,
}

impl FolderAssets {
    pub fn new(scene_file: &Path, max_file_bytes: u64) -> Result<Self> {
        let io = |source| SceneError::Io { path: scene_file.to_owned(), source };
        let scene_file = scene_file.canonicalize().map_err(io)?;
        let dir = scene_file.parent().map(Path::to_owned).unwrap_or_else(|| PathBuf::from("/"));
        Ok(Self { scene_file, dir, max_file_bytes })
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
                "`{reference}` cannot be opened ({e}; looked for {})",
                candidate.display()
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
        let path = self.resolve(reference, place)?;
        let io = |source| SceneError::Io { path: path.clone(), source };
        let size = std::fs::metadata(&path).map_err(io)?.len();
        if size > self.max_file_bytes {
            return Err(SceneError::Limit {
                path: path.clone(),
                what: "the file size (bytes)".into(),
                value: size,
                limit: self.max_file_bytes,
                fix: "simplify the file or raise the limit with --max-file-mb".into(),
            });
        }
        std::fs::read(&path).map_err(io)
    }

    fn scene_path(&self) -> &Path {
        &self.scene_file
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
}

/// The extension of a reference (folder path or bundle reference), lower case.
pub fn extension(reference: &str) -> String {
    Path::new(reference).extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}
