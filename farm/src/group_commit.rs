//! Group commit: finished tiles that arrive while the store is busy committing are written
//! together in the next transaction, so one `fsync` acknowledges many tiles. A lone tile is
//! committed at once (no waiting for company); under load the batches grow by themselves,
//! which is what lets a few hundred workers report thousands of tiles a second while every
//! acknowledged tile stays durable.
//!
//! A job's tiles are dropped through the same queue ([`TileCommits::remove_job`]), so every tile
//! queued before the removal is written before it and none after it survives it: a late result
//! can never bring back the tiles of a job that was finished, cancelled or failed.

use crate::ids::JobId;
use crate::store::{Store, StoreError};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;
use tokio::sync::oneshot;

/// A batch stops growing at this many bytes of pixel data.
const MAX_BATCH_BYTES: usize = 64 << 20;

enum Pending {
    Tile { job: JobId, tile: u32, data: Vec<u8>, done: oneshot::Sender<Result<(), StoreError>> },
    RemoveJob { job: JobId, done: oneshot::Sender<Result<(), StoreError>> },
}

impl Pending {
    fn bytes(&self) -> usize {
        match self {
            Pending::Tile { data, .. } => data.len(),
            Pending::RemoveJob { .. } => 0,
        }
    }
}

/// The queue in front of the store's tile table, drained by one thread.
pub struct TileCommits {
    queue: Option<mpsc::Sender<Pending>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl TileCommits {
    /// Starts the committing thread; dropping the handle commits what is queued and stops it.
    /// Each transaction waits `delay` first (fault injection for tests; zero otherwise).
    pub fn start(store: Arc<Store>, delay: Duration) -> std::io::Result<TileCommits> {
        let (queue, incoming) = mpsc::channel::<Pending>();
        let thread = std::thread::Builder::new().name("store-commit".into()).spawn(move || {
            let mut next = incoming.recv().ok();
            while let Some(first) = next.take() {
                if let Pending::RemoveJob { job, done } = first {
                    let result = store.remove_tiles(&job);
                    if let Err(e) = &result {
                        tracing::warn!(job = %job, "could not drop the job's tiles: {e}");
                    }
                    let _ = done.send(result);
                    next = incoming.recv().ok();
                    continue;
                }
                // Tiles up to the next removal (or the size bound) go in one transaction.
                let mut bytes = first.bytes();
                let mut batch = vec![first];
                while bytes < MAX_BATCH_BYTES {
                    match incoming.try_recv() {
                        Ok(removal @ Pending::RemoveJob { .. }) => {
                            next = Some(removal);
                            break;
                        }
                        Ok(tile) => {
                            bytes += tile.bytes();
                            batch.push(tile);
                        }
                        Err(_) => break,
                    }
                }
                if !delay.is_zero() {
                    std::thread::sleep(delay);
                }
                let tiles: Vec<(&str, u32, &[u8])> = batch
                    .iter()
                    .filter_map(|p| match p {
                        Pending::Tile { job, tile, data, .. } => {
                            Some((&**job, *tile, data.as_slice()))
                        }
                        Pending::RemoveJob { .. } => None,
                    })
                    .collect();
                let result = store.put_tiles(&tiles);
                drop(tiles);
                tracing::trace!(tiles = batch.len(), bytes, "tiles committed");
                for p in batch {
                    if let Pending::Tile { done, .. } = p {
                        let _ = done.send(result.clone());
                    }
                }
                if next.is_none() {
                    next = incoming.recv().ok();
                }
            }
        })?;
        Ok(TileCommits { queue: Some(queue), thread: Some(thread) })
    }

    /// Queues a finished tile for the store; the receiver answers once it is durable (or not).
    /// Queuing itself never waits, so it may be done under the lock that decided to accept the
    /// tile, which is what orders it before a later removal.
    pub fn put(&self, job: JobId, tile: u32, data: Vec<u8>) -> Committed {
        let (done, committed) = oneshot::channel();
        self.send(Pending::Tile { job, tile, data, done });
        Committed(committed)
    }

    /// Queues the removal of every tile of `job`, after the tiles queued before it.
    pub fn remove_job(&self, job: JobId) -> Committed {
        let (done, committed) = oneshot::channel();
        self.send(Pending::RemoveJob { job, done });
        Committed(committed)
    }

    fn send(&self, pending: Pending) {
        // A stopped committer drops the sender, and the receiver then reports it.
        if let Some(queue) = &self.queue {
            let _ = queue.send(pending);
        }
    }
}

/// The answer of the store for one queued operation.
pub struct Committed(oneshot::Receiver<Result<(), StoreError>>);

impl Committed {
    pub async fn wait(self) -> Result<(), StoreError> {
        self.0.await.unwrap_or_else(|_| {
            Err(StoreError::Store {
                path: "store".into(),
                message: "the committing thread has stopped".into(),
            })
        })
    }
}

impl Drop for TileCommits {
    fn drop(&mut self) {
        drop(self.queue.take());
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn concurrent_tiles_are_all_committed_and_survive_reopening() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("store.redb");
        {
            let store = Arc::new(Store::open(&path).unwrap());
            let commits = Arc::new(TileCommits::start(store, Duration::ZERO).unwrap());
            let job = JobId::from("job-a");
            let mut tasks = Vec::new();
            for tile in 0..200u32 {
                let (commits, job) = (commits.clone(), job.clone());
                tasks.push(tokio::spawn(async move {
                    commits.put(job, tile, tile.to_le_bytes().repeat(3)).wait().await
                }));
            }
            for t in tasks {
                t.await.unwrap().unwrap();
            }
            // The last handle: dropping it stops the committer, which closes the store.
            drop(Arc::into_inner(commits).expect("the tasks have ended"));
        }
        let store = Store::open(&path).unwrap();
        assert_eq!(store.finished_tiles("job-a").unwrap(), (0..200).collect::<Vec<_>>());
        assert_eq!(store.tile("job-a", 137).unwrap().unwrap(), 137u32.to_le_bytes().repeat(3));
    }

    /// A removal is ordered after the tiles queued before it and before those queued after.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_removal_drops_what_came_before_it_and_nothing_after() {
        let dir = tempfile::tempdir().unwrap();
        let store = Arc::new(Store::open(&dir.path().join("store.redb")).unwrap());
        let commits = TileCommits::start(store.clone(), Duration::ZERO).unwrap();
        let job = JobId::from("job-a");
        let before: Vec<_> = (0..50).map(|t| commits.put(job.clone(), t, vec![1; 64])).collect();
        let removal = commits.remove_job(job.clone());
        let after = commits.put(job.clone(), 99, vec![2; 64]);
        for c in before {
            c.wait().await.unwrap();
        }
        removal.wait().await.unwrap();
        after.wait().await.unwrap();
        assert_eq!(store.finished_tiles("job-a").unwrap(), vec![99]);
    }
}
