//! `restauro bench cluster`: the throughput of a render through an embedded local cluster (a
//! coordinator and two worker processes on loopback) against the same render in one process.
//!
//! Both are timed end to end as a user runs them — `restauro render SCENE` and
//! `restauro render SCENE --in-process` — from reading the scene to the last result file on
//! disk, Retinex included, alternating so that the machine's drift affects both alike. The
//! cluster's figure therefore includes its process start-ups, the upload, each worker's scene
//! preparation and the results' trip back.

use crate::cli::{BenchArgs, Cli, Command};
use anyhow::{Context, Result, bail};
use clap::Parser;
use serde::Serialize;
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

/// One `restauro render` with these arguments, timed.
fn timed_render(args: &[String]) -> Result<f64> {
    let cli = Cli::try_parse_from(args).context("building the render command")?;
    let Command::Render(render) = &cli.command else { bail!("not a render command") };
    let started = Instant::now();
    crate::render::run(render)?;
    Ok(started.elapsed().as_secs_f64())
}

pub fn bench(args: &BenchArgs) -> Result<String> {
    let dir = tempfile::Builder::new().prefix("restauro-bench-cluster-").tempdir()?;
    let scene =
        crate::scene_cmd::write_aosta(dir.path(), args.width as u32, args.height as u32, 1)?.sunny;
    let workers = 2;
    let command = |in_process: bool| -> Vec<String> {
        let mut v: Vec<String> = vec![
            "restauro".into(),
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
