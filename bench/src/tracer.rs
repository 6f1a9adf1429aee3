//! `restauro bench tracer`: the tracer's speed against the BVH's own.
//!
//! The bound: exactly the rays a Whitted sample casts (depth 1: the camera ray, closest hit; one
//! shadow ray per light, any hit), collected first and then traced through the BVH alone. The
//! whole sample — sampling, 81-band shading, lights, film — is then timed on the same rays.
//! CPU time is the process's user + system time from /proc (Linux), so the figures are per
//! CPU-second whatever else the machine is doing.

use crate::args::{BenchArgs, BenchScene};
use crate::cpu::timed;
use crate::error::{BenchError, io_doing};
use glam::Vec3A;
use restauro_assets::load_scene;
use restauro_render::integrator::lift;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{Rect, camera_ray, render_tile};
use restauro_scene::load::{Limits, LoadedScene};
use restauro_scene::scene_file::Integrator;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

fn blocks_obj() -> String {
    let mut s = String::from("v -60 -60 0\nv 60 -60 0\nv 60 60 0\nv -60 60 0\nf 1 2 3 4\n");
    let mut v = 4;
    let mut rng = restauro_spectral::keyed_random::KeyedRng::new(7);
    for i in 0..90 {
        for j in 0..92 {
            let (x, y) = (-45.0 + i as f32, -46.0 + j as f32);
            let h = 0.5 + 3.0 * rng.next_f32();
            let (a, b) = (0.35, 0.35);
            let c = [
                [x - a, y - b, 0.0],
                [x + a, y - b, 0.0],
                [x + a, y + b, 0.0],
                [x - a, y + b, 0.0],
                [x - a, y - b, h],
                [x + a, y - b, h],
                [x + a, y + b, h],
                [x - a, y + b, h],
            ];
            for p in c {
                let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
            }
            for f in
                [[1, 2, 6, 5], [2, 3, 7, 6], [3, 4, 8, 7], [4, 1, 5, 8], [5, 6, 7, 8], [4, 3, 2, 1]]
            {
                let _ = writeln!(s, "f {} {} {} {}", v + f[0], v + f[1], v + f[2], v + f[3]);
            }
            v += 8;
        }
    }
    s
}

const BLOCKS_TOML: &str = r#"format = 1
[camera]
position = [-20.0, -70.0, 25.0]
target = [0.0, 0.0, 0.0]
width = 640
height = 360
[render]
integrator = "path"
samples_per_pixel = 4
max_depth = 4
seed = 1
[spectra]
stone = "limestone_oolitic_indiana_solid__eco_ward72"
daylight = { illuminant = "D65" }
lamp = { illuminant = "A" }
[materials.stone]
model = "cook-torrance"
reflectance = "stone"
roughness = 0.3
ior = 1.5
[[objects]]
name = "blocks"
mesh = "blocks.obj"
material = "stone"
[[lights]]
kind = "sun"
preset = "sun"
azimuth_deg = 210.0
spectrum = "daylight"
[[lights]]
kind = "point"
position = [0.0, -10.0, 12.0]
intensity_cd = 20000.0
spectrum = "lamp"
"#;

fn load(
    which: BenchScene,
    width: usize,
    height: usize,
) -> Result<(LoadedScene, tempfile::TempDir), BenchError> {
    let dir = tempfile::tempdir().map_err(io_doing("creating a temporary folder"))?;
    let write = |name: &str, text: &str| {
        std::fs::write(dir.path().join(name), text).map_err(io_doing(format!("writing {name}")))
    };
    let path = match which {
        BenchScene::Aosta => {
            let g = restauro_demo::scenes::aosta::generate(width as u32, height as u32, 1);
            std::fs::create_dir_all(dir.path().join("meshes"))
                .map_err(io_doing("creating meshes/"))?;
            write("meshes/facade.obj", &g.facade_obj)?;
            write("aosta.toml", &g.scene_toml)?;
            dir.path().join("aosta.toml")
        }
        BenchScene::Blocks => {
            write("blocks.obj", &blocks_obj())?;
            let toml = BLOCKS_TOML
                .replace("width = 640", &format!("width = {width}"))
                .replace("height = 360", &format!("height = {height}"));
            write("blocks.toml", &toml)?;
            dir.path().join("blocks.toml")
        }
    };
    let scene = load_scene(&path, &Limits::default())
        .map_err(|source| BenchError::SceneNamed { what: "bench scene".into(), source })?;
    Ok((scene, dir))
}

/// A scene file of the user's, loaded with the default limits.
fn load_file(path: &Path) -> Result<LoadedScene, BenchError> {
    load_scene(path, &Limits::default()).map_err(|source| BenchError::SceneNamed {
        what: format!("bench scene {}", path.display()),
        source,
    })
}

#[derive(Serialize)]
struct Run {
    threads: usize,
    /// How many times the image was traced (more than once when it is small).
    repetitions: u64,
    wall_s: f64,
    cpu_s: f64,
    rays: u64,
    rays_per_cpu_s: f64,
    samples_per_cpu_s: f64,
}

#[derive(Serialize)]
struct TracerBench {
    benchmark: &'static str,
    scene: String,
    triangles: usize,
    lights: usize,
    width: usize,
    height: usize,
    spp: u32,
    /// The Whitted rays (camera + one shadow ray per light, depth 1) through the BVH alone.
    bvh_only: Run,
    whitted: Vec<Run>,
    /// Whole Whitted samples' rays per CPU-second over the BVH-only rate, the median of
    /// alternating pairs of runs (target ≥ 0.7).
    whitted_over_bvh_only: f64,
    /// Every pair's ratio, sorted.
    whitted_over_bvh_only_pairs: Vec<f64>,
    path: Vec<Run>,
}

impl Run {
    fn wall_per_run(&self) -> f64 {
        self.wall_s / self.repetitions as f64
    }
}

/// A measurement of `repetitions` runs of `samples` samples each, `rays` rays in all.
fn run(
    threads: usize,
    (rays, repetitions, wall_s, cpu_s): (u64, u64, f64, f64),
    samples: u64,
) -> Run {
    let samples = samples * repetitions;
    Run {
        threads,
        repetitions,
        wall_s,
        cpu_s,
        rays,
        rays_per_cpu_s: rays as f64 / cpu_s,
        samples_per_cpu_s: samples as f64 / cpu_s,
    }
}

/// The rays of every Whitted sample, collected once: the camera rays, and for each that hits,
/// one shadow ray (origin, direction, reach) per light that faces the hit.
struct WhittedRays {
    camera: Vec<Vec3A>,
    shadow: Vec<(Vec3A, Vec3A, f32)>,
}

impl WhittedRays {
    fn collect(prepared: &PreparedScene, spp: u32) -> WhittedRays {
        let (w, h) = (prepared.camera.width, prepared.camera.height);
        let mut camera = Vec::with_capacity(w as usize * h as usize * spp as usize);
        for y in 0..h {
            for x in 0..w {
                for s in 0..spp {
                    camera.push(camera_ray(prepared, x, y, s).0);
                }
            }
        }
        let origin = prepared.camera.origin;
        let mut shadow = Vec::new();
        for d in &camera {
            if let Some(hit) = prepared.intersect(origin, *d, f32::INFINITY) {
                for light in &prepared.lights {
                    if let Some(inc) = light.incident(hit.point)
                        && inc.direction.dot(hit.normal) > 0.0
                    {
                        let reach = if inc.distance.is_finite() {
                            inc.distance * (1.0 - 1e-4)
                        } else {
                            f32::INFINITY
                        };
                        shadow.push((lift(&hit), inc.direction, reach));
                    }
                }
            }
        }
        WhittedRays { camera, shadow }
    }

    /// The rays through the BVH alone, on one thread: the camera rays' closest hits and the
    /// shadow rays' any-hits.
    fn trace(&self, prepared: &PreparedScene, samples: u64) -> Result<Run, BenchError> {
        let origin = prepared.camera.origin;
        let rays = (self.camera.len() + self.shadow.len()) as u64;
        let (_, runs, wall, cpu) = timed(1, || {
            let hits = self
                .camera
                .iter()
                .filter(|d| prepared.intersect(origin, **d, f32::INFINITY).is_some())
                .count();
            let blocked =
                self.shadow.iter().filter(|(o, d, r)| prepared.occluded(*o, *d, *r)).count();
            std::hint::black_box(hits + blocked) as u64
        })?;
        Ok(run(1, (rays * runs, runs, wall, cpu), samples))
    }
}

/// The BVH alone against whole Whitted samples, alternating, the ratio taken pair by pair: the
/// load of a shared machine drifts over seconds, and a ratio of runs far apart would carry it.
/// Returns the median pair's ratio and BVH run, and every ratio, sorted.
fn bvh_against_whole(
    prepared: &PreparedScene,
    args: &BenchArgs,
    say: &dyn Fn(String),
) -> Result<(f64, Run, Vec<f64>), BenchError> {
    let rays = WhittedRays::collect(prepared, args.spp);
    let samples = u64::from(prepared.camera.width * prepared.camera.height) * u64::from(args.spp);
    let full = full_image(prepared);
    let repeats = args.repeats.max(1);
    let mut pairs = Vec::new();
    for i in 0..repeats {
        say(format!("the BVH alone against whole Whitted samples, pair {} of {repeats}", i + 1));
        let bvh = rays.trace(prepared, samples)?;
        let whole = run(1, timed(1, || render_tile(prepared, full, false).rays)?, samples);
        pairs.push((whole.rays_per_cpu_s / bvh.rays_per_cpu_s, bvh));
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let ratios: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let (ratio, bvh_only) = pairs.swap_remove(pairs.len() / 2);
    Ok((ratio, bvh_only, ratios))
}

/// The whole image as one tile.
fn full_image(prepared: &PreparedScene) -> Rect {
    Rect { x: 0, y: 0, width: prepared.camera.width, height: prepared.camera.height }
}

/// The best of `repeats` renders of the whole image on one and on two threads.
fn render_runs(
    prepared: &PreparedScene,
    name: &str,
    args: &BenchArgs,
    say: &dyn Fn(String),
) -> Result<Vec<Run>, BenchError> {
    let samples = u64::from(prepared.camera.width * prepared.camera.height) * u64::from(args.spp);
    let full = full_image(prepared);
    let repeats = args.repeats.max(1);
    let mut runs = Vec::new();
    for threads in [1, 2] {
        let mut best: Option<Run> = None;
        for i in 0..repeats {
            say(format!("{name} on {threads} thread(s), run {} of {repeats}", i + 1));
            let measured = timed(threads, || render_tile(prepared, full, false).rays)?;
            let r = run(threads, measured, samples);
            if best.as_ref().is_none_or(|b| r.wall_per_run() < b.wall_per_run()) {
                best = Some(r);
            }
        }
        runs.extend(best);
    }
    Ok(runs)
}

pub fn bench(args: &BenchArgs) -> Result<String, BenchError> {
    let (w, h) = (args.width, args.height);
    let say = |what: String| restauro_cluster::progress::say(&format!("bench tracer: {what}"));
    let name = match &args.scene_file {
        Some(path) => path.display().to_string(),
        None => format!("{:?}", args.scene).to_lowercase(),
    };
    say(format!("loading the {name} scene at {w}×{h}, {} samples per pixel", args.spp));
    let (mut scene, _dir) = match &args.scene_file {
        Some(path) => (load_file(path)?, None),
        None => {
            let (scene, dir) = load(args.scene, w, h)?;
            (scene, Some(dir))
        }
    };
    (scene.camera.width, scene.camera.height) = (w as u32, h as u32);
    let base = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: args.spp,
        max_depth: 1,
        seed: 1,
        grids: false,
        noise_target: 0.0,
    };
    let whitted = PreparedScene::new(&scene, None, base)?;
    say("collecting the camera and shadow rays of every Whitted sample".into());
    let (ratio, bvh_only, ratios) = bvh_against_whole(&whitted, args, &say)?;
    let whitted_runs = render_runs(&whitted, "Whitted", args, &say)?;
    let path_settings =
        Settings { integrator: Integrator::Path, max_depth: scene.file.render.max_depth, ..base };
    let path = PreparedScene::new(&scene, None, path_settings)?;
    let path_runs = render_runs(&path, "path tracing", args, &say)?;
    let report = TracerBench {
        benchmark: "tracer",
        scene: name,
        triangles: whitted.triangle_count(),
        lights: whitted.lights.len(),
        width: w,
        height: h,
        spp: args.spp,
        bvh_only,
        whitted: whitted_runs,
        whitted_over_bvh_only: ratio,
        whitted_over_bvh_only_pairs: ratios,
        path: path_runs,
    };
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}
