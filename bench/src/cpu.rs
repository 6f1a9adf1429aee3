//! CPU time as the benchmarks count it: the process's user + system time from /proc (Linux), so
//! that the figures are per CPU-second whatever else the machine is doing.

use crate::error::BenchError;
use std::time::Instant;

/// The process's CPU time (user + system), seconds.
fn cpu_seconds() -> f64 {
    process_cpu_seconds("self")
}

/// A process's CPU time (user + system), seconds, from `/proc/<pid>/stat` (Linux; 0 elsewhere).
pub fn process_cpu_seconds(pid: &str) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let fields: Vec<&str> = after.split_whitespace().collect();
    // Fields 14 and 15 of proc_pid_stat(5) are utime and stime in clock ticks (100 per
    // second); after the command name's closing parenthesis the fields start at number 3.
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

/// The least CPU time a measurement takes: /proc counts CPU time in 10 ms ticks, so a small
/// image is traced again until a fifth of a second has passed.
const MIN_CPU_S: f64 = 0.2;

/// `f` run on `threads` threads until [`MIN_CPU_S`] of CPU time has passed: the sum of its
/// counts, the runs, and the wall and CPU seconds.
pub(crate) fn timed(
    threads: usize,
    f: impl Fn() -> u64 + Send + Sync,
) -> Result<(u64, u64, f64, f64), BenchError> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let (c0, t0) = (cpu_seconds(), Instant::now());
    let (mut sum, mut runs) = (0, 0);
    while runs == 0 || cpu_seconds() - c0 < MIN_CPU_S {
        sum += pool.install(&f);
        runs += 1;
    }
    Ok((sum, runs, t0.elapsed().as_secs_f64(), cpu_seconds() - c0))
}
