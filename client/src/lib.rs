//! The `restauro` command line as a library, so that tests run exactly what the binary runs.

pub mod bench;
pub mod bench_cluster;
pub mod bench_mesh;
pub mod bench_scheduler;
pub mod bench_tracer;
pub mod cli;
pub mod cluster;
pub mod color;
pub mod compare;
pub mod demo;
pub mod illuminance;
pub mod jobs_cmd;
pub mod progress;
pub mod render;
pub mod retinex;
pub mod scene_cmd;
pub mod scene_new;
pub mod sheet;
pub mod studio_cmd;
