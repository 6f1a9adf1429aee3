//! Tiles checked: every tile is bit-identical whichever worker renders it, so a second rendering
//! on another worker proves the first (issue 40).
//!
//! * **Which results.** A worker's result is checked with the probability its trust gives:
//!   [`CheckPolicy::new_worker_rate`] until [`CheckPolicy::trust_after`] of its results were
//!   confirmed in its registration, [`CheckPolicy::rate`] after. The draw is a keyed hash of
//!   the lease (the key is the run's own and never leaves the coordinator), so a worker cannot
//!   tell which of its results will be checked, nor a checker that it is checking. A result is
//!   checked only while a worker of another identity is registered to check it.
//! * **The check.** The first result is stored as any other, and the tile waits (not done) for
//!   a worker of another identity to render it again (the scheduler's "Checking"). The two are
//!   compared byte for byte: the same bytes confirm both workers.
//! * **A dispute.** Different bytes: the check's are kept in the store's `disputed` table, and a
//!   third worker, of neither identity, renders the tile. It agrees with one: the other is
//!   quarantined, and the stored tile is the agreed bytes. It agrees with neither: nothing can
//!   be decided (three builds that differ?), the stored tile stands, and the operator is told.
//! * **Quarantine.** The worker found wrong is told so and leaves: its registration is removed,
//!   its leases go back to the queue, and every tile it rendered that no check confirmed in a
//!   running job is rendered again (except tiles of a sequence's frames already written or
//!   being written, and jobs already finished, which the log names). Its identity is kept in
//!   the store, so it cannot register again; `restauro workers` lists it with the reason, and
//!   the metric `restauro_workers_quarantined_total` counts it.
//!
//! What is not checked: a result delivered to a restarted coordinator under an earlier run's
//! lease (its renderer's trust is not known), and a tile whose check was waiting when the
//! coordinator stopped (stored, it counts as done when the job resumes).

use super::{Farm, FarmState, Next, Reported, now_unix_ms};
use crate::error::{FarmError, Result};
use crate::ids::{JobId, WorkerId};
use crate::lease::LeaseClaim;
use crate::scheduler::CheckOutcome;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use tracing::{error, info, warn};

/// How many results are rendered a second time on another worker.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckPolicy {
    /// The share of a trusted worker's results checked.
    pub rate: f64,
    /// The share of a worker's results checked until it is trusted.
    pub new_worker_rate: f64,
    /// Results confirmed by checks before a worker is trusted.
    pub trust_after: u32,
}

impl CheckPolicy {
    /// No checks: a cluster whose workers are the coordinator's own processes on one machine.
    pub const OFF: CheckPolicy = CheckPolicy { rate: 0.0, new_worker_rate: 0.0, trust_after: 0 };
}

impl Default for CheckPolicy {
    /// One result in twenty of a trusted worker, one in two until four are confirmed.
    fn default() -> Self {
        CheckPolicy { rate: 0.05, new_worker_rate: 0.5, trust_after: 4 }
    }
}

/// A quarantined worker, as the store keeps it and `restauro workers` lists it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuarantineRecord {
    pub name: String,
    /// Its identity key, 16 hex digits.
    pub identity: String,
    pub reason: String,
    pub since_unix_ms: u64,
}

/// Who a worker is across its registrations: the first 8 bytes of its identity's digest.
pub(super) fn identity_key(digest: &[u8; 32]) -> u64 {
    u64::from_le_bytes(digest[..8].try_into().expect("8 bytes"))
}

/// The identity key as `restauro workers` shows it.
fn hex(key: u64) -> String {
    format!("{key:016x}")
}

/// A uniform draw in [0, 1) from the run's check key and the lease.
fn draw(key: &[u8; 32], claim: &LeaseClaim) -> f64 {
    let mut h = blake3::Hasher::new_keyed(key);
    h.update(claim.job.as_bytes());
    h.update(&claim.tile.to_le_bytes());
    h.update(&claim.attempt.to_le_bytes());
    let bytes: [u8; 8] = h.finalize().as_bytes()[..8].try_into().expect("8 bytes");
    (u64::from_le_bytes(bytes) >> 11) as f64 / (1u64 << 53) as f64
}

/// A check's result and whom it concerns.
pub(super) struct CheckReport {
    pub claim: LeaseClaim,
    pub checker: u64,
    pub renderer: u64,
    pub disputed_by: Option<u64>,
    pub data: Vec<u8>,
}

/// What a comparison found.
enum Verdict {
    /// The check's bytes are the stored ones; a disputing worker (if any) was wrong.
    Stored { wrong: Option<u64> },
    /// The first check differed: a third rendering will settle it.
    Dispute,
    /// The disputing worker's bytes: the stored ones were wrong, and are replaced.
    Disputing { wrong: u64 },
    /// Three different renderings.
    Undecided,
}

impl Farm {
    /// Whether the result `claim` brings (a lease of this run) is to be checked.
    pub(super) fn wants_check(&self, st: &FarmState, worker: WorkerId, claim: &LeaseClaim) -> bool {
        let policy = self.config.checks;
        let Some(entry) = st.workers.get(&worker) else { return false };
        let rate =
            if entry.confirmed < policy.trust_after { policy.new_worker_rate } else { policy.rate };
        rate > 0.0
            && draw(&self.check_key, claim) < rate
            && st.scheduler.has_checker_for(entry.identity_key)
    }

    /// Compares a check's result with what the store holds, and acts on it (see the module doc).
    pub(super) async fn compare(self: &Arc<Self>, report: CheckReport) -> Result<Reported> {
        let (job, tile) = (report.claim.job.clone(), report.claim.tile);
        if self.lock().quarantine.contains_key(&report.checker) {
            // Quarantined since it took the lease: its rendering proves nothing.
            self.lock().scheduler.check_settled(&job, tile, CheckOutcome::Retry);
            self.work.notify_waiters();
            return Ok(Reported::Stale);
        }
        let verdict = match self.verdict(&report).await {
            Ok(v) => v,
            Err(e) => {
                warn!(%job, tile, "could not compare a check with the stored tile: {e}; checking again");
                self.lock().scheduler.check_settled(&job, tile, CheckOutcome::Retry);
                self.work.notify_waiters();
                return Err(e);
            }
        };
        let outcome = match verdict {
            Verdict::Stored { wrong } => {
                self.confirm(&[report.renderer, report.checker]);
                if let Some(wrong) = wrong {
                    let why = self.disagreement(&job, tile, report.renderer, report.checker);
                    self.quarantine(wrong, why);
                }
                CheckOutcome::Agreed { renderer: report.renderer }
            }
            Verdict::Dispute => {
                self.metrics.tile_checks_disputed.inc();
                let third = self.lock().scheduler.has_third_for(report.renderer, report.checker);
                let (first, second) = (hex(report.renderer), hex(report.checker));
                if third {
                    warn!(%job, tile, %first, %second,
                        "two workers rendered a tile differently; a third will settle it");
                    CheckOutcome::Disputed { by: report.checker }
                } else {
                    self.metrics.tile_checks_undecided.inc();
                    error!(%job, tile, %first, %second,
                        "two workers rendered a tile differently and no third worker is \
                         registered to settle it; the first stands. Run at least three workers \
                         for checks to find which is wrong");
                    CheckOutcome::Undecided
                }
            }
            Verdict::Disputing { wrong } => {
                let agreed = report.disputed_by.unwrap_or(report.checker);
                self.confirm(&[agreed, report.checker]);
                let why = self.disagreement(&job, tile, agreed, report.checker);
                self.quarantine(wrong, why);
                CheckOutcome::Agreed { renderer: agreed }
            }
            Verdict::Undecided => {
                self.metrics.tile_checks_undecided.inc();
                error!(%job, tile, "three workers rendered a tile three ways; the first stands. \
                    Are the workers running different builds of restauro-worker?");
                CheckOutcome::Undecided
            }
        };
        if matches!(outcome, CheckOutcome::Agreed { .. }) {
            self.metrics.tile_checks_agreed.inc();
        }
        let next = {
            let mut st = self.lock();
            let last = st.scheduler.check_settled(&job, tile, outcome);
            match outcome {
                CheckOutcome::Agreed { .. } | CheckOutcome::Undecided => {
                    Self::tile_done(&mut st, &job, tile, last)
                }
                _ => Next::default(),
            }
        };
        self.work.notify_waiters();
        self.follow(&job, next);
        Ok(Reported::Accepted)
    }

    /// Reads what the comparison needs and decides; a dispute's bytes and a replacement are
    /// written before the verdict is acted on.
    async fn verdict(self: &Arc<Self>, report: &CheckReport) -> Result<Verdict> {
        let (store, job, tile) = (self.store.clone(), report.claim.job.clone(), report.claim.tile);
        let disputed = report.disputed_by.is_some();
        let (stored, disputing) = tokio::task::spawn_blocking(move || {
            let stored = store.tile(&job, tile)?;
            let disputing = if disputed { store.disputed(&job, tile)? } else { None };
            Ok::<_, FarmError>((stored, disputing))
        })
        .await??;
        let Some(stored) = stored else {
            return Err(FarmError::Internal(format!(
                "tile {tile} of job {} was to be checked and is not in the store",
                report.claim.job
            )));
        };
        let (job, data) = (&report.claim.job, &report.data);
        let verdict = match (report.disputed_by, disputing) {
            _ if *data == stored => Verdict::Stored { wrong: report.disputed_by },
            (None, _) => {
                let (store, job, data) = (self.store.clone(), job.clone(), data.clone());
                tokio::task::spawn_blocking(move || store.put_disputed(&job, tile, &data))
                    .await??;
                Verdict::Dispute
            }
            (Some(_), Some(disputing)) if *data == disputing => {
                self.commits.put(job.clone(), tile, data.clone()).wait().await?;
                Verdict::Disputing { wrong: report.renderer }
            }
            (Some(_), _) => Verdict::Undecided,
        };
        if report.disputed_by.is_some() {
            let (store, job) = (self.store.clone(), job.clone());
            if let Err(e) =
                tokio::task::spawn_blocking(move || store.remove_disputed(&job, tile)).await?
            {
                warn!(job = %report.claim.job, tile, "could not forget a settled dispute: {e}");
            }
        }
        Ok(verdict)
    }

    /// The words the quarantine gives.
    fn disagreement(&self, job: &JobId, tile: u32, a: u64, b: u64) -> String {
        let st = self.lock();
        format!(
            "its rendering of tile {tile} of job {job} differed from the same tile rendered by \
             {} and {}",
            Self::name_of(&st, a),
            Self::name_of(&st, b)
        )
    }

    fn name_of(st: &FarmState, identity: u64) -> String {
        st.workers
            .values()
            .find(|w| w.identity_key == identity)
            .map_or_else(|| format!("worker {}", hex(identity)), |w| w.name.clone())
    }

    /// Results of these identities were confirmed by a check: they count towards their trust.
    fn confirm(&self, identities: &[u64]) {
        let mut st = self.lock();
        for entry in st.workers.values_mut() {
            if identities.contains(&entry.identity_key) {
                entry.confirmed += 1;
            }
        }
    }

    /// Quarantines the worker of `identity` (see the module doc): kept in the store, its
    /// registrations removed, its unconfirmed tiles in running jobs rendered again.
    pub(super) fn quarantine(self: &Arc<Self>, identity: u64, reason: String) {
        let mut st = self.lock();
        if st.quarantine.contains_key(&identity) {
            return;
        }
        let name = Self::name_of(&st, identity);
        let record = QuarantineRecord {
            name: name.clone(),
            identity: hex(identity),
            reason: reason.clone(),
            since_unix_ms: now_unix_ms(),
        };
        let bytes = serde_json::to_vec(&record).expect("a quarantine record is JSON");
        if let Err(e) = self.store.put_quarantine(&record.identity, &bytes) {
            warn!(worker = %name, "could not keep the quarantine in the store: {e}");
        }
        st.quarantine.insert(identity, record);
        let FarmState { scheduler, jobs, frame_done, .. } = &mut *st;
        // A sequence's frame whose tiles are all done is written, or about to be: kept.
        let keep = |job: &JobId, tile: u32| {
            let (Some(r), Some(done)) = (jobs.get(job), frame_done.get(job)) else {
                return false;
            };
            r.place(tile).is_some_and(|p| {
                p.frame < r.frames_ready
                    || done.get(p.frame as usize) == Some(&(r.frame_range(p.frame).len() as u32))
            })
        };
        let quarantined = scheduler.quarantine(identity, keep);
        st.workers.retain(|_, w| w.identity_key != identity);
        let mut redone = 0;
        for redo in &quarantined.redo {
            // The store forgets them before any new rendering can be stored (this lock is held).
            let all: Vec<u32> = redo.done.iter().chain(&redo.checking).copied().collect();
            if let Err(e) = self.store.remove_tile_list(&redo.job, &all) {
                warn!(job = %redo.job, "could not forget a quarantined worker's tiles: {e}");
            }
            for &tile in &redo.done {
                Self::tile_undone(&mut st, &redo.job, tile);
            }
            redone += all.len();
        }
        let waived = st.scheduler.waive_checks_without_checkers();
        let nexts = Self::waived_done(&mut st, waived);
        drop(st);
        self.metrics.workers_quarantined.inc();
        error!(worker = %name, identity = %hex(identity), tiles_redone = redone,
            leases_revoked = quarantined.revoked.len(),
            "worker quarantined: {reason}. Its unchecked tiles in running jobs are rendered again; \
             jobs that ended before it was found, and frames already written, may hold some");
        info!(worker = %name, "{}", FarmError::Quarantined { name: name.clone(), reason });
        for (job, next) in nexts {
            self.follow(&job, next);
        }
        self.work.notify_waiters();
        self.bump();
    }

    /// Refuses a worker registering with a quarantined identity.
    pub(super) fn check_not_quarantined(&self, identity: u64) -> Result<()> {
        match self.lock().quarantine.get(&identity) {
            Some(q) => {
                Err(FarmError::Quarantined { name: q.name.clone(), reason: q.reason.clone() })
            }
            None => Ok(()),
        }
    }

    /// The quarantined workers, oldest first.
    pub fn quarantined(&self) -> Vec<QuarantineRecord> {
        let mut out: Vec<_> = self.lock().quarantine.values().cloned().collect();
        out.sort_by_key(|q| q.since_unix_ms);
        out
    }

    /// Loads the quarantined identities from the store.
    pub(super) fn load_quarantine(&self) -> Result<()> {
        let all = self.store.quarantine().map_err(FarmError::StoreAtStart)?;
        let mut st = self.lock();
        for (key, bytes) in all {
            let parsed =
                u64::from_str_radix(&key, 16).ok().zip(serde_json::from_slice(&bytes).ok());
            match parsed {
                Some((identity, record)) => {
                    st.quarantine.insert(identity, record);
                }
                None => warn!(key, "an unreadable quarantine record in the store; ignored"),
            }
        }
        Ok(())
    }

    /// Workers left: first checks nobody can make any more are waived (the tiles are done).
    pub(super) fn waive_checks(self: &Arc<Self>) {
        let nexts = {
            let mut st = self.lock();
            let waived = st.scheduler.waive_checks_without_checkers();
            Self::waived_done(&mut st, waived)
        };
        for (job, next) in nexts {
            warn!(%job, "no worker left could check some of its tiles or settle their disputes; \
                their stored results stand");
            self.follow(&job, next);
        }
    }

    fn waived_done(st: &mut FarmState, waived: Vec<(JobId, Vec<u32>)>) -> Vec<(JobId, Next)> {
        waived
            .into_iter()
            .map(|(job, tiles)| {
                let last = st
                    .scheduler
                    .progress(&job)
                    .is_some_and(|p| p.state == crate::scheduler::Dispatch::Finished);
                let mut next = Next::default();
                for (i, &tile) in tiles.iter().enumerate() {
                    next = next.or(Self::tile_done(st, &job, tile, last && i + 1 == tiles.len()));
                }
                (job, next)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_draw_is_uniform_enough_and_depends_on_the_lease() {
        let key = [7u8; 32];
        let claim = |tile| LeaseClaim {
            job: "job-1".into(),
            tile,
            attempt: 1,
            epoch: 1,
            holder: WorkerId(1),
            ticket: [0; 32],
        };
        let draws: Vec<f64> = (0..20_000).map(|t| draw(&key, &claim(t))).collect();
        assert!(draws.iter().all(|&d| (0.0..1.0).contains(&d)));
        let below = draws.iter().filter(|&&d| d < 0.05).count() as f64 / draws.len() as f64;
        assert!((0.045..0.055).contains(&below), "{below}");
        assert_ne!(draw(&key, &claim(1)), draw(&[8u8; 32], &claim(1)));
    }
}
