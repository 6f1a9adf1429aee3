//! The benchmarks' command-line arguments (`restauro bench TARGET ...`).

use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// What to measure.
    #[arg(value_enum)]
    pub target: BenchTarget,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1920)]
    pub width: usize,
    /// Image height in pixels.
    #[arg(long, default_value_t = 1080)]
    pub height: usize,
    /// Retinex: samples per pixel.
    #[arg(long, default_value_t = 20)]
    pub paths: u32,
    /// How many times to run; the best time is reported with all of them.
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Tracer: the scene (the cluster benchmark renders the Aosta facade).
    #[arg(long, value_enum, default_value = "aosta")]
    pub scene: BenchScene,
    /// Tracer and adaptive: a scene file of your own instead of a built-in scene, rendered at --width ×
    /// --height with --spp; the path integrator uses the file's `max_depth`.
    #[arg(long, value_name = "SCENE.toml")]
    pub scene_file: Option<PathBuf>,
    /// Tracer and cluster: samples per pixel; adaptive: the cap.
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
    /// Scheduler: simulated workers, each with its own connection.
    #[arg(long, default_value_t = 300)]
    pub workers: usize,
    /// Scheduler: jobs submitted at once.
    #[arg(long, default_value_t = 4)]
    pub jobs: u32,
    /// Scheduler: tile edge in pixels.
    #[arg(long, default_value_t = 16)]
    pub tile: u32,
    /// Mesh: the sizes of the relief measured, in triangles.
    #[arg(long, value_delimiter = ',', default_value = "50000,500000,5000000")]
    pub triangles: Vec<usize>,
    /// Scheduler: the coordinator's store, a PostgreSQL database (`postgres://…`, an empty
    /// database: the benchmark's jobs stay in it; needs a `restauro` built with `--features
    /// fleet`) instead of its redb file.
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchTarget {
    /// The Brownian-path Retinex on a synthetic Mondrian.
    Retinex,
    /// The tracer: the BVH alone against whole Whitted samples, and the path integrator.
    Tracer,
    /// Adaptive sampling against a fixed count: CPU time and per-pixel error against a
    /// reference of 8 × --spp (use --spp 32 and a smaller --width/--height).
    Adaptive,
    /// A render through an embedded cluster of two workers against the same one in-process.
    Cluster,
    /// The coordinator's leases and results per second over gRPC, with simulated workers.
    Scheduler,
    /// A survey mesh of 50 k, 500 k and 5 M triangles: reading, BVH build, memory, tracing.
    Mesh,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchScene {
    /// The procedural Aosta facade.
    Aosta,
    /// About 100 000 triangles of blocks on a ground plane.
    Blocks,
}
