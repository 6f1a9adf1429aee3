//! Scene assets, content-addressed: each file is kept under `assets/<BLAKE3 hex>` beside the
//! store, so the same bytes are kept once whatever a scene calls them.
//!
//! An upload streams to a temporary file while it is hashed, so the coordinator never holds an
//! asset in memory; it becomes the asset (fsync, rename) only when the bytes have the hash the
//! client named, and is deleted otherwise. Uploads in progress at once share a budget of bytes
//! (`--max-upload-mb`): an upload waits for room, and is refused when none comes.

use crate::error::{FarmError, Result};
use crate::objects::{Objects, asset_key};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use tokio::io::AsyncWriteExt;
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

/// `blake3:<64 hex>.<ext>` → the hash, refusing anything else.
pub fn asset_hash(reference: &str) -> Result<&str> {
    reference
        .strip_prefix("blake3:")
        .and_then(|r| r.split_once('.').map(|(h, _)| h))
        .filter(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
        .ok_or_else(|| FarmError::AssetReference { reference: reference.to_owned() })
}

pub struct AssetStore {
    dir: PathBuf,
    /// Where every asset is kept besides `dir`, when shared (`objects`).
    objects: Arc<Objects>,
    max_file_bytes: u64,
    /// The upload budget in MiB: one permit a MiB of a declared upload.
    budget: Arc<Semaphore>,
    budget_mib: u32,
    /// How long an upload waits for room in the budget.
    wait: Duration,
}

const MIB: u64 = 1 << 20;
const PARTIAL: &str = ".partial";

impl AssetStore {
    /// The asset folder `dir` (created when new; temporary files of interrupted uploads are
    /// removed).
    pub fn open(
        dir: &Path,
        objects: Arc<Objects>,
        max_file_bytes: u64,
        budget_bytes: u64,
    ) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| FarmError::io(dir, e))?;
        for entry in std::fs::read_dir(dir).map_err(|e| FarmError::io(dir, e))? {
            let path = entry.map_err(|e| FarmError::io(dir, e))?.path();
            if path.to_string_lossy().ends_with(PARTIAL) {
                std::fs::remove_file(&path).map_err(|e| FarmError::io(&path, e))?;
            }
        }
        let budget_mib = u32::try_from(budget_bytes.div_ceil(MIB).max(1)).unwrap_or(u32::MAX >> 3);
        Ok(Self {
            dir: dir.to_owned(),
            objects,
            max_file_bytes,
            budget: Arc::new(Semaphore::new(budget_mib as usize)),
            budget_mib,
            wait: Duration::from_secs(60),
        })
    }

    /// Where the asset of `hash` is (or would be) kept.
    pub fn path(&self, hash: &str) -> PathBuf {
        self.dir.join(hash.to_ascii_lowercase())
    }

    /// Whether the asset is here, or in the object store (it is then fetched here).
    pub fn has(&self, hash: &str) -> bool {
        self.path(hash).is_file() || self.fetched(hash)
    }

    /// Fetches the asset from the object store into the folder: whether it is here now. A
    /// failure is logged and counts as missing, so the client uploads the file again.
    fn fetched(&self, hash: &str) -> bool {
        if !self.objects.is_shared() {
            return false;
        }
        let path = self.path(hash);
        match self.objects.fetch(&asset_key(hash), &path) {
            Ok(false) => false,
            Ok(true) => {
                // Not to be trusted more than a file on disk: kept only with its hash.
                let mut hasher = blake3::Hasher::new();
                let intact = std::fs::File::open(&path)
                    .and_then(|mut file| std::io::copy(&mut file, &mut hasher))
                    .is_ok_and(|_| hasher.finalize().to_hex().eq_ignore_ascii_case(hash));
                if !intact {
                    tracing::warn!("asset {hash}: the object store's copy is damaged; dropped");
                    let _ = std::fs::remove_file(&path);
                }
                intact
            }
            Err(e) => {
                tracing::warn!("asset {hash}: {e}");
                false
            }
        }
    }

    /// The asset's bytes, checked against its hash (a file damaged on disk is refused as
    /// missing, so it is uploaded again).
    pub fn read(&self, hash: &str) -> Result<Option<Vec<u8>>> {
        let path = self.path(hash);
        match std::fs::read(&path) {
            Ok(bytes) if blake3::hash(&bytes).to_hex().eq_ignore_ascii_case(hash) => {
                Ok(Some(bytes))
            }
            Ok(_) => {
                tracing::warn!(asset = %path.display(), "asset damaged on disk: removed");
                let _ = std::fs::remove_file(&path);
                Ok(None)
            }
            // Fetched from the object store, its hash checked there.
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && self.fetched(hash) => {
                match std::fs::read(&path) {
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
                    read => read.map(Some).map_err(|e| FarmError::io(&path, e)),
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(FarmError::io(&path, e)),
        }
    }

    /// Keeps `bytes` as the asset of `hash` (a file the studio was sent; an earlier release's
    /// store moving its assets out), in the object store too when there is one.
    pub fn keep(&self, hash: &str, bytes: &[u8]) -> std::io::Result<()> {
        let path = self.path(hash);
        restauro_image::atomic_file::write(&path, bytes)?;
        self.objects.put_file(&asset_key(hash), &path).map_err(|e| {
            let _ = std::fs::remove_file(&path);
            std::io::Error::other(e)
        })
    }

    /// Starts the upload of `reference`, announced as `declared_bytes`; waits for room in the
    /// upload budget.
    pub async fn begin(&self, reference: &str, declared_bytes: u64) -> Result<Upload> {
        let hash = asset_hash(reference)?.to_ascii_lowercase();
        let refuse =
            |problem: String| FarmError::AssetUpload { reference: reference.to_owned(), problem };
        if declared_bytes > self.max_file_bytes {
            return Err(FarmError::Limit {
                what: format!("asset {reference}"),
                value: declared_bytes,
                limit: self.max_file_bytes,
                flag: "--max-file-mb",
                fix: "make the file smaller, or raise the limit on the coordinator",
            });
        }
        let mib = u32::try_from(declared_bytes.div_ceil(MIB).max(1)).unwrap_or(u32::MAX);
        if mib > self.budget_mib {
            return Err(FarmError::Limit {
                what: format!("the upload of {reference} (MiB)"),
                value: mib.into(),
                limit: self.budget_mib.into(),
                flag: "--max-upload-mb",
                fix: "raise the coordinator's upload budget",
            });
        }
        let permit = tokio::time::timeout(self.wait, self.budget.clone().acquire_many_owned(mib))
            .await
            .map_err(|_| FarmError::Limit {
                what: "uploads in progress (MiB)".into(),
                value: u64::from(self.budget_mib - self.budget.available_permits() as u32),
                limit: self.budget_mib.into(),
                flag: "--max-upload-mb",
                fix: "retry when other uploads have finished",
            })?
            .map_err(|_| refuse("the coordinator is stopping".into()))?;
        let temporary = self.dir.join(format!("{}{PARTIAL}", uuid::Uuid::new_v4().simple()));
        let file =
            tokio::fs::File::create(&temporary).await.map_err(|e| FarmError::io(&temporary, e))?;
        Ok(Upload {
            objects: self.objects.clone(),
            reference: reference.to_owned(),
            target: self.path(&hash),
            hash,
            declared_bytes,
            written: 0,
            hasher: blake3::Hasher::new(),
            file: Some(file),
            temporary,
            _permit: permit,
        })
    }
}

/// An upload in progress: its temporary file, removed unless [`Upload::finish`] succeeds.
pub struct Upload {
    objects: Arc<Objects>,
    reference: String,
    hash: String,
    target: PathBuf,
    declared_bytes: u64,
    written: u64,
    hasher: blake3::Hasher,
    file: Option<tokio::fs::File>,
    temporary: PathBuf,
    _permit: OwnedSemaphorePermit,
}

impl Upload {
    fn refuse(&self, problem: String) -> FarmError {
        FarmError::AssetUpload { reference: self.reference.clone(), problem }
    }

    pub async fn write(&mut self, chunk: &[u8]) -> Result<()> {
        let written = self.written + chunk.len() as u64;
        if written > self.declared_bytes {
            return Err(self.refuse(format!(
                "more than the {} bytes announced; announce the file's size in the first chunk",
                self.declared_bytes
            )));
        }
        self.hasher.update(chunk);
        let file = self.file.as_mut().expect("open until finished");
        file.write_all(chunk).await.map_err(|e| FarmError::io(&self.temporary, e))?;
        self.written = written;
        Ok(())
    }

    /// Checks the size and hash, and keeps the file as the asset. Its size.
    pub async fn finish(mut self) -> Result<u64> {
        if self.written != self.declared_bytes {
            return Err(self.refuse(format!(
                "{} bytes received, {} announced; upload it again",
                self.written, self.declared_bytes
            )));
        }
        if !self.hasher.finalize().to_hex().eq_ignore_ascii_case(&self.hash) {
            return Err(
                self.refuse("the bytes received do not have this hash; upload it again".into())
            );
        }
        let mut file = self.file.take().expect("open until finished");
        file.flush().await.map_err(|e| FarmError::io(&self.temporary, e))?;
        file.sync_all().await.map_err(|e| FarmError::io(&self.temporary, e))?;
        drop(file);
        tokio::fs::rename(&self.temporary, &self.target)
            .await
            .map_err(|e| FarmError::io(&self.target, e))?;
        // In the object store before the upload is acknowledged, so a coordinator taking over
        // has it; else it is not kept at all, and the client sends it again.
        let (objects, key, target) =
            (self.objects.clone(), asset_key(&self.hash), self.target.clone());
        let put = tokio::task::spawn_blocking(move || {
            let put = objects.put_file(&key, &target);
            if put.is_err() {
                let _ = std::fs::remove_file(&target);
            }
            put
        });
        put.await.map_err(|e| FarmError::Internal(e.to_string()))??;
        Ok(self.written)
    }
}

impl Drop for Upload {
    fn drop(&mut self) {
        // Unless finished (renamed), the temporary file goes: a refused or abandoned upload
        // leaves nothing behind.
        let _ = std::fs::remove_file(&self.temporary);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(bytes: &[u8]) -> String {
        format!("blake3:{}.obj", blake3::hash(bytes).to_hex())
    }

    #[tokio::test]
    async fn an_upload_becomes_the_asset_only_with_its_hash_and_size() {
        let dir = tempfile::tempdir().unwrap();
        let store =
            AssetStore::open(dir.path(), Arc::new(Objects::Local), 1 << 20, 4 << 20).unwrap();
        let bytes = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let good = reference(bytes);
        let mut up = store.begin(&good, bytes.len() as u64).await.unwrap();
        up.write(&bytes[..10]).await.unwrap();
        up.write(&bytes[10..]).await.unwrap();
        assert_eq!(up.finish().await.unwrap(), bytes.len() as u64);
        let hash = asset_hash(&good).unwrap();
        assert_eq!(store.read(hash).unwrap().unwrap(), bytes);

        // Wrong bytes for the name, too many bytes, too few: refused, nothing left behind.
        let other = reference(b"something else");
        let mut up = store.begin(&other, bytes.len() as u64).await.unwrap();
        up.write(bytes).await.unwrap();
        assert!(up.finish().await.unwrap_err().to_string().contains("do not have this hash"));
        let mut up = store.begin(&other, 3).await.unwrap();
        assert!(up.write(bytes).await.unwrap_err().to_string().contains("more than the 3"));
        drop(up);
        let up = store.begin(&other, 3).await.unwrap();
        assert!(up.finish().await.unwrap_err().to_string().contains("0 bytes received"));
        assert!(!store.has(asset_hash(&other).unwrap()));
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "only the good asset");
    }

    #[tokio::test]
    async fn uploads_share_a_budget_and_large_ones_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let mut store =
            AssetStore::open(dir.path(), Arc::new(Objects::Local), 64 << 20, 2 << 20).unwrap();
        store.wait = Duration::from_millis(50);
        let r = reference(b"x");
        let e = store.begin(&r, 100 << 20).await.err().unwrap();
        assert!(e.to_string().contains("--max-file-mb"), "{e}");
        let e = store.begin(&r, 3 << 20).await.err().unwrap();
        assert!(e.to_string().contains("--max-upload-mb"), "{e}");
        let first = store.begin(&r, 2 << 20).await.unwrap();
        let e = store.begin(&r, 1).await.err().unwrap();
        assert!(e.to_string().contains("uploads in progress"), "{e}");
        drop(first);
        assert!(store.begin(&r, 1).await.is_ok());
        let e = store.begin("blake3:xyz.obj", 1).await.err().unwrap();
        assert!(matches!(e, FarmError::AssetReference { .. }));
    }

    #[test]
    fn a_file_damaged_on_disk_reads_as_missing() {
        let dir = tempfile::tempdir().unwrap();
        let store =
            AssetStore::open(dir.path(), Arc::new(Objects::Local), 1 << 20, 1 << 20).unwrap();
        let hash = blake3::hash(b"abc").to_hex().to_string();
        store.keep(&hash, b"abd").unwrap();
        assert_eq!(store.read(&hash).unwrap(), None);
        assert!(!store.has(&hash));
    }
}
