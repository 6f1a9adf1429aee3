//! The download cache: files by content hash (`sha256/<hex>`, `blake3/<hex>`) in a user
//! folder, held under a size bound by dropping the least recently used; downloads under way in
//! `partial/`, locked, so that two processes fetching one file take turns and a broken-off
//! download resumes where it stopped.

use super::ContentHash;
use super::matches;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The cache folder and its bound.
#[derive(Clone, Debug)]
pub struct Cache {
    pub dir: PathBuf,
    pub max_bytes: u64,
}

/// A download under way: its partial file, locked for this process until dropped.
pub struct Partial {
    pub path: PathBuf,
    pub file: File,
}

impl Cache {
    fn complete_path(&self, hash: &ContentHash) -> PathBuf {
        self.dir.join(hash.algorithm.name()).join(&hash.hex)
    }

    /// The bytes cached for `hash`, checked against it (a damaged entry is dropped) and
    /// marked as used now.
    pub fn get(&self, hash: &ContentHash) -> Option<Vec<u8>> {
        let path = self.complete_path(hash);
        let bytes = std::fs::read(&path).ok()?;
        if !matches(hash, &bytes) {
            tracing::warn!(path = %path.display(), "a cached file does not match its hash; fetching it again");
            let _ = std::fs::remove_file(&path);
            return None;
        }
        if let Ok(file) = File::options().write(true).open(&path) {
            let _ = file.set_modified(SystemTime::now());
        }
        Some(bytes)
    }

    /// Opens (creating) the partial file `name` and locks it: another process downloading the
    /// same file waits here until this one is done.
    pub fn partial(&self, name: &str) -> std::io::Result<Partial> {
        let folder = self.dir.join("partial");
        std::fs::create_dir_all(&folder)?;
        let path = folder.join(name);
        let file = File::options().read(true).append(true).create(true).open(&path)?;
        file.lock()?;
        Ok(Partial { path, file })
    }

    /// Moves a finished download into the cache under `hash`, then drops the least recently
    /// used entries (never this one) until the cache is within its bound.
    pub fn store(&self, partial: Partial, hash: &ContentHash) -> std::io::Result<()> {
        let path = self.complete_path(hash);
        if let Some(folder) = path.parent() {
            std::fs::create_dir_all(folder)?;
        }
        std::fs::rename(&partial.path, &path)?;
        drop(partial);
        self.evict(&path);
        Ok(())
    }

    /// Drops the least recently used files until the cache holds at most `max_bytes`.
    fn evict(&self, keep: &Path) {
        let mut entries: Vec<(SystemTime, u64, PathBuf)> = ["sha256", "blake3"]
            .iter()
            .filter_map(|algorithm| std::fs::read_dir(self.dir.join(algorithm)).ok())
            .flatten()
            .filter_map(|entry| {
                let entry = entry.ok()?;
                let meta = entry.metadata().ok()?;
                meta.is_file().then(|| {
                    (meta.modified().unwrap_or(SystemTime::UNIX_EPOCH), meta.len(), entry.path())
                })
            })
            .collect();
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        entries.sort();
        for (_, size, path) in entries {
            if total <= self.max_bytes {
                break;
            }
            if path != keep && std::fs::remove_file(&path).is_ok() {
                tracing::info!(path = %path.display(), size, "dropped from the download cache");
                total -= size;
            }
        }
    }
}
