use super::*;
use std::collections::HashSet;

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// A worker's identity in these tests: one per name.
fn named(name: &str) -> u64 {
    name.bytes().fold(7, |h, b| h.wrapping_mul(31).wrapping_add(u64::from(b)))
}

fn setup() -> (Scheduler, Instant) {
    (Scheduler::new(Config::default()), Instant::now())
}

fn add(s: &mut Scheduler, id: &str, priority: i32, tiles: u32, now: Instant) {
    s.add_job(id.into(), priority, tiles, &[], now).unwrap();
}

/// Completes and commits a lease; true when it finished its job.
fn finish(s: &mut Scheduler, l: &Lease, now: Instant) -> bool {
    assert_eq!(s.complete(l, now), Completion::Accepted, "{l:?}");
    s.committed(&l.job, l.tile)
}

fn tiles_of(leases: &[Lease]) -> Vec<(String, u32)> {
    leases.iter().map(|l| (l.job.to_string(), l.tile)).collect()
}

#[test]
fn every_tile_leased_once_then_finished() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 10, t0);
    let w1 = s.register_worker("w1", 4, named("w1"), t0);
    let w2 = s.register_worker("w2", 4, named("w2"), t0);
    assert_eq!((w1, w2), (WorkerId(1), WorkerId(2)));
    let mut seen = HashSet::new();
    let mut finished = 0;
    let mut completions = 0;
    loop {
        let mut batch = s.lease(w1, 3, t0);
        batch.extend(s.lease(w2, 3, t0));
        if batch.is_empty() {
            break;
        }
        for l in &batch {
            assert_eq!(l.attempt, 1);
            assert!(seen.insert(l.tile), "tile {} leased twice", l.tile);
        }
        for l in &batch {
            completions += 1;
            if finish(&mut s, l, t0) {
                finished += 1;
                assert_eq!(completions, 10);
            }
        }
    }
    assert_eq!(seen, (0..10).collect());
    assert_eq!(finished, 1);
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.leased, p.queued, p.requeued), (10, 0, 0, 0));
    assert_eq!(p.state, Dispatch::Finished);
    assert_eq!(s.pending_tiles(), 0);
    let done: u64 = s.workers().iter().map(|w| w.done).sum();
    assert_eq!(done, 10);
}

/// The metrics' totals and gauges follow leases, completions, expiries and lost workers.
#[test]
fn totals_and_gauges_count_what_happened() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 5, t0);
    let w1 = s.register_worker("w1", 8, named("w1"), t0);
    let w2 = s.register_worker("w2", 8, named("w2"), t0);
    let first = s.lease(w1, 2, t0);
    let second = s.lease(w2, 1, t0);
    assert_eq!(s.gauges(), Gauges { queued: 2, leased: 3, workers: 2 });
    finish(&mut s, &first[0], t0);
    // Past the lease timeout: w1's other lease and w2's lease expire, and w1, silent since
    // the start, is dropped; w2 heartbeats just before.
    let later = t0 + s.config().lease_timeout.max(s.config().heartbeat_timeout) + secs(1);
    s.heartbeat(w2, later);
    assert_eq!(s.expire(later).len(), 2);
    let t = s.totals();
    let counts = (t.leased, t.done, t.lease_expiries, t.requeued, t.workers_lost);
    assert_eq!(counts, (3, 1, 2, 2, 1));
    assert_eq!(s.gauges(), Gauges { queued: 4, leased: 0, workers: 1 });
    // A late report of an expired lease is stale and not counted as done.
    assert_eq!(s.complete(&second[0], later), Completion::Stale);
    assert_eq!(s.totals().done, 1);
}

#[test]
fn higher_priority_first() {
    let (mut s, t0) = setup();
    add(&mut s, "low", 0, 3, t0);
    add(&mut s, "high", 5, 2, t0);
    let w = s.register_worker("w", 8, named("w"), t0);
    let got = tiles_of(&s.lease(w, 3, t0));
    assert_eq!(got, vec![("high".into(), 0), ("high".into(), 1), ("low".into(), 0)]);
}

#[test]
fn equal_priority_jobs_interleave() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 1, 10, t0);
    add(&mut s, "b", 1, 10, t0);
    let w1 = s.register_worker("w1", 8, named("w1"), t0);
    let w2 = s.register_worker("w2", 8, named("w2"), t0);
    let got = tiles_of(&s.lease(w1, 4, t0));
    assert_eq!(got, vec![("a".into(), 0), ("b".into(), 0), ("a".into(), 1), ("b".into(), 1)]);
    // Completing two of a's tiles makes it the job with fewer leased tiles.
    let first = s.lease(w2, 1, t0);
    assert_eq!(tiles_of(&first), vec![("a".into(), 2)]);
    s.complete(&first[0], t0);
    let more = s.lease(w2, 2, t0);
    assert_eq!(tiles_of(&more), vec![("a".into(), 3), ("b".into(), 2)]);
}

#[test]
fn expired_lease_is_requeued_and_old_completion_is_stale() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let w = s.register_worker("w", 1, named("w"), t0);
    let old = s.lease(w, 1, t0).remove(0);
    assert_eq!((old.tile, old.attempt), (0, 1));
    assert!(s.heartbeat(w, t0 + secs(10)));
    assert!(s.heartbeat(w, t0 + secs(20)));
    assert!(s.expire(t0 + secs(29)).is_empty());
    assert_eq!(s.expire(t0 + secs(30)), vec![old.clone()]);
    let p = s.progress("a").unwrap();
    assert_eq!((p.leased, p.queued, p.requeued), (0, 2, 1));
    // The requeued tile goes before the fresh tile 1.
    let new = s.lease(w, 1, t0 + secs(30)).remove(0);
    assert_eq!((new.tile, new.attempt), (0, 2));
    assert_eq!(s.complete(&old, t0 + secs(31)), Completion::Stale);
    assert_eq!(s.complete(&new, t0 + secs(31)), Completion::Accepted);
    assert!(!s.committed(&new.job, new.tile));
    assert_eq!(s.progress("a").unwrap().done, 1);
}

#[test]
fn heartbeat_timeout_removes_worker_and_requeues() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let w1 = s.register_worker("w1", 1, named("w1"), t0);
    let lost = s.lease(w1, 1, t0 + secs(1)).remove(0);
    let w2 = s.register_worker("w2", 1, named("w2"), t0 + secs(10));
    assert!(s.expire(t0 + secs(15)).is_empty());
    assert_eq!(s.expire(t0 + secs(16)), vec![lost.clone()]);
    assert!(!s.heartbeat(w1, t0 + secs(17)));
    assert!(s.lease(w1, 1, t0 + secs(17)).is_empty());
    assert_eq!(s.workers().iter().map(|w| w.id).collect::<Vec<_>>(), [w2]);
    let again = s.lease(w2, 1, t0 + secs(17)).remove(0);
    assert_eq!((again.tile, again.attempt, again.worker), (0, 2, w2));
    assert_eq!(s.complete(&lost, t0 + secs(18)), Completion::Stale);
    assert_eq!(s.progress("a").unwrap().requeued, 1);
}

#[test]
fn duplicate_completion_is_stale() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let w = s.register_worker("w", 1, named("w"), t0);
    let l = s.lease(w, 1, t0).remove(0);
    assert!(!finish(&mut s, &l, t0));
    assert_eq!(s.complete(&l, t0), Completion::Stale);
    assert_eq!(s.progress("a").unwrap().done, 1);
    assert_eq!(s.workers()[0].done, 1);
    // Someone else's lease, or an unknown job, is stale too.
    let l2 = s.lease(w, 1, t0).remove(0);
    let forged = Lease { worker: WorkerId(99), ..l2.clone() };
    assert_eq!(s.complete(&forged, t0), Completion::Stale);
    let unknown = Lease { job: "zz".into(), ..l2 };
    assert_eq!(s.complete(&unknown, t0), Completion::Stale);
}

#[test]
fn tile_failing_on_three_distinct_workers_fails_job() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let w1 = s.register_worker("w1", 1, named("w1"), t0);
    let w2 = s.register_worker("w2", 1, named("w2"), t0);
    let w3 = s.register_worker("w3", 1, named("w3"), t0);
    let w4 = s.register_worker("w4", 1, named("w4"), t0);
    let l = s.lease(w1, 1, t0).remove(0);
    assert_eq!(l.tile, 0);
    assert_eq!(s.fail(&l, "boom", t0), Failure::Requeued);
    // Same worker, same tile again: counts once for the tile.
    let l = s.lease(w1, 1, t0).remove(0);
    assert_eq!((l.tile, l.attempt), (0, 2));
    assert_eq!(s.fail(&l, "boom", t0), Failure::Requeued);
    assert_eq!(s.fail(&l, "boom", t0), Failure::Stale);
    let l = s.lease(w2, 1, t0).remove(0);
    assert_eq!((l.tile, l.attempt), (0, 3));
    assert_eq!(s.fail(&l, "bad", t0), Failure::Requeued);
    let other = s.lease(w4, 1, t0).remove(0);
    assert_eq!(other.tile, 0);
    assert!(s.give_back(&other, t0));
    let other = s.lease(w4, 2, t0);
    assert_eq!(other.iter().map(|l| l.tile).collect::<Vec<_>>(), [0, 1]);
    // Tile 0 has now failed on w1, w2 and w4 -> the job fails, with the last reason.
    let reason = "tile 0 failed on 3 workers: meh".to_owned();
    assert_eq!(s.fail(&other[0], "meh", t0), Failure::JobFailed { reason: reason.clone() });
    let p = s.progress("a").unwrap();
    assert_eq!(p.state, Dispatch::Failed(reason));
    assert_eq!(s.complete(&other[1], t0), Completion::Stale);
    assert!(s.lease(w3, 1, t0).is_empty());
    assert_eq!(s.pending_tiles(), 0);
    assert!(s.workers().iter().all(|w| w.leases == 0));
    assert_eq!(s.workers()[0].failed, 2);
}

#[test]
fn failure_reason_reported_on_the_failing_call() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let ws: Vec<_> = (0..3)
        .map(|i| s.register_worker(&format!("w{i}"), 1, named(&format!("w{i}")), t0))
        .collect();
    let mut results = Vec::new();
    for &w in &ws {
        let l = s.lease(w, 1, t0).remove(0);
        results.push(s.fail(&l, &format!("err{w}"), t0));
    }
    assert_eq!(
        results,
        vec![
            Failure::Requeued,
            Failure::Requeued,
            Failure::JobFailed { reason: "tile 0 failed on 3 workers: err3".into() }
        ]
    );
    assert_eq!(s.next_deadline(), Some(t0 + secs(15)));
}

#[test]
fn excluded_worker_still_gets_other_jobs() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 1, 10, t0);
    add(&mut s, "b", 0, 10, t0);
    let w1 = s.register_worker("w1", 4, named("w1"), t0);
    let w2 = s.register_worker("w2", 4, named("w2"), t0);
    let ls = s.lease(w1, 2, t0);
    assert_eq!(tiles_of(&ls), vec![("a".into(), 0), ("a".into(), 1)]);
    assert_eq!(s.fail(&ls[0], "missing texture", t0), Failure::Requeued);
    assert_eq!(s.fail(&ls[1], "missing texture", t0), Failure::Requeued);
    // w1 is excluded from a: it gets b's tiles although a has higher priority.
    assert_eq!(tiles_of(&s.lease(w1, 2, t0)), vec![("b".into(), 0), ("b".into(), 1)]);
    // w2 is not: it gets a's requeued tiles first.
    assert_eq!(tiles_of(&s.lease(w2, 2, t0)), vec![("a".into(), 0), ("a".into(), 1)]);
    s.cancel("b");
    // Only a has queued tiles now: w1 gets nothing, and a keeps waiting, not failed.
    assert!(s.lease(w1, 2, t0).is_empty());
    let p = s.progress("a").unwrap();
    assert_eq!((p.state, p.queued, p.leased), (Dispatch::Running, 8, 2));
    assert_eq!(s.pending_tiles(), 8);
}

#[test]
fn cancel_stales_leases_and_stops_leasing() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 5, t0);
    let w = s.register_worker("w", 2, named("w"), t0);
    let ls = s.lease(w, 2, t0);
    assert!(s.cancel("a"));
    assert!(!s.cancel("a"));
    assert!(!s.cancel("nope"));
    assert_eq!(s.complete(&ls[0], t0), Completion::Stale);
    assert_eq!(s.fail(&ls[1], "x", t0), Failure::Stale);
    assert!(!s.give_back(&ls[1], t0));
    assert!(s.lease(w, 2, t0).is_empty());
    assert_eq!(s.pending_tiles(), 0);
    assert_eq!(s.workers()[0].leases, 0);
    let p = s.progress("a").unwrap();
    assert_eq!((p.state, p.done, p.leased, p.queued), (Dispatch::Cancelled, 0, 0, 5));
    // No lease deadline is left behind; only the worker's heartbeat.
    assert_eq!(s.next_deadline(), Some(t0 + secs(15)));
    s.remove_job("a");
    assert_eq!(s.progress("a"), None);
    // The id may be used again once forgotten.
    add(&mut s, "a", 0, 1, t0);
    assert_eq!(s.lease(w, 2, t0).len(), 1);
}

#[test]
fn resume_leases_only_remaining_tiles() {
    let (mut s, t0) = setup();
    s.add_job("a".into(), 0, 5, &[0, 2, 4, 2], t0).unwrap();
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.queued), (3, 2));
    assert_eq!(s.pending_tiles(), 2);
    let w = s.register_worker("w", 8, named("w"), t0);
    let ls = s.lease(w, 8, t0);
    assert_eq!(ls.iter().map(|l| l.tile).collect::<Vec<_>>(), [1, 3]);
    assert!(!finish(&mut s, &ls[0], t0));
    assert!(finish(&mut s, &ls[1], t0));
    s.add_job("b".into(), 0, 2, &[1, 0], t0).unwrap();
    assert_eq!(s.progress("b").unwrap().state, Dispatch::Finished);
    assert_eq!(
        s.add_job("c".into(), 0, 2, &[2], t0),
        Err(AddJobError::TileOutOfRange { tile: 2, tiles: 2 })
    );
    assert_eq!(s.add_job("a".into(), 0, 2, &[], t0), Err(AddJobError::Duplicate("a".into())));
}

#[test]
fn give_back_requeues_without_failure() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 5, t0);
    let w = s.register_worker("w", 3, named("w"), t0);
    let ls = s.lease(w, 3, t0);
    assert!(s.give_back(&ls[1], t0));
    assert!(!s.give_back(&ls[1], t0));
    let p = s.progress("a").unwrap();
    assert_eq!((p.leased, p.queued, p.requeued), (2, 3, 1));
    // The handed-back tile goes first, with the next attempt.
    let again = s.lease(w, 2, t0);
    assert_eq!(again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(), [(1, 2), (3, 1)]);
    // Two more give backs by the same worker would exclude it if they counted as failures.
    assert!(s.give_back(&again[0], t0));
    assert!(s.give_back(&again[1], t0));
    assert_eq!(s.lease(w, 1, t0)[0].tile, 1);
    assert_eq!(s.workers()[0].failed, 0);
    assert_eq!(s.progress("a").unwrap().state, Dispatch::Running);
}

#[test]
fn next_deadline_tracks_leases_and_heartbeats() {
    let mut s = Scheduler::new(Config { heartbeat_timeout: secs(60), ..Config::default() });
    let t0 = Instant::now();
    assert_eq!(s.next_deadline(), None);
    add(&mut s, "a", 0, 2, t0);
    let w = s.register_worker("w", 2, named("w"), t0);
    assert_eq!(s.next_deadline(), Some(t0 + secs(60)));
    let ls = s.lease(w, 2, t0 + secs(1));
    assert_eq!(s.next_deadline(), Some(t0 + secs(31)));
    s.complete(&ls[0], t0 + secs(2));
    assert_eq!(s.next_deadline(), Some(t0 + secs(31)));
    assert_eq!(s.expire(t0 + secs(31)), vec![ls[1].clone()]);
    assert_eq!(s.next_deadline(), Some(t0 + secs(62)));
    assert!(s.expire(t0 + secs(61)).is_empty());
    assert!(s.expire(t0 + secs(62)).is_empty());
    assert!(s.workers().is_empty());
    assert_eq!(s.next_deadline(), None);
}

#[test]
fn remove_worker_returns_and_requeues_its_leases() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 4, t0);
    let w1 = s.register_worker("w1", 2, named("w1"), t0);
    let w2 = s.register_worker("w2", 2, named("w2"), t0);
    let ls = s.lease(w1, 2, t0);
    assert_eq!(s.remove_worker(w1, t0), ls);
    assert!(s.remove_worker(w1, t0).is_empty());
    let p = s.progress("a").unwrap();
    assert_eq!((p.leased, p.queued, p.requeued), (0, 4, 2));
    let again = s.lease(w2, 4, t0);
    assert_eq!(
        again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(),
        [(0, 2), (1, 2), (2, 1), (3, 1)]
    );
    assert_eq!(s.register_worker("w3", 1, named("w3"), t0), WorkerId(3));
}

/// Between acceptance and the store's commit a tile takes no other result, expires with no
/// lease and is not re-leased; it is done only once committed.
#[test]
fn an_accepted_tile_is_done_only_once_committed() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let w1 = s.register_worker("w1", 2, named("w1"), t0);
    let w2 = s.register_worker("w2", 2, named("w2"), t0);
    let l = s.lease(w1, 1, t0).remove(0);
    assert_eq!(s.complete(&l, t0), Completion::Accepted);
    assert_eq!(s.complete(&l, t0), Completion::Stale);
    assert_eq!(s.complete_inherited("a", l.tile), Completion::Stale);
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.leased, p.queued), (0, 0, 1));
    // Past every timeout: nothing of the committing tile expires, and only tile 1 is leased.
    let later = t0 + secs(100);
    s.heartbeat(w2, later);
    assert!(s.expire(later).is_empty());
    assert_eq!(tiles_of(&s.lease(w2, 2, later)), vec![("a".into(), 1)]);
    assert!(!s.committed("a", l.tile));
    assert!(!s.committed("a", l.tile), "committed twice");
    assert_eq!(s.progress("a").unwrap().done, 1);
}

/// A commit that fails gives the lease back to its worker (its result may be sent again),
/// or, for an earlier run's lease, puts the tile back at the head of the queue; against
/// nobody either way.
#[test]
fn a_failed_commit_gives_the_lease_back_or_requeues_the_tile() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 3, t0);
    let w = s.register_worker("w", 3, named("w"), t0);
    let ls = s.lease(w, 2, t0);
    assert_eq!(s.complete(&ls[1], t0), Completion::Accepted);
    s.commit_failed("a", 1, Some(&ls[1]), t0 + secs(1));
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.leased, p.queued, p.requeued), (0, 2, 1, 0));
    assert_eq!(s.workers()[0].done, 0);
    // The same result, sent again, is accepted; the lease has a new deadline.
    assert!(s.heartbeat(w, t0 + secs(29)));
    assert_eq!(s.expire(t0 + secs(30)).len(), 1, "only the other lease expired");
    assert!(!finish(&mut s, &ls[1], t0 + secs(30)));
    // An inherited result that fails to commit puts its tile back in the queue.
    assert_eq!(s.complete_inherited("a", 2), Completion::Accepted);
    s.commit_failed("a", 2, None, t0 + secs(30));
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.leased, p.queued, p.requeued), (1, 0, 2, 2));
    let again = s.lease(w, 2, t0 + secs(30));
    assert_eq!(again.iter().map(|l| (l.tile, l.attempt)).collect::<Vec<_>>(), [(0, 2), (2, 1)]);
    assert_eq!(s.workers()[0].failed, 0);
}

/// A job cancelled while a tile commits: the commit's end changes nothing.
#[test]
fn a_commit_ending_after_a_cancel_changes_nothing() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let w = s.register_worker("w", 1, named("w"), t0);
    let l = s.lease(w, 1, t0).remove(0);
    assert_eq!(s.complete(&l, t0), Completion::Accepted);
    assert!(s.cancel("a"));
    assert!(!s.committed("a", 0));
    s.commit_failed("a", 0, Some(&l), t0);
    let p = s.progress("a").unwrap();
    assert_eq!((p.state, p.done), (Dispatch::Cancelled, 0));
    assert_eq!(s.pending_tiles(), 0);
}

/// A result of a lease from a previous run of the coordinator takes a tile that is queued or
/// leased in this run (revoking that lease), never one done or committing.
#[test]
fn an_inherited_result_takes_a_tile_not_yet_done() {
    let (mut s, t0) = setup();
    s.add_job("a".into(), 0, 4, &[3], t0).unwrap();
    let w = s.register_worker("w", 4, named("w"), t0);
    let leased = s.lease(w, 1, t0).remove(0);
    assert_eq!(leased.tile, 0);
    // Tile 0 is leased in this run, tile 1 queued, tile 3 done at resume.
    assert_eq!(s.complete_inherited("a", 0), Completion::Accepted);
    assert_eq!(s.complete(&leased, t0), Completion::Stale, "the revoked lease");
    assert_eq!(s.complete_inherited("a", 1), Completion::Accepted);
    assert_eq!(s.complete_inherited("a", 1), Completion::Stale);
    assert_eq!(s.complete_inherited("a", 3), Completion::Stale);
    assert_eq!(s.complete_inherited("a", 9), Completion::Stale);
    assert_eq!(s.complete_inherited("zz", 0), Completion::Stale);
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.leased, p.queued), (1, 0, 1));
    assert_eq!(s.workers()[0].leases, 0);
    assert_eq!(tiles_of(&s.lease(w, 4, t0)), vec![("a".into(), 2)]);
    assert!(!s.committed("a", 0));
    assert!(!s.committed("a", 1));
    let last = Lease { job: "a".into(), tile: 2, attempt: 1, worker: w };
    assert!(finish(&mut s, &last, t0));
}

// ------------------------------------------------------------------ checks

/// The lease of `worker` for `job`'s tile `tile`, as the scheduler holds it.
fn leased(s: &mut Scheduler, worker: WorkerId, now: Instant) -> Lease {
    let mut got = s.lease(worker, 1, now);
    assert_eq!(got.len(), 1, "worker {worker} got {got:?}");
    got.remove(0)
}

/// Renders, stores and holds for a check the lease's tile.
fn stored_for_check(s: &mut Scheduler, l: &Lease, now: Instant) {
    assert_eq!(s.complete(l, now), Completion::Accepted);
    assert!(s.committed_for_check(&l.job, l.tile));
}

#[test]
fn a_check_goes_to_another_identity_and_the_tile_is_done_only_once_it_agrees() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let w1 = s.register_worker("w1", 1, named("w1"), t0);
    let l = leased(&mut s, w1, t0);
    stored_for_check(&mut s, &l, t0);
    assert_eq!(s.progress("a").unwrap().checking, 1);
    // The renderer, even registered again under the same identity, gets the fresh tile only.
    let again = s.register_worker("w1", 1, named("w1"), t0);
    let fresh = leased(&mut s, again, t0);
    assert_eq!(fresh.tile, 1);
    assert!(s.lease(again, 1, t0).is_empty(), "the check of its own tile went to it");
    assert!(!finish(&mut s, &fresh, t0), "a job finished with a check pending");
    let w2 = s.register_worker("w2", 1, named("w2"), t0);
    let check = leased(&mut s, w2, t0);
    assert_eq!((check.tile, check.attempt), (0, 2));
    assert_eq!(
        s.complete(&check, t0),
        Completion::Check { renderer: named("w1"), disputed_by: None }
    );
    assert!(s.check_settled("a", 0, CheckOutcome::Agreed { renderer: named("w1") }));
    assert_eq!(s.progress("a").unwrap().state, Dispatch::Finished);
}

#[test]
fn a_dispute_goes_to_a_third_identity() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let [w1, w2, w3] = ["w1", "w2", "w3"].map(|n| s.register_worker(n, 1, named(n), t0));
    let l = leased(&mut s, w1, t0);
    stored_for_check(&mut s, &l, t0);
    let check = leased(&mut s, w2, t0);
    assert!(matches!(s.complete(&check, t0), Completion::Check { disputed_by: None, .. }));
    assert!(!s.check_settled("a", 0, CheckOutcome::Disputed { by: named("w2") }));
    assert!(s.lease(w1, 1, t0).is_empty(), "the first renderer settles its own dispute");
    assert!(s.lease(w2, 1, t0).is_empty(), "the disputing checker settles its own dispute");
    let third = leased(&mut s, w3, t0);
    assert_eq!(
        s.complete(&third, t0),
        Completion::Check { renderer: named("w1"), disputed_by: Some(named("w2")) }
    );
    assert!(s.check_settled("a", 0, CheckOutcome::Agreed { renderer: named("w2") }));
}

#[test]
fn a_check_lease_that_expires_or_fails_waits_for_another_check() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let [w1, w2, w3] = ["w1", "w2", "w3"].map(|n| s.register_worker(n, 1, named(n), t0));
    let l = leased(&mut s, w1, t0);
    stored_for_check(&mut s, &l, t0);
    let check = leased(&mut s, w2, t0);
    assert_eq!(s.fail(&check, "out of memory", t0), Failure::Requeued);
    let again = leased(&mut s, w3, t0);
    s.heartbeat(w1, t0 + secs(31));
    s.heartbeat(w2, t0 + secs(31));
    let revoked = s.expire(t0 + secs(31));
    assert_eq!(tiles_of(&revoked), vec![("a".to_owned(), 0)]);
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.queued, p.checking), (0, 0, 1), "{p:?}");
    assert_eq!(s.gauges().queued, 1, "a check waiting counts in the queue's depth");
    let last = leased(&mut s, w2, t0 + secs(31));
    assert!(last.attempt > again.attempt);
    assert!(matches!(s.complete(&last, t0 + secs(31)), Completion::Check { .. }));
}

#[test]
fn a_quarantined_worker_leaves_and_its_unchecked_tiles_are_redone() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 6, t0);
    let liar = s.register_worker("liar", 4, named("liar"), t0);
    let honest = s.register_worker("honest", 4, named("honest"), t0);
    // The liar renders tiles 0..4: 0 and 1 done unchecked, 2 checked and confirmed, 3 waiting
    // for a check; the honest worker renders 4, and 5 is leased to the liar.
    let mine: Vec<Lease> = s.lease(liar, 4, t0);
    assert_eq!(tiles_of(&mine).len(), 4);
    for l in &mine[..2] {
        assert!(!finish(&mut s, l, t0));
    }
    stored_for_check(&mut s, &mine[2], t0);
    let check = leased(&mut s, honest, t0);
    assert_eq!(check.tile, 2, "the check before the fresh tile");
    assert!(matches!(s.complete(&check, t0), Completion::Check { .. }));
    assert!(!s.check_settled("a", 2, CheckOutcome::Agreed { renderer: named("liar") }));
    let four = leased(&mut s, honest, t0);
    assert_eq!(four.tile, 4);
    assert!(!finish(&mut s, &four, t0));
    stored_for_check(&mut s, &mine[3], t0);
    let five = leased(&mut s, liar, t0);
    assert_eq!(five.tile, 5, "its own tile's check went to it");
    // Tile 1 is in a written frame: kept.
    let q = s.quarantine(named("liar"), |job, tile| &**job == "a" && tile == 1);
    assert_eq!(tiles_of(&q.revoked), vec![("a".to_owned(), 5)]);
    assert_eq!(q.redo, vec![Redo { job: "a".into(), done: vec![0], checking: vec![3] }]);
    assert!(s.workers().iter().all(|w| w.id != liar));
    let p = s.progress("a").unwrap();
    // Done: 1 (kept), 2 (checked), 4 (the honest worker's); queued: 0, 3 and 5.
    assert_eq!((p.done, p.queued, p.checking), (3, 3, 0), "{p:?}");
    let redo: Vec<u32> = s.lease(honest, 4, t0).iter().map(|l| l.tile).collect();
    assert_eq!(redo, vec![0, 3, 5]);
}

#[test]
fn a_check_nobody_left_can_make_is_waived_and_a_dispute_waits_while_a_third_is_there() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 2, t0);
    let [w1, w2, w3] = ["w1", "w2", "w3"].map(|n| s.register_worker(n, 1, named(n), t0));
    let first = leased(&mut s, w1, t0);
    stored_for_check(&mut s, &first, t0);
    let second = leased(&mut s, w2, t0);
    assert_eq!(second.tile, 0, "the check first");
    assert!(matches!(s.complete(&second, t0), Completion::Check { .. }));
    assert!(!s.check_settled("a", 0, CheckOutcome::Disputed { by: named("w2") }));
    let fresh = leased(&mut s, w2, t0);
    assert_eq!(fresh.tile, 1);
    stored_for_check(&mut s, &fresh, t0);
    s.remove_worker(w1, t0);
    // w3 could check tile 1 and settle tile 0's dispute: nothing is waived.
    assert!(s.waive_checks_without_checkers().is_empty());
    assert!(s.has_third_for(named("w1"), named("w2")));
    s.remove_worker(w3, t0);
    assert!(!s.has_third_for(named("w1"), named("w2")));
    // w2 alone: it cannot check its own tile 1, nor settle its own dispute of tile 0.
    assert_eq!(s.waive_checks_without_checkers(), vec![("a".into(), vec![0, 1])]);
    let p = s.progress("a").unwrap();
    assert_eq!((p.done, p.checking, p.state.clone()), (2, 0, Dispatch::Finished), "{p:?}");
}

#[test]
fn an_undecided_check_ends_with_the_stored_result_and_a_failed_read_checks_again() {
    let (mut s, t0) = setup();
    add(&mut s, "a", 0, 1, t0);
    let [w1, w2] = ["w1", "w2"].map(|n| s.register_worker(n, 1, named(n), t0));
    let l = leased(&mut s, w1, t0);
    stored_for_check(&mut s, &l, t0);
    let check = leased(&mut s, w2, t0);
    assert!(matches!(s.complete(&check, t0), Completion::Check { .. }));
    assert!(!s.check_settled("a", 0, CheckOutcome::Retry));
    assert!(!s.check_settled("a", 0, CheckOutcome::Agreed { renderer: 1 }), "not being compared");
    let again = leased(&mut s, w2, t0);
    assert!(matches!(s.complete(&again, t0), Completion::Check { .. }));
    assert!(s.check_settled("a", 0, CheckOutcome::Undecided));
}
