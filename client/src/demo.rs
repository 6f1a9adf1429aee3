//! `restauro demo`: what restauro is for, in one command. On an embedded local cluster (a
//! coordinator and workers, real processes on loopback) it renders
//!
//! 1. the south facade of the Roman theatre of Aosta as found and cleaned, under the sun of a
//!    summer afternoon at the site (with its clear sky), under the CIE overcast sky of
//!    10 000 lux and under the same sun with the CIE standard clear sky, each as rendered and
//!    as seen (adapted to its light, `restauro_spectral::seen`);
//! 2. the paper's stone experiment (Rossi, Marini & Rizzi 2004, Fig. 12): travertine and pudding
//!    stone, as found and cleaned, beside a white tile under CIE illuminants A, B, C and D65,
//!    as rendered and as seen;
//! 3. the facade floodlit at night, and the illuminance over one bay on its calculation grid,
//!    written as `restauro illuminance` writes it (a false-colour map, a table, a document);
//!
//! and writes labelled contact sheets, a CIEDE2000 map between the two hypotheses, and a report
//! (Markdown and JSON) of every image, its scene, light, parameters and render time, and the
//! mean colour of each stone under each light as rendered and as seen.
//!
//! **How colours are compared.** A stone's colour in a render is the mean absolute XYZ over the
//! inner 60 % of its square, made relative to the white tile of the same render (Y = 1 for the
//! tile) and expressed in CIELAB with the D65 display white: what a camera balanced for daylight
//! and exposed for the white card shows. The seen image is already relative XYZ with a D65
//! white. The reference is the D65 render; the paper's claim is that, under another light, the
//! seen image comes closer to it than the unfiltered render does. The seen image is also
//! compared with the D65 render's own seen image: what an observer sees under the light
//! against what they see in daylight (under A, a warmth people keep).
//!
//! The facade's CIEDE2000 map compares the as-found and cleaned renders pixel by pixel in CIELAB
//! relative to the luminance of a perfect white horizontal surface under the same light (E_h/π)
//! with a D65 white; pixels that see the sky are left out.

use crate::cli::DemoArgs;
use crate::sheet::{Grid, Rgb8, colour_bar};
use anyhow::{Context, Result, anyhow, bail};
use indicatif::{ProgressBar, ProgressStyle};
use restauro_assets::bundle_scene;
use restauro_assets::load_scene;
use restauro_cluster::progress::Progress;
use restauro_cluster::{self as cluster, Client, LocalCluster};
use restauro_demo::scene_files::write_aosta;
use restauro_demo::scenes::photo_block;
use restauro_demo::scenes::samples::{self, PixelRect, SAMPLES, WHITE_REFLECTANCE};
use restauro_image::atomic_file;
use restauro_image::image_files::{PngPixels, XyzImage, read_exr, write_png};
use restauro_proto as pb;
use restauro_scene::job::{JobName, JobSpec};
use restauro_scene::load::{Limits, LoadedScene, ResolvedLight};
use restauro_scene::plan::RenderOptions;
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Lab;
use restauro_spectral::appearance::d65_white;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::Xyz;
use restauro_spectral::display::{Exposure, exposure_scale};
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The illuminants of the stone experiment, as the paper uses them.
pub const ILLUMINANTS: [&str; 4] = ["A", "B", "C", "D65"];
/// The share of a sample square (per side) whose pixels are averaged: its edges, antialiased
/// against the board, are left out.
pub const INNER_FRACTION: f64 = 0.6;

/// Image sizes and samples.
struct Size {
    facade: (u32, u32),
    facade_spp: u32,
    samples: (u32, u32),
    samples_spp: u32,
    /// Samples a point of the floodlit facade's grid.
    grid_spp: u32,
    /// The width of a facade image on its contact sheet.
    sheet_cell: u32,
}

impl Size {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                facade: (320, 180),
                facade_spp: 4,
                samples: (300, 200),
                samples_spp: 1,
                grid_spp: 16,
                sheet_cell: 320,
            }
        } else {
            Self {
                facade: (1280, 720),
                facade_spp: 32,
                samples: (600, 400),
                samples_spp: 4,
                grid_spp: 256,
                sheet_cell: 560,
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
enum FacadeLight {
    SummerAfternoon,
    Overcast,
    ClearSky,
}

impl FacadeLight {
    fn title(self) -> &'static str {
        match self {
            FacadeLight::SummerAfternoon => "summer afternoon",
            FacadeLight::Overcast => "overcast sky",
            FacadeLight::ClearSky => "CIE clear sky",
        }
    }
}

#[derive(Clone, Debug)]
enum Kind {
    Facade {
        light: FacadeLight,
        variant: &'static str,
    },
    Samples {
        illuminant: &'static str,
    },
    /// The facade floodlit at night, cleaned.
    Night,
    /// The floodlit scene's calculation grid.
    Grid,
    /// The pudding-stone blocks, flat and with a photo, as found and cleaned.
    Block,
}

impl Kind {
    /// The restoration hypothesis rendered.
    fn variant(&self) -> Option<String> {
        match self {
            Kind::Facade { variant, .. } => Some(variant.to_string()),
            Kind::Night => Some("cleaned".into()),
            Kind::Block => Some(photo_block::VARIANT.into()),
            Kind::Samples { .. } | Kind::Grid => None,
        }
    }
}

/// One render of the demo.
struct Job {
    /// The job's name, and the stem of its files.
    key: String,
    scene: PathBuf,
    kind: Kind,
    spp: u32,
}

/// A finished render, as the report lists it.
#[derive(Serialize)]
struct RenderRecord {
    job: String,
    scene: String,
    variant: Option<String>,
    lights: Vec<String>,
    /// The scene file's keyword (`path`, `whitted`); the Markdown shows its name.
    integrator: Integrator,
    width: u32,
    height: u32,
    samples_per_pixel: u32,
    max_depth: u32,
    retinex: String,
    /// From the job's first tile to its results written (s).
    render_s: f64,
    files: Vec<String>,
}

#[derive(Serialize)]
struct Image {
    file: String,
    what: String,
}

#[derive(Clone, Serialize)]
struct Measured {
    /// Mean XYZ over the square: absolute (cd/m²) as rendered, relative to a D65 white
    /// of Y = 1 after it.
    xyz: [f64; 3],
    /// CIELAB as described in the module documentation.
    lab: [f64; 3],
    /// The colour shown on an sRGB display.
    srgb_hex: String,
    /// ΔE00 to the same square of the D65 render as rendered (unfiltered).
    delta_e00_to_d65: f64,
    /// As seen only: ΔE00 to the same square of the D65 render as seen (its seen image
    /// output) — how far what an observer sees under this light is from what they see under
    /// daylight.
    #[serde(skip_serializing_if = "Option::is_none")]
    delta_e00_to_d65_seen: Option<f64>,
}

#[derive(Serialize)]
struct StoneColour {
    stone: &'static str,
    state: &'static str,
    illuminant: &'static str,
    before_retinex: Measured,
    after_retinex: Measured,
}

#[derive(Serialize)]
struct SampleRegion {
    label: &'static str,
    stone: &'static str,
    state: &'static str,
    /// The averaged pixels of the sample renders.
    rect: PixelRect,
}

#[derive(Serialize)]
struct CleaningDifference {
    light: FacadeLight,
    /// The luminance of a perfect white horizontal surface under this light, the CIELAB white.
    white_cd_m2: f64,
    mean_delta_e00: f64,
    p95_delta_e00: f64,
    /// Pixels compared (the sky is left out).
    pixels: usize,
}

#[derive(Serialize)]
struct Report {
    schema: &'static str,
    quick: bool,
    workers: usize,
    total_s: f64,
    soot_fraction: f64,
    white_reflectance: f64,
    /// Every image written, relative to the output folder.
    images: Vec<Image>,
    renders: Vec<RenderRecord>,
    samples: Vec<SampleRegion>,
    stones: Vec<StoneColour>,
    cleaning: Vec<CleaningDifference>,
    floodlighting: Floodlighting,
}

fn bar_style(template: &str) -> Result<ProgressStyle> {
    ProgressStyle::with_template(template).context("progress template")
}

pub fn run(args: &DemoArgs) -> Result<String> {
    let started = Instant::now();
    let out = &args.out;
    let size = Size::new(args.quick);
    let workers = args.workers.max(1);
    let bar = Progress::new(
        "demo",
        "tiles",
        Some(1),
        "{msg:>12} {bar:40} {pos}/{len} {elapsed} elapsed, eta {eta}",
    )?;
    bar.enable_steady_tick(Duration::from_millis(200));

    // The cluster starts first: its processes come up while the scenes are written.
    bar.set_message("cluster");
    let local = LocalCluster::start(workers, args.cluster_logs.as_deref())?;
    bar.set_message("scenes");
    let jobs = write_scenes(out, &size)?;
    let mut scenes: BTreeMap<PathBuf, LoadedScene> = BTreeMap::new();
    for job in &jobs {
        if !scenes.contains_key(&job.scene) {
            let loaded = load_scene(&job.scene, &Limits::default())?;
            scenes.insert(job.scene.clone(), loaded);
        }
    }

    let runtime = cluster::runtime()?;
    let finished = runtime.block_on(render_all(&local, &jobs, out, &bar))?;
    drop(local);

    bar.set_message("analysis");
    bar.set_style(bar_style("{msg:>12} {spinner} {elapsed} elapsed")?);
    let analysis = analyse(out, &size, &jobs, &finished, &scenes)?;
    bar.finish_and_clear();

    let total_s = started.elapsed().as_secs_f64();
    let report = Report {
        schema: "restauro.demo/1",
        quick: args.quick,
        workers,
        total_s,
        soot_fraction: 0.3,
        white_reflectance: WHITE_REFLECTANCE,
        images: analysis.images,
        renders: finished.into_iter().map(|f| f.record).collect(),
        samples: SAMPLES
            .iter()
            .map(|s| SampleRegion {
                label: s.label,
                stone: s.stone,
                state: s.state,
                rect: samples::pixel_rect(s, size.samples.0, size.samples.1, INNER_FRACTION),
            })
            .collect(),
        stones: analysis.stones,
        cleaning: analysis.cleaning,
        floodlighting: analysis.floodlighting,
    };
    let md_path = out.join("report.md");
    let json_path = out.join("report.json");
    atomic_file::write(&md_path, markdown(&report).as_bytes())
        .with_context(|| format!("cannot write {}", md_path.display()))?;
    atomic_file::write(&json_path, (serde_json::to_string_pretty(&report)? + "\n").as_bytes())
        .with_context(|| format!("cannot write {}", json_path.display()))?;

    let mut s = String::new();
    let _ = writeln!(
        s,
        "restauro demo: {} renders on an embedded cluster of {workers} workers in {total_s:.1} s",
        report.renders.len()
    );
    for stone in &report.stones {
        if stone.illuminant == "A" && stone.stone != "white reference" {
            let _ = writeln!(
                s,
                "  under CIE A, {} {}: ΔE00 to the D65 render {:.1} unfiltered, {:.1} as seen \
                 ({:.1} to the D65 render as seen)",
                stone.stone,
                stone.state,
                stone.before_retinex.delta_e00_to_d65,
                stone.after_retinex.delta_e00_to_d65,
                stone.after_retinex.delta_e00_to_d65_seen.unwrap_or(f64::NAN)
            );
        }
    }
    for c in &report.cleaning {
        let _ = writeln!(
            s,
            "  cleaning the facade, {}: mean ΔE00 {:.1} (95th percentile {:.1})",
            c.light.title(),
            c.mean_delta_e00,
            c.p95_delta_e00
        );
    }
    let f = &report.floodlighting;
    let _ = writeln!(
        s,
        "  the floodlit facade at night, {}: mean {:.1} lx (from {:.1} to {:.1} lx), uniformity \
         {:.2}; map {}",
        f.grid,
        f.mean_lux,
        f.min_lux,
        f.max_lux,
        f.uniformity,
        out.join(&f.map).display()
    );
    let _ = writeln!(s, "contact sheets:");
    for image in report.images.iter().filter(|i| i.file.starts_with("sheets/")) {
        let _ = writeln!(s, "  {}", out.join(&image.file).display());
    }
    let _ = writeln!(s, "report: {}", md_path.display());
    let _ = writeln!(s, "results are in {}", out.display());
    Ok(s)
}

/// Writes the facade scene and the four sample scenes; returns the renders to make.
fn write_scenes(out: &Path, size: &Size) -> Result<Vec<Job>> {
    let aosta = write_aosta(&out.join("scenes/aosta"), size.facade.0, size.facade.1, 1)?;
    let mut jobs = Vec::new();
    for (light, scene, stem) in [
        (FacadeLight::SummerAfternoon, &aosta.sunny, "facade-sun"),
        (FacadeLight::Overcast, &aosta.overcast, "facade-overcast"),
        (FacadeLight::ClearSky, &aosta.clear, "facade-clear"),
    ] {
        for variant in ["as-found", "cleaned"] {
            jobs.push(Job {
                key: format!("{stem}-{variant}"),
                scene: scene.clone(),
                kind: Kind::Facade { light, variant },
                spp: size.facade_spp,
            });
        }
    }
    jobs.push(Job {
        key: "facade-night-cleaned".into(),
        scene: aosta.floodlit.clone(),
        kind: Kind::Night,
        spp: size.facade_spp,
    });
    jobs.push(Job {
        key: "floodlit-grid".into(),
        scene: aosta.floodlit.clone(),
        kind: Kind::Grid,
        spp: size.grid_spp,
    });
    jobs.push(Job {
        key: "block".into(),
        scene: write_photo_block(&out.join("scenes/block"), size)?,
        kind: Kind::Block,
        spp: size.facade_spp,
    });
    let dir = out.join("scenes/samples");
    for illuminant in ILLUMINANTS {
        let g = samples::generate(illuminant, size.samples.0, size.samples.1, size.samples_spp);
        let scene = dir.join(format!("samples-{illuminant}.toml"));
        for (path, text) in [
            (dir.join("board.obj"), &g.board_obj),
            (dir.join("grey.csv"), &g.grey_csv),
            (dir.join("white.csv"), &g.white_csv),
            (scene.clone(), &g.scene_toml),
        ] {
            atomic_file::write(&path, text.as_bytes())
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        jobs.push(Job {
            key: format!("samples-{illuminant}"),
            scene,
            kind: Kind::Samples { illuminant },
            spp: size.samples_spp,
        });
    }
    Ok(jobs)
}

/// The photo block's scene, its meshes and its photo, in `dir`; returns the scene's path.
fn write_photo_block(dir: &Path, size: &Size) -> Result<PathBuf> {
    let (w, _) = size.facade;
    let g = photo_block::generate(w, w * 3 / 8, size.facade_spp);
    let scene = dir.join("blocks.toml");
    let mut files: Vec<(PathBuf, &[u8])> = g
        .blocks
        .iter()
        .map(|(name, obj)| (dir.join(format!("blocks/{name}.obj")), obj.as_bytes()))
        .collect();
    files.push((dir.join("blocks/ground.obj"), photo_block::GROUND_OBJ.as_bytes()));
    files.push((dir.join(photo_block::PHOTO_FILE), photo_block::PHOTO));
    files.push((scene.clone(), g.scene_toml.as_bytes()));
    for (path, bytes) in files {
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("cannot create {}", parent.display()))?;
        }
        atomic_file::write(&path, bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(scene)
}

/// A render fetched from the cluster.
struct Finished {
    record: RenderRecord,
    dir: PathBuf,
}

/// Submits every job at once, follows them on one progress bar and fetches their files.
async fn render_all(
    local: &LocalCluster,
    jobs: &[Job],
    out: &Path,
    bar: &ProgressBar,
) -> Result<Vec<Finished>> {
    let mut client =
        cluster::connect_as(&local.url, &local.client_token, None, pb::PROTOCOL_VERSION).await?;
    bar.set_message("upload");
    let mut submitted = Vec::new();
    // Falling priorities: the renders run one after another (equal priorities would share the
    // workers), so each one's time is its own.
    for (index, job) in jobs.iter().enumerate() {
        let bundle = bundle_scene(&job.scene, &Limits::default())?;
        cluster::upload(&mut client, &bundle).await?;
        let spec = JobSpec {
            name: JobName::new(&job.key)?,
            priority: (jobs.len() - index) as i32,
            render: RenderOptions {
                variant: job.kind.variant(),
                samples_per_pixel: NonZeroU32::new(job.spp),
                grids: matches!(job.kind, Kind::Grid),
                ..RenderOptions::default()
            },
            ..JobSpec::default()
        };
        let what = format!("submitting {}", job.scene.display());
        let status = cluster::submit(&mut client, &bundle, &spec, &what).await?;
        submitted.push(status);
    }
    let total: u64 = submitted.iter().map(|s| u64::from(s.tiles_total)).sum();
    bar.set_length(total);
    bar.set_position(0);
    bar.set_message("render");
    bar.set_style(bar_style("{msg:>12} {bar:40} {pos}/{len} tiles, {elapsed} elapsed, eta {eta}")?);
    let statuses = watch_all(&client, &submitted, bar).await?;
    bar.set_message("fetch");
    let mut finished = Vec::new();
    for ((job, (status, render_s)), plan) in jobs.iter().zip(statuses).zip(&submitted) {
        if status.state != pb::JobState::Done as i32 {
            bail!(
                "the demo's render {} ended without results: {}",
                job.key,
                crate::jobs_cmd::shown(&status.error)
            );
        }
        let dir = out.join("renders").join(&job.key);
        let files = cluster::fetch(&client, &status, &dir).await?;
        let loaded = load_scene(&job.scene, &Limits::default())?;
        let render = &loaded.file.render;
        finished.push(Finished {
            record: RenderRecord {
                job: job.key.clone(),
                scene: relative(out, &job.scene),
                variant: job.kind.variant(),
                lights: loaded.lights.iter().map(ToString::to_string).collect(),
                integrator: render.integrator,
                width: plan.width,
                height: plan.height,
                samples_per_pixel: job.spp,
                max_depth: render.max_depth,
                retinex: format!(
                    "adapted to the light each render measured: CAT16 with CAM16's degree of \
                     adaptation and a blue bias, mesopic below 5 cd/m², sunlit and shadowed \
                     surfaces adapted apart (framework weight {}, plane weight {}); lightness by \
                     Brownian paths from the known white, 20 per pixel, the white an area, the \
                     sky passed over, seed 0",
                    restauro_spectral::retinex::DEFAULT_FRAMEWORK_WEIGHT,
                    restauro_spectral::seen::DEFAULT_PLANE_WEIGHT,
                ),
                render_s,
                files: files.iter().map(|f| relative(out, f)).collect(),
            },
            dir,
        });
    }
    Ok(finished)
}

/// Follows every job to its end on one progress bar; returns each final status and the time from
/// its first tile to its end.
async fn watch_all(
    client: &Client,
    submitted: &[pb::JobStatus],
    bar: &ProgressBar,
) -> Result<Vec<(pb::JobStatus, f64)>> {
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
    let mut tasks = tokio::task::JoinSet::new();
    for (index, job) in submitted.iter().enumerate() {
        let (mut client, tx, id) = (client.clone(), tx.clone(), job.job_id.clone());
        tasks.spawn(async move {
            let mut stream = client
                .watch_job(pb::JobRef { job_id: id.clone() })
                .await
                .map_err(|s| cluster::refused(&format!("watching job {id}"), s))?
                .into_inner();
            while let Some(status) = stream
                .message()
                .await
                .map_err(|s| cluster::refused(&format!("watching {id}"), s))?
            {
                let _ = tx.send((index, status));
            }
            anyhow::Ok(())
        });
    }
    drop(tx);
    let mut last: Vec<Option<pb::JobStatus>> = vec![None; submitted.len()];
    let mut first_tile: Vec<Option<Instant>> = vec![None; submitted.len()];
    let mut ended: Vec<Option<f64>> = vec![None; submitted.len()];
    let mut done = vec![0u64; submitted.len()];
    while let Some((index, status)) = rx.recv().await {
        done[index] = u64::from(status.tiles_done);
        bar.set_position(done.iter().sum());
        if (status.tiles_done > 0 || status.tiles_leased > 0) && first_tile[index].is_none() {
            first_tile[index] = Some(Instant::now());
        }
        let state = pb::JobState::try_from(status.state).unwrap_or(pb::JobState::Unspecified);
        if matches!(state, pb::JobState::Done | pb::JobState::Failed | pb::JobState::Cancelled) {
            let from = first_tile[index].unwrap_or_else(Instant::now);
            ended[index].get_or_insert(from.elapsed().as_secs_f64());
            last[index] = Some(status);
            if ended.iter().all(Option::is_some) {
                break;
            }
        } else if ended[index].is_none() {
            last[index] = Some(status);
        }
    }
    tasks.abort_all();
    last.into_iter()
        .zip(ended)
        .enumerate()
        .map(|(i, (status, s))| match (status, s) {
            (Some(status), Some(s)) => Ok((status, s)),
            _ => Err(anyhow!("the coordinator stopped reporting job {}", submitted[i].job_id)),
        })
        .collect()
}

fn relative(out: &Path, path: &Path) -> String {
    path.strip_prefix(out).unwrap_or(path).display().to_string()
}

/// The horizontal illuminance of a scene's lights that light the whole ground alike (sun and
/// sky), lux.
fn horizontal_illuminance_lux(scene: &LoadedScene) -> f64 {
    scene
        .lights
        .iter()
        .map(|l| match l {
            ResolvedLight::Sun { illuminance_lux, elevation_deg, .. } => {
                illuminance_lux * elevation_deg.to_radians().sin()
            }
            ResolvedLight::Sky { illuminance_lux, .. } => *illuminance_lux,
            _ => 0.0,
        })
        .sum()
}

struct Analysis {
    images: Vec<Image>,
    stones: Vec<StoneColour>,
    cleaning: Vec<CleaningDifference>,
    floodlighting: Floodlighting,
}

/// The floodlit facade's calculation grid, as a lighting designer reads it.
#[derive(Serialize)]
struct Floodlighting {
    scene: String,
    grid: String,
    points: usize,
    samples_per_point: u32,
    min_lux: f64,
    mean_lux: f64,
    max_lux: f64,
    /// E_min / E_mean.
    uniformity: f64,
    /// The false-colour map, the points' table and the document (`restauro.illuminance/1`).
    map: String,
    table: String,
    document: String,
}

/// The floodlit grid's documents, written as `restauro illuminance` writes them, into
/// `out/floodlit/`; its map is listed among the images.
fn floodlighting(
    out: &Path,
    jobs: &[Job],
    finished: &[Finished],
    scenes: &BTreeMap<PathBuf, LoadedScene>,
    images: &mut Vec<Image>,
) -> Result<Floodlighting> {
    use crate::illuminance::{Document, SCHEMA, grid_results, write_documents};
    let (job, f) = jobs
        .iter()
        .zip(finished)
        .find(|(j, _)| matches!(j.kind, Kind::Grid))
        .ok_or_else(|| anyhow!("the floodlit grid is missing"))?;
    let exr = f.dir.join(format!("{}.exr", f.record.job));
    let image = read_exr(&exr, usize::MAX).with_context(|| format!("reading {}", exr.display()))?;
    let grids = grid_results(&scenes[&job.scene], &image, &exr)?;
    let document =
        Document { schema: SCHEMA, scene: relative(out, &job.scene), variant: None, grids };
    let json = serde_json::to_string_pretty(&document)? + "\n";
    let written = write_documents(&out.join("floodlit"), &document, &json)?;
    let (Some(grid), Some([csv, png])) = (document.grids.first(), written.per_grid.first()) else {
        bail!("the floodlit scene has no grid");
    };
    let map = relative(out, png);
    images.push(Image {
        file: map.clone(),
        what: format!(
            "the floodlit bay ({}): illuminance in false colour, isolines, lux scale",
            grid.name
        ),
    });
    Ok(Floodlighting {
        scene: relative(out, &job.scene),
        grid: grid.name.clone(),
        points: grid.points.len(),
        samples_per_point: job.spp,
        min_lux: grid.min_lux,
        mean_lux: grid.mean_lux,
        max_lux: grid.max_lux,
        uniformity: grid.uniformity,
        map,
        table: relative(out, csv),
        document: relative(out, &written.json),
    })
}

/// The two images of a render: as rendered (absolute XYZ) and as seen (relative).
struct Pair {
    rendered: XyzImage,
    seen: XyzImage,
}

fn read_pair(f: &Finished) -> Result<Pair> {
    let read = |name: String| {
        let path = f.dir.join(&name);
        read_exr(&path, usize::MAX).with_context(|| format!("reading {}", path.display()))
    };
    Ok(Pair {
        rendered: read(format!("{}.exr", f.record.job))?,
        seen: read(format!("{}-retinex.exr", f.record.job))?,
    })
}

/// The sRGB picture of an XYZ image.
use crate::compare::picture;

fn write_sheet(out: &Path, name: &str, image: &Rgb8, what: &str) -> Result<Image> {
    let path = out.join("sheets").join(name);
    write_png(
        &path,
        image.width as usize,
        image.height as usize,
        &PngPixels::Eight(image.data.clone()),
        RgbSpace::Srgb,
    )
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(Image { file: relative(out, &path), what: what.to_owned() })
}

fn analyse(
    out: &Path,
    size: &Size,
    jobs: &[Job],
    finished: &[Finished],
    scenes: &BTreeMap<PathBuf, LoadedScene>,
) -> Result<Analysis> {
    let mut images = Vec::new();
    for (job, f) in jobs.iter().zip(finished) {
        for file in &f.record.files {
            let what = if matches!(job.kind, Kind::Grid) {
                "the floodlit bay's grid: illuminance (Y in lux), row 0 direct, row 1 indirect, \
                 OpenEXR"
            } else if file.ends_with("-retinex.exr") {
                "as seen, adapted to its light: XYZ relative to a D65 white (Y = 1), OpenEXR"
            } else if file.ends_with("-retinex.png") {
                "as seen, adapted to its light, sRGB"
            } else if file.ends_with(".exr") {
                "as rendered: absolute XYZ (Y in cd/m²), OpenEXR"
            } else {
                "as rendered, sRGB (automatic exposure)"
            };
            images.push(Image { file: file.clone(), what: what.to_owned() });
        }
    }

    // The facade: pairs by light and hypothesis.
    let mut facade: BTreeMap<(FacadeLight, &str), (Pair, &Job)> = BTreeMap::new();
    let mut stones: BTreeMap<&str, Pair> = BTreeMap::new();
    let mut block = None;
    for (job, f) in jobs.iter().zip(finished) {
        match &job.kind {
            Kind::Block => block = Some(read_pair(f)?),
            Kind::Facade { light, variant } => {
                facade.insert((*light, variant), (read_pair(f)?, job));
            }
            Kind::Samples { illuminant } => {
                stones.insert(illuminant, read_pair(f)?);
            }
            Kind::Night | Kind::Grid => {}
        }
    }
    let lights = [FacadeLight::SummerAfternoon, FacadeLight::Overcast, FacadeLight::ClearSky];
    let get = |light, variant: &'static str| {
        facade.get(&(light, variant)).ok_or_else(|| anyhow!("the {variant} render is missing"))
    };

    // Sheet 1: the hypotheses side by side, each light's two renders at one exposure (that of
    // the cleaned render) so that their difference shows.
    let mut cells = Vec::new();
    let mut row_labels = Vec::new();
    for light in lights {
        let (found, _) = get(light, "as-found")?;
        let (cleaned, _) = get(light, "cleaned")?;
        let k = exposure_scale(&cleaned.rendered.pixels, Exposure::Automatic { key: 0.18 });
        let exposure = Exposure::Absolute { white_cd_m2: 1.0 / k };
        cells.push(vec![
            Some(picture(&found.rendered, exposure).resized_to_width(size.sheet_cell)),
            Some(picture(&cleaned.rendered, exposure).resized_to_width(size.sheet_cell)),
        ]);
        row_labels.push(format!("{}, as rendered", light.title()));
        cells.push(vec![
            Some(picture(&found.seen, Exposure::Relative).resized_to_width(size.sheet_cell)),
            Some(picture(&cleaned.seen, Exposure::Relative).resized_to_width(size.sheet_cell)),
        ]);
        row_labels.push(format!("{}, as seen", light.title()));
    }
    let (w, h) = size.facade;
    let sheet = Grid {
        title: "Roman theatre of Aosta, south facade: as found and cleaned",
        column_labels: vec!["as found".into(), "cleaned".into()],
        row_labels,
        cells,
        captions: Vec::new(),
        cell_width: size.sheet_cell,
        footer: vec![
            format!(
                "Rendered {w}x{h}, path tracing, {} samples per pixel, 81 bands 380-780 nm.",
                size.facade_spp
            ),
            "Summer afternoon: the sun at 15:30 CEST on 15 July at 45.74 N 7.32 E, and a clear sky of 15 000 lux.".into(),
            "Overcast: the CIE standard overcast sky, 10 000 lux. Each light's two renders share one exposure.".into(),
            "CIE clear sky: the same sun under the CIE standard clear sky (general sky type 12), 15 000 lux, over a ground of reflectance 0.2.".into(),
            "As found = a soot proxy where no sky or driving rain washes the stone, up to 70 % (derived, not measured).".into(),
            "As seen: adapted to the light measured at each surface (CAT16, CAM16's degree of adaptation, a blue bias); sun and shadow apart; lightness by Marini-Rizzi paths.".into(),
        ],
    }
    .render();
    images.push(write_sheet(out, "facade.png", &sheet, "contact sheet: the facade as found and cleaned, under sun and overcast sky, rendered and seen")?);

    // Sheet 2: CIEDE2000 between the hypotheses, pixel by pixel.
    let mut maps = Vec::new();
    let mut cleaning = Vec::new();
    for light in lights {
        let (found, job) = get(light, "as-found")?;
        let (cleaned, _) = get(light, "cleaned")?;
        let scene = &scenes[&job.scene];
        let white_cd_m2 = horizontal_illuminance_lux(scene) / std::f64::consts::PI;
        let white = d65_white().scale(white_cd_m2);
        // The two share the scene's geometry, so their skies (left out) are the same pixels.
        let map =
            restauro_image::delta_e::delta_e_map(&found.rendered, &cleaned.rendered, white, 2.0);
        cleaning.push(CleaningDifference {
            light,
            white_cd_m2,
            mean_delta_e00: map.stats.mean,
            p95_delta_e00: map.stats.p95,
            pixels: map.stats.pixels,
        });
        maps.push(map);
    }
    let all: Vec<f32> = maps.iter().flat_map(|m| m.values.iter().copied()).collect();
    let scale_max = restauro_image::delta_e::scale_max(&all);
    let cells = vec![
        maps.iter()
            .map(|map| {
                let picture = crate::compare::map_picture(map, w as usize, h as usize, scale_max);
                Some(picture.resized_to_width(size.sheet_cell))
            })
            .collect(),
    ];
    let captions = vec![
        cleaning
            .iter()
            .map(|c| {
                format!("mean {:.1}, 95th percentile {:.1}", c.mean_delta_e00, c.p95_delta_e00)
            })
            .collect(),
    ];
    let grid = Grid {
        title: "What cleaning changes: CIEDE2000 between as found and cleaned",
        column_labels: lights.iter().map(|l| l.title().to_owned()).collect(),
        row_labels: vec!["ΔE00 per pixel".into()],
        cells,
        captions,
        cell_width: size.sheet_cell,
        footer: vec![
            "CIELAB relative to a perfect white horizontal surface under each light (E_h/pi),"
                .into(),
            "D65 white; the sky in grey.".into(),
        ],
    }
    .render();
    let cell_h = (f64::from(size.sheet_cell) * f64::from(h) / f64::from(w)).round() as u32;
    let bar = colour_bar(scale_max, 6, 0, "ΔE00", cell_h);
    let mut sheet = Rgb8::new(
        grid.width + bar.width + 24,
        grid.height.max(bar.height + 60),
        crate::sheet::BACKGROUND,
    );
    sheet.blit(0, 0, &grid);
    sheet.blit(i64::from(grid.width), 56, &bar);
    images.push(write_sheet(
        out,
        "cleaning-delta-e.png",
        &sheet,
        "contact sheet: CIEDE2000 map between as found and cleaned, with its colour scale",
    )?);

    // Sheet 3 and the table: the stone experiment.
    let (sw, sh) = size.samples;
    let rect = |s: &samples::Sample| samples::pixel_rect(s, sw, sh, INNER_FRACTION);
    let mean = |image: &XyzImage, r: PixelRect| -> Xyz {
        let mut sum = [0.0f64; 3];
        let mut n = 0.0f64;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                let p = image.pixels[y as usize * image.width + x as usize];
                for k in 0..3 {
                    sum[k] += f64::from(p[k]);
                }
                n += 1.0;
            }
        }
        Xyz::from_array(sum.map(|v| v / n.max(1.0)))
    };
    let white_sample = &SAMPLES[SAMPLES.len() - 1];
    let d65 = stones.get("D65").ok_or_else(|| anyhow!("the D65 render is missing"))?;
    let lab_rendered = |pair: &Pair, s: &samples::Sample| -> (Xyz, Lab) {
        let white_y = mean(&pair.rendered, rect(white_sample)).y;
        let m = mean(&pair.rendered, rect(s));
        (m, Lab::from_xyz(m.scale(1.0 / white_y.max(1e-12)), d65_white()))
    };
    let lab_seen = |pair: &Pair, s: &samples::Sample| -> (Xyz, Lab) {
        let m = mean(&pair.seen, rect(s));
        (m, Lab::from_xyz(m, d65_white()))
    };
    let hex = |lab: Lab| -> String {
        let xyz = lab.to_xyz(d65_white());
        let image = XyzImage::new(1, 1, vec![[xyz.x as f32, xyz.y as f32, xyz.z as f32]]);
        let p = picture(&image, Exposure::Relative);
        format!("#{:02x}{:02x}{:02x}", p.data[0], p.data[1], p.data[2])
    };
    let mut table = Vec::new();
    let mut cells: Vec<Vec<Option<Rgb8>>> = vec![Vec::new(); SAMPLES.len()];
    let mut captions: Vec<Vec<String>> = vec![Vec::new(); SAMPLES.len()];
    let crop = 96;
    for illuminant in ILLUMINANTS {
        let pair =
            stones.get(illuminant).ok_or_else(|| anyhow!("the {illuminant} render is missing"))?;
        let white_y = mean(&pair.rendered, rect(white_sample)).y;
        for (row, s) in SAMPLES.iter().enumerate() {
            let reference = lab_rendered(d65, s).1;
            let reference_seen = lab_seen(d65, s).1;
            let (before_xyz, before) = lab_rendered(pair, s);
            let (after_xyz, after) = lab_seen(pair, s);
            let measured = |xyz: Xyz, lab: Lab, seen: Option<Lab>| Measured {
                xyz: xyz.to_array(),
                lab: [lab.l, lab.a, lab.b],
                srgb_hex: hex(lab),
                delta_e00_to_d65: ciede2000(reference, lab),
                delta_e00_to_d65_seen: seen.map(|seen| ciede2000(seen, lab)),
            };
            let before_m = measured(before_xyz, before, None);
            let after_m = measured(after_xyz, after, Some(reference_seen));
            // The squares as shown: the render exposed for the white tile, and the seen image.
            let r = samples::pixel_rect(s, sw, sh, 0.9);
            let exposure = Exposure::Absolute { white_cd_m2: white_y.max(1e-12) };
            cells[row].push(Some(crop_picture(&pair.rendered, r, exposure).resized_to_width(crop)));
            cells[row]
                .push(Some(crop_picture(&pair.seen, r, Exposure::Relative).resized_to_width(crop)));
            captions[row].push(format!("dE {:.1}", before_m.delta_e00_to_d65));
            captions[row].push(format!("dE {:.1}", after_m.delta_e00_to_d65));
            table.push(StoneColour {
                stone: s.stone,
                state: s.state,
                illuminant,
                before_retinex: before_m,
                after_retinex: after_m,
            });
        }
    }
    let grid = Grid {
        title: "Stone samples under CIE A, B, C and D65 (after Rossi, Marini & Rizzi 2004, Fig. 12)",
        column_labels: ILLUMINANTS.iter().flat_map(|i| [i.to_string(), format!("{i} seen")]).collect(),
        row_labels: SAMPLES.iter().map(|s| s.label.to_owned()).collect(),
        cells,
        captions,
        cell_width: crop,
        footer: vec![
            "Each light gives the board 1000 lux from above. Rendered: the white tile is the reference".into(),
            "white (70 % of the display's), on a D65 display without adaptation. Seen: adapted to the light, as a person there sees it.".into(),
            "dE: CIEDE2000 to the same sample in the D65 render (Lab relative to the white tile, D65 white).".into(),
            "As found = stone + 30 % soot-proxy mixture (derived, not measured).".into(),
        ],
    }
    .render();
    images.push(write_sheet(
        out,
        "stones.png",
        &grid,
        "contact sheet: the stone experiment, each sample under A, B, C and D65, rendered and seen",
    )?);

    // The boards themselves, whole, for the report.
    let mut boards = Vec::new();
    for illuminant in ILLUMINANTS {
        let pair = &stones[illuminant];
        let white_y = mean(&pair.rendered, rect(white_sample)).y;
        let exposure = Exposure::Absolute { white_cd_m2: white_y.max(1e-12) };
        boards.push(Some(picture(&pair.rendered, exposure).resized_to_width(300)));
        boards.push(Some(picture(&pair.seen, Exposure::Relative).resized_to_width(300)));
    }
    let grid = Grid {
        title: "The sample board under each illuminant: rendered and seen",
        column_labels: vec!["rendered".into(), "seen".into()],
        row_labels: ILLUMINANTS.iter().map(|i| format!("CIE {i}")).collect(),
        cells: boards.chunks(2).map(<[Option<Rgb8>]>::to_vec).collect(),
        captions: Vec::new(),
        cell_width: 300,
        footer: vec![
            "Top: travertine as found, cleaned; bottom: pudding stone as found, cleaned;".into(),
            "right: the white tile (90 %); the board: grey (30 %).".into(),
        ],
    }
    .render();
    images.push(write_sheet(
        out,
        "boards.png",
        &grid,
        "contact sheet: the whole sample board under each illuminant, rendered and seen",
    )?);
    let block = block.ok_or_else(|| anyhow!("the photo block's render is missing"))?;
    images.push(photo_block_sheet(out, size, &block)?);
    let floodlighting = floodlighting(out, jobs, finished, scenes, &mut images)?;
    Ok(Analysis { images, stones: table, cleaning, floodlighting })
}

/// The photo block's contact sheet: the render and what a person sees.
fn photo_block_sheet(out: &Path, size: &Size, block: &Pair) -> Result<Image> {
    let exposure = Exposure::Automatic { key: 0.18 };
    let width = 2 * size.sheet_cell;
    let labels: Vec<&str> = photo_block::BLOCKS.iter().map(|b| b.3).collect();
    let sheet = Grid {
        title: "Pudding stone: a photograph as detail over the measured spectrum",
        column_labels: vec![labels.join(" | ")],
        row_labels: vec!["as rendered".into(), "as seen".into()],
        cells: vec![
            vec![Some(picture(&block.rendered, exposure).resized_to_width(width))],
            vec![Some(picture(&block.seen, Exposure::Relative).resized_to_width(width))],
        ],
        captions: Vec::new(),
        cell_width: width,
        footer: vec![
            "Each block reflects the conglomerate's measured spectrum (USGS/ECOSTRESS), as found with".into(),
            "30 % soot proxy (derived). The photo blocks vary it by a photograph's relative luminance,".into(),
            "rho(lambda, x) = rho_m(lambda) Y(x)/mean Y: the same colour, the stones' detail. Photo: Gravel04,".into(),
            "CC0Textures (ambientCG), CC0, via scikit-image. Summer afternoon sun and clear sky.".into(),
        ],
    }
    .render();
    write_sheet(
        out,
        "block.png",
        &sheet,
        "contact sheet: pudding-stone blocks, flat and with a photograph as detail, as found and cleaned",
    )
}

/// The sRGB picture of the pixels of `r`.
fn crop_picture(image: &XyzImage, r: PixelRect, exposure: Exposure) -> Rgb8 {
    let mut pixels = Vec::new();
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            pixels.push(image.pixels[y as usize * image.width + x as usize]);
        }
    }
    let cropped = XyzImage {
        width: (r.x1 - r.x0) as usize,
        height: (r.y1 - r.y0) as usize,
        pixels,
        emitter: None,
        lit_by: None,
        white: None,
    };
    picture(&cropped, exposure)
}

/// "travertine (as found)", and the white tile by its name alone (its state is `reference`).
fn sample_name(stone: &str, state: &str) -> String {
    if state == "reference" { stone.to_owned() } else { format!("{stone} ({state})") }
}

/// L* a* b* to one decimal, without the "-0.0" of a value that rounds to zero from below.
fn lab_text(lab: [f64; 3]) -> String {
    let [l, a, b] = lab.map(|v| (v * 10.0).round() / 10.0 + 0.0);
    format!("{l:.1} {a:.1} {b:.1}")
}

fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# restauro demo\n");
    let _ = writeln!(
        s,
        "{} renders on an embedded cluster of {} workers, {:.1} s in all{}. Every image below is \
         beside this report; the JSON form is `report.json` (schema `{}`).\n",
        r.renders.len(),
        r.workers,
        r.total_s,
        if r.quick { " (`--quick`: small images, few samples)" } else { "" },
        r.schema
    );
    let _ = writeln!(s, "## Contact sheets\n");
    for i in r.images.iter().filter(|i| i.file.starts_with("sheets/")) {
        let _ = writeln!(s, "### {}\n\n![{}]({})\n", i.what, i.what, i.file);
    }
    let _ = writeln!(s, "## Renders\n");
    let _ = writeln!(
        s,
        "| render | scene | variant | lights | integrator | size | spp | max depth | render time |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---:|---:|---:|");
    for x in &r.renders {
        let _ = writeln!(
            s,
            "| {} | `{}` | {} | {} | {} | {}×{} | {} | {} | {:.1} s |",
            x.job,
            x.scene,
            x.variant.as_deref().unwrap_or("—"),
            x.lights.join("; "),
            x.integrator,
            x.width,
            x.height,
            x.samples_per_pixel,
            x.max_depth,
            x.render_s
        );
    }
    let _ = writeln!(s, "\nSeen: {}.\n", r.renders.first().map_or("", |x| x.retinex.as_str()));
    let _ = writeln!(s, "## Images\n");
    let _ = writeln!(s, "| file | what |");
    let _ = writeln!(s, "|---|---|");
    for i in &r.images {
        let _ = writeln!(s, "| [`{}`]({}) | {} |", i.file, i.file, i.what);
    }
    let _ = writeln!(s, "\n## The stones under each light, as rendered and as seen\n");
    let _ = writeln!(
        s,
        "Mean over the inner {:.0} % of each square. *Before*: CIELAB of the render relative to \
         its white tile ({:.0} % reflectance), D65 white — what a camera balanced for daylight \
         shows. *After*: CIELAB of the seen image (adapted to the light; D65 white). ΔE00 to the \
         same square in the D65 render as rendered (before and after) and, after, also as seen \
         (the D65 render's seen image: what an observer sees in daylight; under A people keep \
         some of the light's warmth). *As found* is derived: \
         {:.0} % of the surface covered by a soot proxy.\n",
        INNER_FRACTION * 100.0,
        r.white_reflectance * 100.0,
        r.soot_fraction * 100.0
    );
    let _ = writeln!(
        s,
        "| sample | light | before: L* a* b* | sRGB | before: ΔE00 to D65 rendered | after: L* a* b* \
         | sRGB | after: ΔE00 to D65 rendered | after: ΔE00 to D65 seen |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---|---|---:|---:|");
    for c in &r.stones {
        let (b, a) = (&c.before_retinex, &c.after_retinex);
        let _ = writeln!(
            s,
            "| {} | CIE {} | {} | `{}` | {:.2} | {} | `{}` | {:.2} | {:.2} |",
            sample_name(c.stone, c.state),
            c.illuminant,
            lab_text(b.lab),
            b.srgb_hex,
            b.delta_e00_to_d65,
            lab_text(a.lab),
            a.srgb_hex,
            a.delta_e00_to_d65,
            a.delta_e00_to_d65_seen.unwrap_or(f64::NAN)
        );
    }
    let _ = writeln!(s, "\n## What cleaning changes on the facade\n");
    let _ = writeln!(s, "| light | CIELAB white (cd/m²) | mean ΔE00 | 95th percentile | pixels |");
    let _ = writeln!(s, "|---|---:|---:|---:|---:|");
    for c in &r.cleaning {
        let _ = writeln!(
            s,
            "| {} | {:.0} | {:.2} | {:.2} | {} |",
            c.light.title(),
            c.white_cd_m2,
            c.mean_delta_e00,
            c.p95_delta_e00,
            c.pixels
        );
    }
    let f = &r.floodlighting;
    let _ = writeln!(s, "\n## The facade floodlit at night\n");
    let _ = writeln!(
        s,
        "`{}`: two metal-halide floodlights and an LED spot of measured photometry. The \
         illuminance over the fourth bay (grid `{}`, {} points, {} samples a point, direct and \
         inter-reflected light, computed on the cluster as `restauro illuminance` computes it):\n",
        f.scene, f.grid, f.points, f.samples_per_point
    );
    let _ = writeln!(s, "| minimum | mean | maximum | uniformity E_min/E_mean |");
    let _ = writeln!(s, "|---:|---:|---:|---:|");
    let _ = writeln!(
        s,
        "| {:.1} lx | {:.1} lx | {:.1} lx | {:.3} |\n",
        f.min_lux, f.mean_lux, f.max_lux, f.uniformity
    );
    let _ = writeln!(
        s,
        "![the floodlit bay in false colour]({})\n\nEach point: [`{}`]({}); the document: \
         [`{}`]({}).",
        f.map, f.table, f.table, f.document, f.document
    );
    let _ = writeln!(s, "\n{}", restauro_spectral::library::ECOSTRESS_ACKNOWLEDGEMENT);
    s
}
