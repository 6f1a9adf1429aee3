#![allow(clippy::print_stdout)] // A benchmark: its JSON on stdout is its output.
//! Throughput of the tile scheduler: 300 workers, 4 jobs of 5,000 tiles. Each round every worker
//! leases up to 4 tiles (so ~1,200 leases are outstanding at once, as on a busy farm), then all
//! of them are completed and committed. `Instant::now()` is read for every call, as the coordinator would.
//! The scenario is repeated to get a measurable duration; setup is not timed.

use restauro_farm::scheduler::{Completion, Config, Scheduler, WorkerId};
use std::time::{Duration, Instant};

const WORKERS: u32 = 300;
const JOBS: u32 = 4;
const TILES: u32 = 5_000;
const PER_LEASE: u32 = 4;
const RUNS: u32 = 50;

fn main() {
    let mut pairs: u64 = 0;
    let mut elapsed = Duration::ZERO;
    for _ in 0..RUNS {
        let t0 = Instant::now();
        let mut s = Scheduler::new(Config::default());
        let workers: Vec<WorkerId> = (0..WORKERS)
            .map(|i| s.register_worker(&format!("worker-{i}"), PER_LEASE, i as u64 + 1, t0))
            .collect();
        for j in 0..JOBS {
            let id = format!("00000000-0000-4000-8000-{j:012}");
            s.add_job(id.into(), 0, TILES, &[], t0).expect("fresh job");
        }
        let mut finished = 0;
        let mut batch = Vec::with_capacity((WORKERS * PER_LEASE) as usize);
        let start = Instant::now();
        while finished < JOBS {
            for &w in &workers {
                batch.extend(s.lease(w, PER_LEASE, Instant::now()));
            }
            assert!(!batch.is_empty(), "scheduler stalled");
            for lease in batch.drain(..) {
                match s.complete(&lease, Instant::now()) {
                    Completion::Accepted => {
                        finished += u32::from(s.committed(&lease.job, lease.tile));
                    }
                    other => panic!("unexpected completion {other:?}: nothing is checked here"),
                }
                pairs += 1;
            }
        }
        elapsed += start.elapsed();
        assert_eq!(s.pending_tiles(), 0);
    }
    assert_eq!(pairs, u64::from(RUNS * JOBS * TILES));
    let secs = elapsed.as_secs_f64();
    println!(
        "{{\"workers\":{WORKERS},\"jobs\":{JOBS},\"tiles_per_job\":{TILES},\"runs\":{RUNS},\
         \"pairs\":{pairs},\"seconds\":{secs:.4},\"pairs_per_sec\":{:.0}}}",
        pairs as f64 / secs
    );
}
