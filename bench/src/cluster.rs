//! `restauro bench cluster`: the throughput of a render through an embedded local cluster (a
//! coordinator and two worker processes on loopback) against the same render in one process.
//!
//! Both are timed end to end as a user runs them, each a process of this executable —
//! `restauro render SCENE` and `restauro render SCENE --in-process` — from reading the scene to
//! the last result file on disk, Retinex included, alternating so that the machine's drift affects both alike. The
//! cluster's figure therefore includes its process start-ups, the upload, each worker's scene
//! preparation and the results' trip back.

use crate::args::BenchArgs;
use crate::error::{BenchError, io_doing};
use serde::Serialize;
use std::process::{Command, Stdio};
use std::time::Instant;

#[derive(Serialize)]
struct ClusterBench {
    benchmark: &'static str,
    width: usize,
    height: usize,
    samples_per_pixel: u32,
    integrator: &'static str,
    workers: usize,
    /// The tiles the image is split into (the automatic tile size, as `restauro render` picks).
    tiles: u32,
    repeats: u32,
    /// Wall-clock seconds of each in-process render.
    in_process_seconds: Vec<f64>,
    /// Wall-clock seconds of each render through the embedded cluster.
    cluster_seconds: Vec<f64>,
    in_process_median_seconds: f64,
    cluster_median_seconds: f64,
    /// The cluster's throughput as a fraction of one process's: in-process median / cluster
    /// median (the target is at least 0.95).
    throughput_ratio: f64,
    /// Tiles delivered per second through the cluster, end to end (tiles / cluster median).
    cluster_tiles_per_second: f64,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) }
}

/// One `restauro render` with these arguments, run as a user runs it (this executable, as a
/// process of its own), timed.
fn timed_render(args: &[String]) -> Result<f64, BenchError> {
    let exe = std::env::current_exe().map_err(io_doing("finding this executable"))?;
    let started = Instant::now();
    let output = Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .map_err(io_doing("running `restauro render`"))?;
    let seconds = started.elapsed().as_secs_f64();
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        return Err(BenchError::Render(stderr.trim().to_owned()));
    }
    Ok(seconds)
}

pub fn bench(args: &BenchArgs) -> Result<String, BenchError> {
    let (dir, scene) = crate::aosta_scene("restauro-bench-cluster-", args)?;
    let workers = 2;
    let command = |in_process: bool| -> Vec<String> {
        let mut v: Vec<String> = vec![
            "render".into(),
            scene.display().to_string(),
            "--out".into(),
            dir.path().join("out").display().to_string(),
            "--integrator".into(),
            "path".into(),
            "--spp".into(),
            args.spp.to_string(),
            "--workers".into(),
            workers.to_string(),
            "--progress".into(),
            "none".into(),
        ];
        if in_process {
            v.push("--in-process".into());
        }
        v
    };
    let (mut in_process_seconds, mut cluster_seconds) = (Vec::new(), Vec::new());
    for i in 0..args.repeats.max(1) {
        // Alternate which goes first, so neither always follows the other.
        for in_process in if i % 2 == 0 { [true, false] } else { [false, true] } {
            let seconds = timed_render(&command(in_process))?;
            if in_process { &mut in_process_seconds } else { &mut cluster_seconds }.push(seconds);
        }
    }
    let (a, b) = (median(&in_process_seconds), median(&cluster_seconds));
    let tiles = restauro_scene::plan::tile_count(
        args.width as u32,
        args.height as u32,
        restauro_scene::plan::auto_tile(args.width as u32, args.height as u32),
    );
    let report = ClusterBench {
        benchmark: "cluster",
        width: args.width,
        height: args.height,
        samples_per_pixel: args.spp,
        integrator: "path",
        workers,
        tiles,
        repeats: args.repeats.max(1),
        in_process_seconds,
        cluster_seconds,
        in_process_median_seconds: a,
        cluster_median_seconds: b,
        throughput_ratio: a / b,
        cluster_tiles_per_second: f64::from(tiles) / b,
    };
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}
