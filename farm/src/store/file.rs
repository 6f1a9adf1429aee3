//! The coordinator's embedded, crash-safe store in one file (redb: copy-on-write B-trees, a
//! durable commit per write transaction); the default. It keeps what a restart needs to resume without rendering a finished
//! tile again: every job's record, every finished tile's pixels, and the run's identity (the
//! secret that signs leases and the count of runs, see `lease`). Scene assets are files beside
//! it (`asset_store`).
//!
//! A tile is committed before the worker is told it was accepted, so an acknowledged tile is
//! never lost; a crash between the two makes the worker's result look unacknowledged, and the
//! tile is stored a second time with the same bytes (tiles are deterministic).
//!
//! **When the disk fails** (full, or a device error), redb refuses every write after the failed
//! commit until the database is opened again. The store then drops its handle and opens the
//! file again on the next call (once no transaction holds the old handle), says so in the log
//! and in [`Store::problem`] — which the coordinator shows in `restauro jobs`, its metrics and
//! `/readyz` — and clears the problem once writes succeed again with no failure for a few
//! seconds: the coordinator goes on without a restart when space returns.

use redb::{Database, ReadableDatabase, ReadableTable, TableDefinition};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Job id → the job's record (JSON).
const JOBS: TableDefinition<&str, &[u8]> = TableDefinition::new("jobs");
/// (job id, tile index) → the tile's pixel data.
const TILES: TableDefinition<(&str, u32), &[u8]> = TableDefinition::new("tiles");
/// Asset hash → bytes: where an earlier release kept the assets (moved to files on open).
const ASSETS: TableDefinition<&str, &[u8]> = TableDefinition::new("assets");
/// (job id, tile index) → a check's rendering that differed from the stored tile, kept until a
/// third rendering settles which of the two is right (`farm::checks`).
const DISPUTED: TableDefinition<(&str, u32), &[u8]> = TableDefinition::new("disputed");
/// A quarantined worker's identity key (16 hex digits) → why, as JSON (`farm::checks`).
const QUARANTINE: TableDefinition<&str, &[u8]> = TableDefinition::new("quarantine");
/// The run's identity: `secret` (32 bytes) and `epoch` (u64 little-endian).
const META: TableDefinition<&str, &[u8]> = TableDefinition::new("meta");
/// The studio's scene revisions: (scene id, revision number) → the revision's record.
const SCENE_REVISIONS: TableDefinition<(&str, u32), &[u8]> =
    TableDefinition::new("scene_revisions");

use super::{Result, StoreError};
use crate::problem::Problems;

pub struct FileStore {
    path: PathBuf,
    /// `None` after an I/O error: the next call opens the file again.
    db: Mutex<Option<Arc<Database>>>,
    problem: Problems,
}

type Fallible<T> = std::result::Result<T, redb::Error>;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl FileStore {
    /// Opens the store at `path`, creating it (and its tables) when new.
    pub fn open(path: &Path) -> Result<FileStore> {
        let db = Database::create(path)
            .map_err(|e| StoreError::Store { path: path.to_owned(), message: e.to_string() })?;
        let store = FileStore {
            path: path.to_owned(),
            db: Mutex::new(Some(Arc::new(db))),
            problem: Problems::of("store"),
        };
        store.write(|txn| {
            txn.open_table(JOBS)?;
            txn.open_table(TILES)?;
            txn.open_table(ASSETS)?;
            txn.open_table(META)?;
            txn.open_table(SCENE_REVISIONS)?;
            txn.open_table(DISPUTED)?;
            txn.open_table(QUARANTINE)?;
            Ok(())
        })?;
        Ok(store)
    }

    /// Why the store cannot write now, when it cannot.
    pub fn problem(&self) -> Option<String> {
        self.problem.describe(&self.path.display().to_string())
    }

    fn error(&self, e: impl std::fmt::Display) -> StoreError {
        StoreError::Store { path: self.path.clone(), message: e.to_string() }
    }

    /// The open database, opening the file again after an I/O error.
    fn handle(&self) -> Result<Arc<Database>> {
        let mut slot = lock(&self.db);
        if let Some(db) = &*slot {
            return Ok(db.clone());
        }
        let db = Arc::new(Database::create(&self.path).map_err(|e| self.error(e))?);
        tracing::info!(store = %self.path.display(), "store opened again");
        *slot = Some(db.clone());
        Ok(db)
    }

    /// Turns a redb error into the store's; an I/O error also drops the handle (redb refuses
    /// every later write until the database is opened again) and records the problem.
    fn failed(&self, db: &Arc<Database>, e: redb::Error) -> StoreError {
        if matches!(e, redb::Error::Io(_) | redb::Error::PreviousIo) {
            let mut slot = lock(&self.db);
            if slot.as_ref().is_some_and(|current| Arc::ptr_eq(current, db)) {
                *slot = None;
            }
            self.problem.failed(&self.path.display().to_string(), &e.to_string());
        }
        self.error(e)
    }

    fn write<T>(&self, f: impl FnOnce(&redb::WriteTransaction) -> Fallible<T>) -> Result<T> {
        let db = self.handle()?;
        let run = || -> Fallible<T> {
            let txn = db.begin_write()?;
            let value = f(&txn)?;
            txn.commit()?;
            Ok(value)
        };
        let value = run().map_err(|e| self.failed(&db, e))?;
        self.problem.succeeded();
        Ok(value)
    }

    fn read<T>(&self, f: impl FnOnce(&redb::ReadTransaction) -> Fallible<T>) -> Result<T> {
        let db = self.handle()?;
        let run = || -> Fallible<T> { f(&db.begin_read()?) };
        run().map_err(|e| self.failed(&db, e))
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

    pub fn put_job(&self, id: &str, record: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(JOBS)?.insert(id, record)?;
            Ok(())
        })
    }

    /// Every job record, by id.
    pub fn jobs(&self) -> Result<Vec<(String, Vec<u8>)>> {
        self.entries(JOBS)
    }

    /// Every entry of a table keyed by a string.
    fn entries(&self, def: TableDefinition<&str, &[u8]>) -> Result<Vec<(String, Vec<u8>)>> {
        self.read(|txn| {
            let table = txn.open_table(def)?;
            let mut out = Vec::new();
            for entry in table.iter()? {
                let (k, v) = entry?;
                out.push((k.value().to_owned(), v.value().to_vec()));
            }
            Ok(out)
        })
    }

    /// Keeps revision `number` of scene `scene`.
    pub fn put_revision(&self, scene: &str, number: u32, record: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(SCENE_REVISIONS)?.insert((scene, number), record)?;
            Ok(())
        })
    }

    /// Every scene revision: scene id, number and record, by scene and number.
    pub fn revisions(&self) -> Result<Vec<(String, u32, Vec<u8>)>> {
        self.read(|txn| {
            let table = txn.open_table(SCENE_REVISIONS)?;
            let mut out = Vec::new();
            for entry in table.iter()? {
                let (k, v) = entry?;
                let (scene, number) = k.value();
                out.push((scene.to_owned(), number, v.value().to_vec()));
            }
            Ok(out)
        })
    }

    /// Several finished tiles in one durable transaction (see `group_commit`).
    pub fn put_tiles(&self, tiles: &[(&str, u32, &[u8])]) -> Result<()> {
        self.write(|txn| {
            let mut table = txn.open_table(TILES)?;
            for &(job, tile, data) in tiles {
                table.insert((job, tile), data)?;
            }
            Ok(())
        })
    }

    /// The indices of a job's finished tiles, ascending.
    pub fn finished_tiles(&self, job: &str) -> Result<Vec<u32>> {
        self.read(|txn| {
            let table = txn.open_table(TILES)?;
            let mut out = Vec::new();
            for entry in table.range((job, 0)..=(job, u32::MAX))? {
                out.push(entry?.0.value().1);
            }
            Ok(out)
        })
    }

    pub fn tile(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        self.read(|txn| Ok(txn.open_table(TILES)?.get((job, tile))?.map(|v| v.value().to_vec())))
    }

    /// Forgets a job's tiles (its results are written; the record stays), and any disputed
    /// rendering of them.
    pub fn remove_tiles(&self, job: &str) -> Result<()> {
        self.write(|txn| {
            for def in [TILES, DISPUTED] {
                txn.open_table(def)?.retain_in((job, 0)..=(job, u32::MAX), |_, _| false)?;
            }
            Ok(())
        })
    }

    /// Forgets some tiles of a job, and any disputed rendering of them (a quarantined
    /// worker's tiles, to be rendered again).
    pub fn remove_tile_list(&self, job: &str, tiles: &[u32]) -> Result<()> {
        self.write(|txn| {
            for def in [TILES, DISPUTED] {
                let mut table = txn.open_table(def)?;
                for &tile in tiles {
                    table.remove((job, tile))?;
                }
            }
            Ok(())
        })
    }

    /// Keeps a check's rendering of a tile that differed from the stored one.
    pub fn put_disputed(&self, job: &str, tile: u32, data: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(DISPUTED)?.insert((job, tile), data)?;
            Ok(())
        })
    }

    pub fn disputed(&self, job: &str, tile: u32) -> Result<Option<Vec<u8>>> {
        self.read(|txn| Ok(txn.open_table(DISPUTED)?.get((job, tile))?.map(|v| v.value().to_vec())))
    }

    pub fn remove_disputed(&self, job: &str, tile: u32) -> Result<()> {
        self.write(|txn| {
            txn.open_table(DISPUTED)?.remove((job, tile))?;
            Ok(())
        })
    }

    /// Records a quarantined worker (`key`: its identity key in hex; `record`: why, as JSON).
    pub fn put_quarantine(&self, key: &str, record: &[u8]) -> Result<()> {
        self.write(|txn| {
            txn.open_table(QUARANTINE)?.insert(key, record)?;
            Ok(())
        })
    }

    /// Every quarantined worker: its key and its record.
    pub fn quarantine(&self) -> Result<Vec<(String, Vec<u8>)>> {
        self.entries(QUARANTINE)
    }

    /// Forgets the tiles `tiles` of a job (a sequence's frame whose files are written).
    pub fn remove_tile_range(&self, job: &str, tiles: std::ops::Range<u32>) -> Result<()> {
        if tiles.is_empty() {
            return Ok(());
        }
        self.write(|txn| {
            let mut table = txn.open_table(TILES)?;
            table.retain_in((job, tiles.start)..=(job, tiles.end - 1), |_, _| false)?;
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
            let next = self.read(|txn| {
                let table = txn.open_table(ASSETS)?;
                let first = table.iter()?.next().transpose()?;
                Ok(first.map(|(k, v)| (k.value().to_owned(), v.value().to_vec())))
            })?;
            let Some((hash, bytes)) = next else { return Ok(moved) };
            keep(&hash, &bytes).map_err(|e| self.error(e))?;
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
            let s = FileStore::open(&path).unwrap();
            s.put_job("a", b"{\"x\":1}").unwrap();
            s.put_tiles(&[("a", 3, &[1u8, 2, 3][..])]).unwrap();
            s.put_tiles(&[("a", 1, &[4u8][..]), ("b", 0, &[5u8][..])]).unwrap();
            s.put_legacy_asset("00", b"v 0 0 0").unwrap();
            assert_eq!(s.begin_run([7; 32]).unwrap(), ([7; 32], 1));
        }
        let s = FileStore::open(&path).unwrap();
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
