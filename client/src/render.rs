//! `restauro render`: a scene rendered through a cluster — an embedded local one (a coordinator
//! and workers on loopback, real processes) unless `--coordinator` names one — or, with
//! `--in-process`, in this process. Either way the scene and options are resolved by the same
//! plan and the results written by the same code, so the images are bit-identical.

use crate::cli::RenderArgs;
use anyhow::{Context, Result};
use restauro_assets::bundle_scene;
use restauro_assets::load_scene;
use restauro_cluster::progress::Progress;
use restauro_cluster::{self as cluster, LocalCluster};
use restauro_image::framebuffer::{Framebuffer, TileExtras, TileLayout, encode_tile};
use restauro_image::image_files::{MAX_PIXELS, read_exr};
use restauro_image::results::{ResultOptions, write_grid_results, write_results};
use restauro_proto as pb;
use restauro_proto::job_status::JobState;
use restauro_render::prepared::PreparedScene;
use restauro_render::tile::render_tile;
use restauro_scene::bundle::Bundle;
use restauro_scene::job::{JobName, JobSpec, RetinexOptions};
use restauro_scene::load::Limits;
use restauro_scene::plan::{Plan, RenderOptions};
use restauro_spectral::display::Exposure;
use restauro_spectral::retinex::RetinexParams;
use std::fmt::Write as _;
use std::time::Instant;

/// The scene-level options of the command line.
pub fn render_options(args: &RenderArgs) -> RenderOptions {
    RenderOptions {
        variant: args.variant.clone(),
        integrator: args.integrator,
        samples_per_pixel: args.spp,
        width: args.width,
        height: args.height,
        spectral: args.spectral,
        tile: args.tile,
        grids: args.grids,
        noise_target: args.noise,
    }
}

/// The job's name: the scene file's stem, and the variant.
pub fn job_name(args: &RenderArgs) -> String {
    let stem = args.scene.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
    let name = match &args.variant {
        Some(v) => format!("{stem}-{v}"),
        None => stem.to_owned(),
    };
    if args.grids { format!("{name}-illuminance") } else { name }
}

/// The job the command line asks for: its one conversion to the domain's job, checked here as
/// the coordinator checks it.
pub fn job_spec(args: &RenderArgs, priority: i32) -> Result<JobSpec> {
    let exposure: Exposure = args.exposure.parse().map_err(|e| anyhow::anyhow!("--{e}"))?;
    let retinex = RetinexOptions::new(Some(args.retinex_paths), Some(args.retinex_seed))
        .map_err(|e| anyhow::anyhow!("--retinex-paths: {}", e.problem))?;
    let name = job_name(args);
    let name = JobName::new(&name).map_err(|e| {
        anyhow::anyhow!("the job's name (from the scene file and variant) `{name}`: {}", e.problem)
    })?;
    let spec = JobSpec {
        name,
        priority,
        render: render_options(args),
        exposure,
        retinex,
        frames: Vec::new(),
    };
    spec.checked().map_err(|e| {
        let flag = match e.field {
            "render.samples_per_pixel" => "spp",
            "render.noise_target" => "noise",
            other => other.trim_start_matches("render."),
        };
        anyhow::anyhow!("--{flag}: {}", e.problem)
    })
}

/// Checks the scene here (errors name the user's own files) and bundles it for a coordinator.
pub fn checked_bundle(args: &RenderArgs) -> Result<(Bundle, Plan)> {
    let limits: Limits = (&args.run.limits).into();
    let scene = load_scene(&args.scene, &limits)?;
    let plan = Plan::new(&scene, &render_options(args), &limits, &args.scene)?;
    let bundle = bundle_scene(&args.scene, &limits)?;
    Ok((bundle, plan))
}

pub fn run(args: &RenderArgs) -> Result<String> {
    if !args.variants.is_empty() {
        return run_variants(args);
    }
    if args.run.in_process {
        return run_in_process(args);
    }
    let started = Instant::now();
    let cluster = Cluster::open(args)?;
    let spec = job_spec(args, 0)?;
    let (bundle, plan) = checked_bundle(args)?;
    let (status, files) = cluster.run(&bundle, &spec, &args.scene, &args.out)?;
    let mut s = String::new();
    let size = if plan.grids {
        format!("{} grid points", plan.width)
    } else {
        format!("{}×{}", plan.width, plan.height)
    };
    let _ = writeln!(
        s,
        "{} {} ({size}, {}, {} spp, {} tiles) through {} in {:.2} s (job {})",
        if plan.grids { "computed" } else { "rendered" },
        args.scene.display(),
        plan.integrator,
        plan.samples_per_pixel,
        status.tiles_total,
        cluster.description(args),
        started.elapsed().as_secs_f64(),
        status.id
    );
    for f in files {
        let _ = writeln!(s, "wrote {}", f.display());
    }
    Ok(s)
}

/// The cluster a render runs on: the coordinator named, or an embedded local one (started
/// first, so that its processes come up while the scene is checked), kept while this lives.
pub struct Cluster {
    url: String,
    token: String,
    tls_ca: Option<std::path::PathBuf>,
    _local: Option<LocalCluster>,
}

impl Cluster {
    pub fn open(args: &RenderArgs) -> Result<Self> {
        let tls_ca = args.run.connect.tls_ca.clone();
        match &args.run.connect.coordinator {
            Some(url) => {
                let token = crate::connect::client_token(args.run.connect.token_file.as_deref())?;
                Ok(Self { url: url.clone(), token, tls_ca, _local: None })
            }
            None => {
                // The embedded coordinator checks the job against the limits given here.
                let limits = args.run.limits.to_args();
                let limits: Vec<&str> = limits.iter().map(String::as_str).collect();
                let c = LocalCluster::start_with(
                    args.run.workers.max(1),
                    args.run.cluster_logs.as_deref(),
                    &limits,
                )?;
                let (url, token) = (c.url.clone(), c.client_token.clone());
                Ok(Self { url, token, tls_ca, _local: Some(c) })
            }
        }
    }

    /// "coordinator URL" or "an embedded cluster of N workers".
    pub fn description(&self, args: &RenderArgs) -> String {
        match self._local {
            None => format!("coordinator {}", self.url),
            Some(_) => format!("an embedded cluster of {} workers", args.run.workers.max(1)),
        }
    }

    /// Uploads `bundle`, submits `spec`, follows the job with a progress bar and fetches its
    /// files into `out`. Refused when the job ends without results.
    pub fn run(
        &self,
        bundle: &Bundle,
        spec: &JobSpec,
        scene: &std::path::Path,
        out: &std::path::Path,
    ) -> Result<(restauro_proto::job_status::JobStatus, Vec<std::path::PathBuf>)> {
        let runtime = cluster::runtime()?;
        runtime.block_on(async {
            let tls_ca = self.tls_ca.as_deref();
            let mut client =
                cluster::connect_as(&self.url, &self.token, tls_ca, pb::PROTOCOL_VERSION).await?;
            cluster::upload(&mut client, bundle).await?;
            let what = format!("submitting {}", scene.display());
            let submitted = cluster::submit(&mut client, bundle, spec, &what).await?;
            let status = cluster::watch(&mut client, &submitted.id, true).await?;
            if status.state != JobState::Done {
                anyhow::bail!(
                    "job {} ended without results: {}",
                    status.id,
                    crate::connect::shown(&status.error)
                );
            }
            let files = cluster::fetch(&client, &status, out).await?;
            anyhow::Ok((status, files))
        })
    }
}

/// `--variants a,b,…`: each variant rendered as `--variant` renders it, then the first compared
/// with each other, as rendered (the white the display chooses for the first) and as seen
/// (after the Retinex, relative to its white).
fn run_variants(args: &RenderArgs) -> Result<String> {
    let mut text = String::new();
    let mut stems = Vec::new();
    for variant in &args.variants {
        let one =
            RenderArgs { variant: Some(variant.clone()), variants: Vec::new(), ..args.clone() };
        text.push_str(&run(&one)?);
        stems.push((variant.as_str(), job_spec(&one, 0)?.name.file_stem()));
    }
    let read = |stem: &str, suffix: &str| {
        let path = args.out.join(format!("{stem}{suffix}.exr"));
        read_exr(&path, MAX_PIXELS).with_context(|| format!("reading {}", path.display()))
    };
    let Some(((first, first_stem), others)) = stems.split_first() else { return Ok(text) };
    for (variant, stem) in others {
        let dir = args.out.join(format!("compare-{first}-vs-{variant}"));
        for (suffix, what, white) in
            [("", "rendered", Exposure::default()), ("-retinex", "seen", Exposure::Relative)]
        {
            let (a, b) = (read(first_stem, suffix)?, read(stem, suffix)?);
            let white_text = if suffix.is_empty() { "auto" } else { "relative" };
            let names = (format!("{first}, {what}"), format!("{variant}, {what}"));
            text.push_str(&crate::compare::compare_images(
                (&a, &names.0),
                (&b, &names.1),
                (white, white_text),
                2.0,
                &dir.join(what),
            )?);
        }
    }
    Ok(text)
}

fn run_in_process(args: &RenderArgs) -> Result<String> {
    let limits: Limits = (&args.run.limits).into();
    let mut scene = load_scene(&args.scene, &limits)?;
    let spec = job_spec(args, 0)?;
    let plan = Plan::new(&scene, &spec.render, &limits, &args.scene)?;
    plan.apply(&mut scene);
    let started = Instant::now();
    let prepared = PreparedScene::for_plan(&scene, &plan)?;
    let prepare_s = started.elapsed().as_secs_f64();
    let bar = Progress::new(
        "render",
        "tiles",
        Some(plan.tile_count().into()),
        "render {bar:40} {pos}/{len} tiles, {elapsed} elapsed, eta {eta}",
    )?;
    let layout = TileLayout::from(&plan);
    let mut frame = Framebuffer::new(plan.width, plan.height, layout);
    let render_started = Instant::now();
    for (index, rect) in plan.tiles().enumerate() {
        let tile = render_tile(&prepared, rect, plan.spectral);
        // The same bytes a worker sends: the in-process image is the cluster's, bit for bit.
        let extras = TileExtras {
            sky: tile.sky.as_deref(),
            lit_by: tile.lit_by.as_deref(),
            white: tile.white.as_deref().filter(|_| layout.white),
            samples: tile.samples.as_deref().filter(|_| layout.counts()),
        };
        let data = encode_tile(
            &tile.xyz,
            extras,
            tile.spectral.as_ref().map(|s| s.iter().map(|p| &p.0[..])),
        );
        frame.place(index as u32, &rect, &data)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let render_s = render_started.elapsed().as_secs_f64();
    let mean_y = frame.xyz.iter().map(|p| f64::from(p[1])).sum::<f64>() / frame.xyz.len() as f64;
    let name = spec.name.file_stem();
    let integrator = plan.integrator.keyword();
    let info = format!(
        "variant={} integrator={integrator} spp={} max_depth={} seed={}",
        plan.variant.as_deref().unwrap_or("base"),
        plan.samples_per_pixel,
        plan.max_depth,
        plan.seed
    );
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    if plan.grids {
        let written = write_grid_results(&args.out, frame, &name, &info)?;
        let mut s = format!(
            "computed {} points of {} in {render_s:.2} s after {prepare_s:.2} s of preparation\n",
            plan.width,
            args.scene.display()
        );
        for f in written.files {
            let _ = writeln!(s, "wrote {}", args.out.join(f).display());
        }
        return Ok(s);
    }
    let written = write_results(
        &args.out,
        frame,
        &ResultOptions {
            name: &name,
            info: &info,
            exposure: spec.exposure,
            retinex: Some(RetinexParams {
                paths: spec.retinex.paths,
                seed: spec.retinex.seed,
                ..RetinexParams::default()
            }),
            eye: None,
        },
    )?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "rendered {} ({}×{}, {integrator}, {} spp, {} triangles) in {render_s:.2} s after {prepare_s:.2} s of preparation; mean luminance {mean_y:.2} cd/m²",
        args.scene.display(),
        plan.width,
        plan.height,
        plan.samples_per_pixel,
        prepared.triangle_count()
    );
    for f in written.files {
        let _ = writeln!(s, "wrote {}", args.out.join(f).display());
    }
    Ok(s)
}
