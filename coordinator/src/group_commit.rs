//! Group commit: finished tiles that arrive while the store is busy committing are written
//! together in the next transaction, so one `fsync` acknowledges many tiles. A lone tile is
//! committed at once (no waiting for company); under load the batches grow by themselves,
//! which is what lets a few hundred workers report thousands of tiles a second while every
//! acknowledged tile stays durable.

use crate::store::{Store, StoreError};
use std::sync::Arc;
use std::sync::mpsc;
use tokio::sync::oneshot;

/// A batch stops growing at this many bytes of pixel data.
const MAX_BATCH_BYTES: usize = 64 << 20;

struct Pending {
    job: Arc<str>,
    tile: u32,
    data: Vec<u8>,
    done: oneshot::Sender<Result<(), StoreError>>,
}

/// The queue in front of the store's tile table, drained by one thread.
pub struct TileCommits {
    queue: Option<mpsc::Sender<Pending>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl TileCommits {
    /// Starts the committing thread; dropping the handle commits what is queued and stops it.
    pub fn start(store: Arc<Store>) -> std::io::Result<TileCommits> {
        let (queue, incoming) = mpsc::channel::<Pending>();
        let thread = std::thread::Builder::new().name("store-commit".into()).spawn(move || {
            while let Ok(first) = incoming.recv() {
                let mut bytes = first.data.len();
                let mut batch = vec![first];
                while bytes < MAX_BATCH_BYTES {
                    let Ok(next) = incoming.try_recv() else { break };
                    bytes += next.data.len();
                    batch.push(next);
                }
                let result =
                    store.put_tiles(batch.iter().map(|p| (&*p.job, p.tile, p.data.as_slice())));
                tracing::trace!(tiles = batch.len(), bytes, "tiles committed");
                for p in batch {
                    let _ = p.done.send(result.clone());
                }
            }
        })?;
        Ok(TileCommits { queue: Some(queue), thread: Some(thread) })
    }

    /// Stores a finished tile; returns once it is durable.
    pub async fn put(&self, job: Arc<str>, tile: u32, data: Vec<u8>) -> Result<(), StoreError> {
        let (done, committed) = oneshot::channel();
        let lost = || StoreError::Store {
            path: "store".into(),
            message: "the committing thread has stopped".into(),
        };
        let queue = self.queue.as_ref().ok_or_else(lost)?;
        queue.send(Pending { job, tile, data, done }).map_err(|_| lost())?;
        committed.await.map_err(|_| lost())?
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
            let commits = Arc::new(TileCommits::start(store).unwrap());
            let job: Arc<str> = Arc::from("job-a");
            let mut tasks = Vec::new();
            for tile in 0..200u32 {
                let (commits, job) = (commits.clone(), job.clone());
                tasks.push(tokio::spawn(async move {
                    commits.put(job, tile, tile.to_le_bytes().repeat(3)).await
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
}
