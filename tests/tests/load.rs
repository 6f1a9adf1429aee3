//! Build item 5 of "trust under load": 200 studio sessions (each signs in, keeps its event
//! stream open, fetches the scene's view and preview, takes a snapshot, follows it and fetches
//! its pictures) and 50 `restauro submit --wait` clients on one coordinator with two workers,
//! while 96 readers never read a 16 MiB file, 4 uploads announce 200 MiB and send nothing, and
//! 20 event streams are never read. Every honest job must finish bit-identical (the clients' to
//! the in-process render, the snapshots to one taken on the quiet farm), every studio request
//! must be answered, and the coordinator's resident memory must stay under 512 MiB. Latencies
//! are printed, never asserted: `cargo run -p restauro-tests --bin load` is their benchmark.

use restauro_tests::load::{LoadPlan, run};

/// The coordinator's memory bound under this load: its own 60 MiB, two scene loads at once
/// (`--max-scene-loads`), 32 files being sent (`--max-downloads`, 64 KiB ahead each), the
/// studio's 470 connections and the jobs' records, with room to spare.
const MEMORY_BOUND_MIB: f64 = 512.0;

#[test]
fn two_hundred_sessions_and_fifty_clients_with_hostile_callers_among_them() {
    let dir = tempfile::tempdir().unwrap();
    let plan = LoadPlan::issue();
    let report = run(dir.path(), &plan);
    eprintln!("{}", serde_json::to_string_pretty(&report.json()).unwrap());
    assert_eq!(report.jobs, plan.sessions + plan.clients, "{:?}", report.job_failures);
    assert_eq!(report.jobs_identical, report.jobs, "{:?}", report.job_failures);
    assert_eq!(
        report.studio_answered, report.studio_requests,
        "unanswered: {:?}",
        report.studio_failures
    );
    assert!(
        report.memory_peak_mib < MEMORY_BOUND_MIB,
        "the coordinator reached {:.0} MiB",
        report.memory_peak_mib
    );
    // The hostile callers were there, and were held to their limits.
    assert!(report.slow_readers_refused > 0, "--max-downloads never acted");
    assert_eq!(report.stalled_uploads_cut, plan.stalled_uploads);
}
