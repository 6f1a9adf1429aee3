//! The scheduler's part of checking tiles (see the module doc's "Checks"): a stored result
//! waiting for a second rendering, how a comparison ended, a worker found wrong, and checks
//! that no worker left could make.

use super::{
    BTreeSet, CheckOutcome, Dispatch, JobId, Quarantined, Redo, Scheduler, Slot, TileState, reindex,
};

impl Scheduler {
    /// The accepted result of `tile` is durable and is to be checked: it waits for a worker of
    /// another identity to render the tile again. False, and nothing changes, when the tile is
    /// not being committed (the job ended meanwhile).
    pub fn committed_for_check(&mut self, job: &str, tile: u32) -> bool {
        let Some(slot) = self.committing(job, tile) else {
            return false;
        };
        let before = self.job(slot).ready_key(slot);
        let job = self.job_mut(slot);
        job.committing -= 1;
        job.checking += 1;
        job.tiles[tile as usize].state = TileState::Checking;
        job.checks.insert(tile);
        let after = job.ready_key(slot);
        reindex(&mut self.ready, before, after);
        true
    }

    /// Whether a registered worker of an identity other than `identity` could check its tile.
    pub fn has_checker_for(&self, identity: u64) -> bool {
        self.workers.values().any(|w| w.identity != identity)
    }

    /// Whether a registered worker of neither identity could settle their dispute.
    pub fn has_third_for(&self, a: u64, b: u64) -> bool {
        self.workers.values().any(|w| w.identity != a && w.identity != b)
    }

    /// How the comparison of a check's result ended (see [`CheckOutcome`]). True when the tile
    /// was the job's last (the job is then `Finished`). False, and nothing changes, when the
    /// tile is not being compared (the job ended meanwhile).
    pub fn check_settled(&mut self, job: &str, tile: u32, outcome: CheckOutcome) -> bool {
        let Some(slot) = self.tile_in(job, tile, TileState::Comparing) else {
            return false;
        };
        let before = self.job(slot).ready_key(slot);
        let entry = &mut self.job_mut(slot).tiles[tile as usize];
        let settled = match outcome {
            CheckOutcome::Agreed { renderer } => {
                entry.renderer = renderer;
                entry.disputed_by = 0;
                entry.checked = true;
                true
            }
            CheckOutcome::Undecided => true,
            CheckOutcome::Disputed { by } => {
                entry.disputed_by = by;
                false
            }
            CheckOutcome::Retry => false,
        };
        let job = self.job_mut(slot);
        if !settled {
            job.tiles[tile as usize].state = TileState::Checking;
            job.checks.insert(tile);
            let after = job.ready_key(slot);
            reindex(&mut self.ready, before, after);
            return false;
        }
        job.checking -= 1;
        let finished = self.mark_done(slot, tile);
        let after = self.job(slot).ready_key(slot);
        reindex(&mut self.ready, before, after);
        finished
    }

    /// A worker found wrong leaves the farm: every registration of `identity` is removed (its
    /// leases requeued), and in every running job the tiles it rendered that no check confirmed
    /// go back to the queue, except those `keep` names (a sequence's frame already written or
    /// being written). A tile waiting for a check that it disputed waits for another check.
    pub fn quarantine(&mut self, identity: u64, keep: impl Fn(&JobId, u32) -> bool) -> Quarantined {
        let mut registrations: Vec<_> = self
            .workers
            .iter()
            .filter(|(_, w)| w.identity == identity)
            .map(|(&id, _)| id)
            .collect();
        registrations.sort_unstable();
        let mut out = Quarantined::default();
        for worker in registrations {
            let now = self.workers[&worker].last_seen;
            out.revoked.extend(self.remove_worker(worker, now));
        }
        for slot in 0..self.jobs.len() as Slot {
            let Some(job) = self.jobs[slot as usize].as_ref() else { continue };
            if job.state != Dispatch::Running {
                continue;
            }
            let redo: Vec<u32> = (0..job.total)
                .filter(|&t| {
                    let tile = &job.tiles[t as usize];
                    tile.renderer == identity
                        && !tile.checked
                        && matches!(tile.state, TileState::Done | TileState::Checking)
                        && !keep(&job.id, t)
                })
                .collect();
            let (done, checking) =
                redo.into_iter().partition(|&t| job.tiles[t as usize].state == TileState::Done);
            let redo = Redo { job: job.id.clone(), done, checking };
            self.forget_disputes_by(slot, identity);
            if !redo.done.is_empty() || !redo.checking.is_empty() {
                for &tile in redo.done.iter().chain(&redo.checking) {
                    self.redo(slot, tile);
                }
                out.redo.push(redo);
            }
        }
        out
    }

    /// A tile whose stored result is not trusted goes back to the queue, first in its job.
    fn redo(&mut self, slot: Slot, tile: u32) {
        let before = self.job(slot).ready_key(slot);
        let job = self.job_mut(slot);
        match job.tiles[tile as usize].state {
            TileState::Done => job.done -= 1,
            TileState::Checking => {
                job.checking -= 1;
                job.checks.remove(&tile);
            }
            other => unreachable!("only a stored tile is redone, not one {other:?}"),
        }
        let entry = &mut job.tiles[tile as usize];
        entry.state = TileState::Queued;
        entry.renderer = 0;
        entry.disputed_by = 0;
        job.requeue.insert(tile);
        job.queued += 1;
        job.requeued += 1;
        self.totals.requeued += 1;
        let after = self.job(slot).ready_key(slot);
        reindex(&mut self.ready, before, after);
    }

    /// A quarantined worker's disagreement with a stored result proves nothing: the tile waits
    /// for a check of its own again.
    fn forget_disputes_by(&mut self, slot: Slot, identity: u64) {
        let job = self.job_mut(slot);
        for tile in job.tiles.iter_mut().filter(|t| t.disputed_by == identity) {
            tile.disputed_by = 0;
        }
    }

    /// To call after a worker left: a check that no registered worker can make any more (every
    /// one left is of the renderer's identity, or for a dispute, of one of the two) is waived,
    /// and the tile is done with its stored result, unchecked or undecided. The tiles waived,
    /// by job.
    pub fn waive_checks_without_checkers(&mut self) -> Vec<(JobId, Vec<u32>)> {
        let identities: BTreeSet<u64> = self.workers.values().map(|w| w.identity).collect();
        let mut out = Vec::new();
        for slot in 0..self.jobs.len() as Slot {
            let Some(job) = self.jobs[slot as usize].as_ref() else { continue };
            if job.state != Dispatch::Running || job.checks.is_empty() {
                continue;
            }
            let waived: Vec<u32> = job
                .checks
                .iter()
                .copied()
                .filter(|&t| {
                    let tile = &job.tiles[t as usize];
                    identities.iter().all(|&i| i == tile.renderer || i == tile.disputed_by)
                })
                .collect();
            if waived.is_empty() {
                continue;
            }
            let id = job.id.clone();
            let before = job.ready_key(slot);
            for &tile in &waived {
                let job = self.job_mut(slot);
                job.checks.remove(&tile);
                job.checking -= 1;
                if self.mark_done(slot, tile) {
                    break;
                }
            }
            let after = self.job(slot).ready_key(slot);
            reindex(&mut self.ready, before, after);
            out.push((id, waived));
        }
        out
    }
}
