//! The load benchmark and soak of issue 35: `cargo run -p restauro-tests --bin load -- [OPTIONS]`
//! puts studio sessions, command-line clients and hostile callers on a real coordinator with two
//! workers (the binaries of `target/debug`: build them first with `cargo build --workspace`)
//! and prints what it saw as JSON: latency per kind of request, the coordinator's memory over
//! time, and whether every honest job was bit-identical to the in-process render. Exits 1 when
//! a job differed or failed, or a studio request went unanswered.
//!
//! Options (each `--name value`): `--sessions 200`, `--clients 50`, `--slow-readers 96`,
//! `--stalled-uploads 4`, `--unread-event-streams 20`, and for a soak `--soak-minutes 60` with
//! `--kill-worker-every-s 90` and `--kill-coordinator-every-s 300`.

use restauro_tests::load::{LoadPlan, Soak, run};
use std::time::Duration;

fn main() {
    let mut plan = LoadPlan::issue();
    let (mut soak_minutes, mut worker_s, mut coordinator_s) = (0.0, 90.0, 300.0);
    let args: Vec<String> = std::env::args().skip(1).collect();
    for pair in args.chunks(2) {
        let [name, value] = pair else {
            eprintln!("load: `{}` has no value; options are `--name value`", pair[0]);
            std::process::exit(2);
        };
        let number = || -> f64 {
            value.parse().unwrap_or_else(|_| {
                eprintln!("load: {name} {value}: not a number");
                std::process::exit(2)
            })
        };
        match name.as_str() {
            "--sessions" => plan.sessions = number() as usize,
            "--clients" => plan.clients = number() as usize,
            "--slow-readers" => plan.slow_readers = number() as usize,
            "--stalled-uploads" => plan.stalled_uploads = number() as usize,
            "--unread-event-streams" => plan.unread_event_streams = number() as usize,
            "--soak-minutes" => soak_minutes = number(),
            "--kill-worker-every-s" => worker_s = number(),
            "--kill-coordinator-every-s" => coordinator_s = number(),
            other => {
                eprintln!("load: unknown option {other}");
                std::process::exit(2);
            }
        }
    }
    if soak_minutes > 0.0 {
        plan.soak = Some(Soak {
            duration: Duration::from_secs_f64(soak_minutes * 60.0),
            worker_kill_every: Duration::from_secs_f64(worker_s),
            coordinator_kill_every: Duration::from_secs_f64(coordinator_s),
        });
    }
    let dir = tempfile::tempdir().expect("a temporary folder");
    let report = run(dir.path(), &plan);
    let text = serde_json::to_string_pretty(&report.json()).expect("JSON") + "\n";
    if let Err(e) = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes()) {
        eprintln!("load: writing the report: {e}");
        std::process::exit(2);
    }
    let whole = report.jobs == report.jobs_identical
        && report.studio_requests == report.studio_answered
        && report.job_failures.is_empty();
    std::process::exit(if whole { 0 } else { 1 });
}
