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
//! This module is the command: the cluster, the renders through it, and the floodlit grid's
//! documents (with [`crate::illuminance`]). What the demo renders, its scenes, is
//! `restauro_demo::plan`; the analysis, the contact sheets and the report — and how they compare
//! colours — are `restauro_demo::report`.

use crate::cli::DemoArgs;
use anyhow::{Context, Result, anyhow, bail};
use indicatif::{ProgressBar, ProgressStyle};
use restauro_assets::bundle_scene;
use restauro_assets::load_scene;
use restauro_cluster::progress::Progress;
use restauro_cluster::{self as cluster, Client, LocalCluster};
use restauro_demo::plan::{Job, Kind, Size, write_scenes};
use restauro_demo::report::{
    Finished, Floodlighting, RenderRecord, Report, Run, analyse, relative, seen_method,
};
use restauro_image::image_files::read_exr;
use restauro_proto as pb;
use restauro_proto::job_status::{JobState, JobStatus};
use restauro_scene::job::{JobName, JobSpec};
use restauro_scene::load::{Limits, LoadedScene};
use restauro_scene::plan::RenderOptions;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

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
    let scenes = load_scenes(&jobs)?;

    let runtime = cluster::runtime()?;
    let finished = runtime.block_on(render_all(&local, &jobs, out, &bar))?;
    drop(local);

    bar.set_message("analysis");
    bar.set_style(bar_style("{msg:>12} {spinner} {elapsed} elapsed")?);
    let analysis = analyse(out, &size, &jobs, &finished, &scenes)?;
    let floodlighting = floodlighting(out, &jobs, &finished, &scenes)?;
    bar.finish_and_clear();

    let total_s = started.elapsed().as_secs_f64();
    let run = Run { quick: args.quick, workers, total_s };
    let report = Report::new(run, &size, analysis, finished, floodlighting);
    let md_path = report.write(out)?;
    Ok(summary(&report, out, &md_path))
}

/// Each scene the jobs render, loaded once.
fn load_scenes(jobs: &[Job]) -> Result<BTreeMap<PathBuf, LoadedScene>> {
    let mut scenes: BTreeMap<PathBuf, LoadedScene> = BTreeMap::new();
    for job in jobs {
        if !scenes.contains_key(&job.scene) {
            let loaded = load_scene(&job.scene, &Limits::default())?;
            scenes.insert(job.scene.clone(), loaded);
        }
    }
    Ok(scenes)
}

/// What the command prints: the renders, the stones under CIE A, what cleaning changes, the
/// floodlit bay, and where the sheets and the report are.
fn summary(report: &Report, out: &Path, md_path: &Path) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "restauro demo: {} renders on an embedded cluster of {} workers in {:.1} s",
        report.renders.len(),
        report.workers,
        report.total_s
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
    s
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
    let submitted = submit_all(&mut client, jobs).await?;
    let total: u64 = submitted.iter().map(|s| u64::from(s.tiles_total)).sum();
    bar.set_length(total);
    bar.set_position(0);
    bar.set_message("render");
    bar.set_style(bar_style("{msg:>12} {bar:40} {pos}/{len} tiles, {elapsed} elapsed, eta {eta}")?);
    let statuses = watch_all(&client, &submitted, bar).await?;
    bar.set_message("fetch");
    let mut finished = Vec::new();
    for ((job, (status, render_s)), plan) in jobs.iter().zip(statuses).zip(&submitted) {
        if status.state != JobState::Done {
            bail!(
                "the demo's render {} ended without results: {}",
                job.key,
                crate::connect::shown(&status.error)
            );
        }
        let dir = out.join("renders").join(&job.key);
        let files = cluster::fetch(&client, &status, &dir).await?;
        let record = render_record(out, job, plan, render_s, &files)?;
        finished.push(Finished { record, dir });
    }
    Ok(finished)
}

/// Uploads each job's scene and submits it; returns their first statuses, in the jobs' order.
async fn submit_all(client: &mut Client, jobs: &[Job]) -> Result<Vec<JobStatus>> {
    let mut submitted = Vec::new();
    // Falling priorities: the renders run one after another (equal priorities would share the
    // workers), so each one's time is its own.
    for (index, job) in jobs.iter().enumerate() {
        let bundle = bundle_scene(&job.scene, &Limits::default())?;
        cluster::upload(client, &bundle).await?;
        let spec = JobSpec {
            name: JobName::new(&job.key)?,
            priority: (jobs.len() - index) as i32,
            render: RenderOptions {
                variant: job.kind.variant(),
                samples_per_pixel: NonZeroU32::new(job.spp),
                noise_target: job.noise_target,
                grids: matches!(job.kind, Kind::Grid),
                width: job.size.and_then(|(w, _)| NonZeroU32::new(w)),
                height: job.size.and_then(|(_, h)| NonZeroU32::new(h)),
                ..RenderOptions::default()
            },
            frames: job.frames.clone(),
            ..JobSpec::default()
        };
        let what = format!("submitting {}", job.scene.display());
        let status = cluster::submit(client, &bundle, &spec, &what).await?;
        submitted.push(status);
    }
    Ok(submitted)
}

/// A fetched render as the report lists it: its scene (read again for its lights and
/// integrator), its size from the plan the coordinator made, its time and its files.
fn render_record(
    out: &Path,
    job: &Job,
    plan: &JobStatus,
    render_s: f64,
    files: &[PathBuf],
) -> Result<RenderRecord> {
    let loaded = load_scene(&job.scene, &Limits::default())?;
    let render = &loaded.file.render;
    Ok(RenderRecord {
        job: job.key.clone(),
        scene: relative(out, &job.scene),
        variant: job.kind.variant(),
        lights: loaded.lights.iter().map(ToString::to_string).collect(),
        integrator: render.integrator,
        width: plan.width,
        height: plan.height,
        samples_per_pixel: job.spp,
        noise_target: job.noise_target,
        max_depth: render.max_depth,
        retinex: seen_method(),
        render_s,
        files: files.iter().map(|f| relative(out, f)).collect(),
    })
}

/// Follows every job to its end on one progress bar; returns each final status and the time from
/// its first tile to its end.
async fn watch_all(
    client: &Client,
    submitted: &[JobStatus],
    bar: &ProgressBar,
) -> Result<Vec<(JobStatus, f64)>> {
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
    let mut tasks = tokio::task::JoinSet::new();
    for (index, job) in submitted.iter().enumerate() {
        let (mut client, tx, id) = (client.clone(), tx.clone(), job.id.clone());
        tasks.spawn(async move {
            let mut stream = client
                .watch_job(pb::JobRef { job_id: id.to_string() })
                .await
                .map_err(|s| cluster::refused(&format!("watching job {id}"), s))?
                .into_inner();
            while let Some(sent) = stream
                .message()
                .await
                .map_err(|s| cluster::refused(&format!("watching {id}"), s))?
            {
                let _ = tx.send((index, cluster::read_status(sent)?));
            }
            anyhow::Ok(())
        });
    }
    drop(tx);
    let mut last: Vec<Option<JobStatus>> = vec![None; submitted.len()];
    let mut first_tile: Vec<Option<Instant>> = vec![None; submitted.len()];
    let mut ended: Vec<Option<f64>> = vec![None; submitted.len()];
    let mut done = vec![0u64; submitted.len()];
    while let Some((index, status)) = rx.recv().await {
        done[index] = u64::from(status.tiles_done);
        bar.set_position(done.iter().sum());
        if (status.tiles_done > 0 || status.tiles_leased > 0) && first_tile[index].is_none() {
            first_tile[index] = Some(Instant::now());
        }
        if status.state.is_final() {
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
            _ => Err(anyhow!("the coordinator stopped reporting job {}", submitted[i].id)),
        })
        .collect()
}

/// The floodlit grid's documents, written as `restauro illuminance` writes them, into
/// `out/floodlit/`; returns their numbers and files for the report.
fn floodlighting(
    out: &Path,
    jobs: &[Job],
    finished: &[Finished],
    scenes: &BTreeMap<PathBuf, LoadedScene>,
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
        Document { schema: SCHEMA.into(), scene: relative(out, &job.scene), variant: None, grids };
    let json = serde_json::to_string_pretty(&document)? + "\n";
    let written = write_documents(&out.join("floodlit"), &document, &json)?;
    let (Some(grid), Some([csv, png])) = (document.grids.first(), written.per_grid.first()) else {
        bail!("the floodlit scene has no grid");
    };
    Ok(Floodlighting {
        scene: relative(out, &job.scene),
        grid: grid.name.clone(),
        points: grid.points.len(),
        samples_per_point: job.spp,
        min_lux: grid.min_lux,
        mean_lux: grid.mean_lux,
        max_lux: grid.max_lux,
        uniformity: grid.uniformity,
        map: relative(out, png),
        table: relative(out, csv),
        document: relative(out, &written.json),
    })
}
