//! `restauro bench mesh`: what a survey mesh costs as it grows (issue 20, item 7). For each size,
//! a relief of that many triangles is written as binary PLY (the format scanners export), then
//! timed as a render prepares it: reading the scene (parsing and checking the mesh), preparing
//! it (materials, the CWBVH build), and tracing Whitted samples through it. Memory is the
//! prepared scene's own count (what a worker's scene cache charges for it) and the process's
//! peak resident set while reading and preparing, reset before each size (Linux).

use crate::args::BenchArgs;
use crate::cpu::timed;
use crate::error::{BenchError, io_doing};
use restauro_assets::load_scene;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, render_tile};
use restauro_scene::load::Limits;
use restauro_scene::scene_file::Integrator;
use serde::Serialize;
use std::io::Write;
use std::time::Instant;

#[derive(Serialize)]
struct Size {
    triangles: usize,
    file_mib: f64,
    /// Reading the scene: the PLY parsed and checked, placed in the world.
    read_s: f64,
    /// Preparing it for tracing: materials resolved, the CWBVH built.
    prepare_s: f64,
    /// The prepared scene's bytes per triangle (BVH, triangles, normals, materials).
    prepared_bytes_per_triangle: f64,
    /// The process's peak resident memory while reading and preparing, per triangle (the
    /// parser's temporary copies included).
    peak_bytes_per_triangle: Option<f64>,
    /// Whitted samples (camera ray and the sun's shadow ray) traced per CPU-second.
    rays_per_cpu_s: f64,
    /// `read_s` and `prepare_s` over n log₂ n, relative to the smallest size: at most about 1
    /// when the cost grows no worse than n log n.
    read_over_n_log_n: f64,
    prepare_over_n_log_n: f64,
}

#[derive(Serialize)]
struct MeshBench {
    benchmark: &'static str,
    threads: usize,
    width: usize,
    height: usize,
    spp: u32,
    sizes: Vec<Size>,
}

/// The process's resident memory now and at its peak, bytes, from /proc/self/status (Linux).
fn resident_bytes() -> Option<(f64, f64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let field = |name: &str| -> Option<f64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024.0)
    };
    Some((field("VmRSS:")?, field("VmHWM:")?))
}

/// Resets the peak resident memory to the current one (proc(5), clear_refs: "5").
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// A relief of about `triangles` triangles (2:1, two triangles a quad), written as binary PLY
/// with its scene into `dir`.
fn write_relief(dir: &std::path::Path, triangles: usize) -> Result<usize, BenchError> {
    let ny = ((triangles as f64 / 4.0).sqrt().round() as usize).max(1);
    let nx = (triangles / (2 * ny)).max(1);
    let path = dir.join("relief.ply");
    let writing = format!("writing {}", path.display());
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).map_err(io_doing(&writing))?);
    restauro_demo::scenes::relief::write_ply(&mut f, nx, ny).map_err(io_doing(&writing))?;
    f.flush().map_err(io_doing(&writing))?;
    std::fs::write(dir.join("scene.toml"), restauro_demo::scenes::relief::SCENE_TOML)
        .map_err(io_doing("writing the relief's scene.toml"))?;
    Ok(2 * nx * ny)
}

pub fn bench(args: &BenchArgs) -> Result<String, BenchError> {
    let say = |what: String| restauro_cluster::progress::say(&format!("bench mesh: {what}"));
    let (w, h) = (args.width, args.height);
    let mut sizes: Vec<Size> = Vec::new();
    for &asked in &args.triangles {
        let dir = tempfile::Builder::new()
            .prefix("restauro-bench-mesh-")
            .tempdir()
            .map_err(io_doing("creating a temporary folder"))?;
        say(format!("writing a relief of {asked} triangles"));
        let triangles = write_relief(dir.path(), asked)?;
        let file_mib = std::fs::metadata(dir.path().join("relief.ply"))
            .map_err(io_doing("reading relief.ply's size"))?
            .len() as f64
            / 1048576.0;
        reset_peak();
        let before = resident_bytes();
        say(format!("reading {triangles} triangles"));
        let started = Instant::now();
        let mut scene = load_scene(&dir.path().join("scene.toml"), &Limits::default())?;
        let read_s = started.elapsed().as_secs_f64();
        (scene.camera.width, scene.camera.height) = (w as u32, h as u32);
        say("preparing (the BVH)".into());
        let settings = Settings {
            integrator: Integrator::Whitted,
            samples_per_pixel: args.spp,
            max_depth: 1,
            seed: 1,
            grids: false,
            noise_target: 0.0,
        };
        let started = Instant::now();
        let prepared = PreparedScene::new(&scene, None, settings)?;
        let prepare_s = started.elapsed().as_secs_f64();
        let peak = resident_bytes().zip(before).map(|((_, peak), (rss, _))| peak - rss);
        drop(scene);
        say("tracing".into());
        let full = Rect { x: 0, y: 0, width: w as u32, height: h as u32 };
        let threads = rayon::current_num_threads();
        let (rays, _, _, cpu_s) = timed(threads, || render_tile(&prepared, full, false).rays)?;
        let n_log_n = |n: usize| n as f64 * (n as f64).log2();
        let (read_0, prepare_0, n_0) = sizes
            .first()
            .map_or((read_s, prepare_s, triangles), |s| (s.read_s, s.prepare_s, s.triangles));
        sizes.push(Size {
            triangles,
            file_mib,
            read_s,
            prepare_s,
            prepared_bytes_per_triangle: prepared.memory_bytes() as f64 / triangles as f64,
            peak_bytes_per_triangle: peak.map(|p| p / triangles as f64),
            rays_per_cpu_s: rays as f64 / cpu_s,
            read_over_n_log_n: (read_s / n_log_n(triangles)) / (read_0 / n_log_n(n_0)),
            prepare_over_n_log_n: (prepare_s / n_log_n(triangles)) / (prepare_0 / n_log_n(n_0)),
        });
    }
    let report = MeshBench {
        benchmark: "mesh",
        threads: rayon::current_num_threads(),
        width: w,
        height: h,
        spp: args.spp,
        sizes,
    };
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}
