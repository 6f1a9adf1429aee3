//! Why a store (the coordinator's store, its object store) cannot write, since when: shown in
//! `restauro jobs`, the metrics and `/readyz` until writes succeed again with no failure for a
//! few seconds.

use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime};

/// A problem is over once writes have succeeded and none has failed for this long: a nearly
/// full disk may still take a small write between failing large ones.
const PROBLEM_QUIET: Duration = Duration::from_secs(3);

/// Why the store cannot write, since when, and when a write last failed.
#[derive(Clone, Debug)]
struct Problem {
    since: SystemTime,
    last: Instant,
    /// When a write last succeeded after the last failure.
    recovered: Option<Instant>,
    message: String,
}

/// A store's current problem, if any.
pub(crate) struct Problems {
    /// What the store is, in words: "store", "object store".
    kind: &'static str,
    problem: Mutex<Option<Problem>>,
}

impl Problems {
    /// The problems of a `kind` of store ("store", "object store").
    pub fn of(kind: &'static str) -> Problems {
        Problems { kind, problem: Mutex::new(None) }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Option<Problem>> {
        self.problem.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A write failed with `message`; `store` names the store in the log.
    pub fn failed(&self, store: &str, message: &str) {
        let mut problem = self.lock();
        match &mut *problem {
            Some(p) => {
                p.last = Instant::now();
                p.recovered = None;
            }
            None => {
                let kind = self.kind;
                tracing::error!(store, "the {kind} cannot be written: {message}; retrying");
                *problem = Some(Problem {
                    since: SystemTime::now(),
                    last: Instant::now(),
                    recovered: None,
                    message: message.to_owned(),
                });
            }
        }
    }

    /// A write succeeded.
    pub fn succeeded(&self) {
        if let Some(p) = &mut *self.lock() {
            p.recovered = Some(Instant::now());
        }
    }

    /// The problem in words, naming `store`, until it is over.
    pub fn describe(&self, store: &str) -> Option<String> {
        let mut problem = self.lock();
        if problem
            .as_ref()
            .is_some_and(|p| p.recovered.is_some() && p.last.elapsed() >= PROBLEM_QUIET)
        {
            *problem = None;
            tracing::info!(store, "the {} can be written again", self.kind);
        }
        problem.as_ref().map(|p| {
            let seconds = p.since.elapsed().map_or(0, |d| d.as_secs());
            format!("the {} {store} cannot be written ({seconds} s): {}", self.kind, p.message)
        })
    }
}
