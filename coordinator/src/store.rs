//! The coordinator's embedded, crash-safe store (redb: copy-on-write B-trees, a durable commit
//! per write transaction). It keeps what a restart needs to resume without rendering a finished
//! tile again: every job's record, every finished tile's pixels, and the run's identity (the
//! secret that signs leases and the count of runs, see `lease_ticket`). Scene assets are files
//! beside it (`asset_store`).
//!
//! A tile is committed before the worker is told it was accepted, so an acknowledged tile is
//! never lost; a crash between the two makes the worker's result look unacknowledged, and the
//! tile is stored a second time with the same bytes (tiles are deterministic).

use redb::{Database, ReadableDatabase, ReadableTable, TableDefinition};
use std::path::{Path, PathBuf};

/// Job id → the job's record (JSON).
const JOBS: TableDefinition<&str, &[u8]> = TableDefinition::new("jobs");
/// (job id, tile index) → the tile's pixel data.
const TILES: TableDefinition<(&str, u32), &[u8]> = TableDefinition::new("tiles");
/// Asset hash → bytes: where an earlier release kept the assets (moved to files on open).
const ASSETS: TableDefinition<&str, &[u8]> = TableDefinition::new("assets");
/// The run's identity: `secret` (32 bytes) and `epoch` (u64 little-endian).
const META: TableDefinition<&str, &[u8]> = TableDefinition::new("meta");

#[derive(Clone, Debug, thiserror::Error)]
pub enum StoreError {
    #[error("store {}: {message}", path.display())]
    Store { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, StoreError>;

pub struct Store {
    db: Database,
    path: PathBuf,
}

impl Store {
    /// Opens the store at `path`, creating it (and its tables) when new.
    pub fn open(path: &Path) -> Result<Store> {
        let fail = |e: &dyn std::fmt::Display| StoreError::Store {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let db = Database::create(path).map_err(|e| fail(&e))?;
        let store = Store { db, path: path.to_owned() };
        let txn = store.db.begin_write().map_err(|e| fail(&e))?;
        txn.open_table(JOBS).map_err(|e| fail(&e))?;
        txn.open_table(TILES).map_err(|e| fail(&e))?;
        txn.open_table(ASSETS).map_err(|e| fail(&e))?;
        txn.open_table(META).map_err(|e| fail(&e))?;
        txn.commit().map_err(|e| fail(&e))?;
        Ok(store)
    }

    /// Starts a run of the coordinator on this store: the lease-signing secret (made on the
    /// first run and kept) and this run's epoch, one more than the last run's.
    pub fn begin_run(&self, new_secret: [u8; 32]) -> Result<([u8; 32], u64)> {
        self.write(|txn| {
            let mut meta = txn.open_table(META)?;
            let secret = match meta.get("secret")? {
                Some(v) if v.value().len() == 32 => {
                    let mut s = [0u8; 32];
                    s.copy_from_slice(v.value());
                    s
                }
                _ => new_secret,
            };
            let last = meta
                .get("epoch")?
                .and_then(|v| <[u8; 8]>::try_from(v.value()).ok())
                .map_or(0, u64::from_le_bytes);
            let epoch = last + 1;
            meta.insert("secret", &secret[..])?;
            meta.insert("epoch", &epoch.to_le_bytes()[..])?;
            Ok((secret, epoch))
        })
    }

    fn fail(&self, e: impl std::fmt::Display) -> StoreError {
        StoreError::Store { path: self.path.clone(), message: e.to_string() }
    }

    fn write<T>(
        &self,
        f: impl FnOnce(&redb::WriteTransaction) -> std::result::Result<T, redb::Error>,
    ) -> Result<T> {
        let txn = self.db.begin_write().map_err(|e| self.fail(e))?;
        let value = f(&txn).map_err(|e| self.fail(e))?;
        txn.commit().map_err(|e| self.fail(e))?;
        Ok(value)
    }

    pub fn put_job(&self, id: &str, record: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(JOBS)?.insert(id, record)?;
            Ok(())
        })
    }

    /// Every job record, by id.
    pub fn jobs(&self) -> Result<Vec<(String, Vec<u8>)>> {
        let txn = self.db.begin_read().map_err(|e| self.fail(e))?;
        let table = txn.open_table(JOBS).map_err(|e| self.fail(e))?;
        let mut out = Vec::new();
        for entry in table.iter().map_err(|e| self.fail(e))? {
            let (k, v) = entry.map_err(|e| self.fail(e))?;
            out.push((k.value().to_owned(), v.value().to_vec()));
        }
        Ok(out)
    }

    /// Several finished tiles in one durable transaction (see `group_commit`).
    pub fn put_tiles<'a>(
        &self,
        tiles: impl IntoIterator<Item = (&'a str, u32, &'a [u8])>,
    ) -> Result<()> {
        self.write(|txn| {
            let mut table = txn.open_table(TILES)?;
            for (job, tile, data) in tiles {
                table.insert((job, tile), data)?;
            }
            Ok(())
        })
    }

    /// The indices of a job's finished tiles, ascending.
    pub fn finished_tiles(&self, job: &str) -> Result<Vec<u32>> {
        let txn = self.db.begin_read().map_err(|e| self.fail(e))?;
        let table = txn.open_table(TILES).map_err(|e| self.fail(e))?;
        let mut out = Vec::new();
        for entry in table.range((job, 0)..=(job, u32::MAX)).map_err(|e| self.fail(e))? {
            let (k, _) = entry.map_err(|e| self.fail(e))?;
            out.push(k.value().1);
        }
        Ok(out)
    }

    pub fn tile(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        let txn = self.db.begin_read().map_err(|e| self.fail(e))?;
        let table = txn.open_table(TILES).map_err(|e| self.fail(e))?;
        Ok(table.get((job, tile)).map_err(|e| self.fail(e))?.map(|v| v.value().to_vec()))
    }

    /// Forgets a job's tiles (its results are written; the record stays).
    pub fn remove_tiles(&self, job: &str) -> Result<()> {
        self.write(|txn| {
            let mut table = txn.open_table(TILES)?;
            table.retain_in((job, 0)..=(job, u32::MAX), |_, _| false)?;
            Ok(())
        })
    }

    /// Takes the assets an earlier release kept in the store, one at a time, for `keep` to
    /// write elsewhere; each is removed from the store once `keep` succeeded. How many moved.
    pub fn drain_legacy_assets(
        &self,
        mut keep: impl FnMut(&str, &[u8]) -> std::io::Result<()>,
    ) -> Result<usize> {
        let mut moved = 0;
        loop {
            let next = {
                let txn = self.db.begin_read().map_err(|e| self.fail(e))?;
                let table = txn.open_table(ASSETS).map_err(|e| self.fail(e))?;
                let mut iter = table.iter().map_err(|e| self.fail(e))?;
                match iter.next() {
                    Some(entry) => {
                        let (k, v) = entry.map_err(|e| self.fail(e))?;
                        Some((k.value().to_owned(), v.value().to_vec()))
                    }
                    None => None,
                }
            };
            let Some((hash, bytes)) = next else { return Ok(moved) };
            keep(&hash, &bytes).map_err(|e| self.fail(e))?;
            self.write(|txn| {
                txn.open_table(ASSETS)?.remove(hash.as_str())?;
                Ok(())
            })?;
            moved += 1;
        }
    }

    #[cfg(test)]
    fn put_legacy_asset(&self, hash: &str, data: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(ASSETS)?.insert(hash, data)?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_committed_survives_reopening() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("store.redb");
        {
            let s = Store::open(&path).unwrap();
            s.put_job("a", b"{\"x\":1}").unwrap();
            s.put_tiles([("a", 3, &[1u8, 2, 3][..])]).unwrap();
            s.put_tiles([("a", 1, &[4u8][..]), ("b", 0, &[5u8][..])]).unwrap();
            s.put_legacy_asset("00", b"v 0 0 0").unwrap();
            assert_eq!(s.begin_run([7; 32]).unwrap(), ([7; 32], 1));
        }
        let s = Store::open(&path).unwrap();
        assert_eq!(s.jobs().unwrap(), vec![("a".to_owned(), b"{\"x\":1}".to_vec())]);
        assert_eq!(s.finished_tiles("a").unwrap(), vec![1, 3]);
        assert_eq!(s.tile("a", 3).unwrap(), Some(vec![1, 2, 3]));
        assert_eq!(s.tile("a", 2).unwrap(), None);
        // The secret is kept, the epoch counts the runs.
        assert_eq!(s.begin_run([9; 32]).unwrap(), ([7; 32], 2));
        let mut moved = Vec::new();
        let keep = |h: &str, b: &[u8]| {
            moved.push((h.to_owned(), b.to_vec()));
            Ok(())
        };
        assert_eq!(s.drain_legacy_assets(keep).unwrap(), 1);
        assert_eq!(moved, [("00".to_owned(), b"v 0 0 0".to_vec())]);
        assert_eq!(s.drain_legacy_assets(|_, _| Ok(())).unwrap(), 0);
        s.remove_tiles("a").unwrap();
        assert!(s.finished_tiles("a").unwrap().is_empty());
        assert_eq!(s.finished_tiles("b").unwrap(), vec![0]);
    }
}
