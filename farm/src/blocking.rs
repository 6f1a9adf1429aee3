//! A runtime of its own for a client that the farm calls from plain threads and from async
//! tasks alike (the PostgreSQL store, the object store): each call runs on a thread of its own,
//! on this runtime, so a blocking call never enters the caller's runtime.

/// A one-thread runtime whose calls block their caller.
pub(crate) struct Blocking {
    /// Taken only when dropped (see `Drop`).
    runtime: Option<tokio::runtime::Runtime>,
}

impl Blocking {
    pub fn start(name: &str) -> std::io::Result<Blocking> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name(name)
            .enable_all()
            .build()?;
        Ok(Blocking { runtime: Some(runtime) })
    }

    /// Runs the future `work` makes to its end on this runtime, from a thread of its own.
    pub fn run<T: Send, F: Future<Output = T>>(&self, work: impl FnOnce() -> F + Send) -> T {
        let runtime = self.runtime.as_ref().expect("taken only when dropped");
        std::thread::scope(|s| {
            s.spawn(|| runtime.block_on(work()))
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    }
}

/// The client may be dropped from async code (a coordinator's start that failed): its runtime
/// is shut down without waiting there, which tokio forbids.
impl Drop for Blocking {
    fn drop(&mut self) {
        if let Some(runtime) = self.runtime.take() {
            runtime.shutdown_background();
        }
    }
}
