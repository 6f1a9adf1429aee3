//! `restauro bench`: measured speed, printed as JSON. Tests never assert wall-clock times; this
//! is where the figures in the issues' notes come from. Each target is a module: [`tracer`]
//! (the tracer against its BVH alone), [`adaptive`] (adaptive sampling against a fixed count
//! at equal error), [`mesh`] (survey meshes as they grow), [`retinex`] (the
//! seen image), [`scheduler`] (the coordinator's leases over gRPC) and [`cluster`] (a render
//! through the embedded cluster against one process). Scripts that measure beyond these (against
//! a peer renderer, light by light, growth) are in this folder's `growth/`, `lights/` and
//! `peer/`.

pub mod adaptive;
pub mod args;
pub mod cluster;
pub mod cpu;
pub mod error;
pub mod mesh;
pub mod retinex;
pub mod scheduler;
pub mod tracer;

pub use args::{BenchArgs, BenchScene, BenchTarget};
pub use error::BenchError;
pub use retinex::mondrian;

use error::io_doing;
use restauro_spectral::appearance::ChannelSpace;
use restauro_spectral::seen::Adaptation;
use std::path::PathBuf;

pub fn run(args: &BenchArgs) -> Result<String, BenchError> {
    match args.target {
        BenchTarget::Tracer => tracer::bench(args),
        BenchTarget::Adaptive => adaptive::bench(args),
        BenchTarget::Cluster => cluster::bench(args),
        BenchTarget::Scheduler => scheduler::bench(args),
        BenchTarget::Mesh => mesh::bench(args),
        BenchTarget::Retinex => {
            let mut out = String::new();
            for adaptation in [Adaptation::Light, Adaptation::Retinex(ChannelSpace::default())] {
                out += &serde_json::to_string_pretty(&retinex::seen_bench(args, adaptation)?)?;
                out += "\n";
            }
            Ok(out)
        }
    }
}

/// The Aosta facade's summer afternoon at the benchmark's size, written into a temporary folder
/// named with `prefix`; the folder goes when the returned handle drops.
fn aosta_scene(prefix: &str, args: &BenchArgs) -> Result<(tempfile::TempDir, PathBuf), BenchError> {
    let dir = tempfile::Builder::new()
        .prefix(prefix)
        .tempdir()
        .map_err(io_doing("creating a temporary folder"))?;
    let (width, height) = (args.width as u32, args.height as u32);
    let files = restauro_demo::scene_files::write_aosta(dir.path(), width, height, 1)
        .map_err(io_doing("writing the Aosta scene"))?;
    Ok((dir, files.sunny))
}
