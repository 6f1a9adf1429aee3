//! `restauro sequence`: one scene as a sequence of frames (the sun through a day or across the
//! year, a walk through saved views, the hypotheses), rendered as one job on a cluster. The
//! frames are expanded here, from the scene file, and each frame's files are fetched into
//! `--out` as `<scene>-<frame>.exr`, `.png`, … (frame numbers from 0000); then the contact sheet
//! and the video of the seen frames are made from them.

mod sheet;
mod video;

use crate::cli::{RenderArgs, SequenceArgs};
use crate::render::{Cluster, checked_bundle, job_spec};
use anyhow::{Context, Result, bail};
use restauro_proto::job_status::JobStatus;
use restauro_scene::job::JobSpec;
use restauro_scene::load::Limits;
use restauro_scene::plan::Plan;
use restauro_scene::sequence::Sequence;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// The sequence the flags ask for: exactly one kind.
pub fn sequence(args: &SequenceArgs) -> Result<Sequence> {
    let kinds = [
        args.sun.sun_from.is_some(),
        !args.sun.dates.is_empty(),
        !args.path.is_empty(),
        !args.render.variants.is_empty(),
    ];
    match kinds.iter().filter(|&&k| k).count() {
        1 => {}
        0 => bail!(
            "say which sequence: --sun-from 06:00 --to 21:00 --every 15m (a day), --dates \
             2026-06-21,2026-12-21 --at 12:00 (dates), --path VIEW,VIEW --fps 25 (a walk) or \
             --variants as-found,cleaned (the hypotheses)"
        ),
        _ => {
            bail!("give one kind of sequence: a day, dates, a walk or the hypotheses, not several")
        }
    }
    if let Some(sun) = args.sun.sequence() {
        return Ok(sun);
    }
    if !args.path.is_empty() {
        return Ok(Sequence::Walk {
            views: args.path.clone(),
            fps: args.fps,
            speed_m_s: args.speed,
        });
    }
    Ok(Sequence::Hypotheses { variants: args.render.variants.clone() })
}

/// A sequence rendered and fetched: its job, the first frame's plan, the cluster it ran on, the
/// job's last status and the files fetched.
pub struct Rendered {
    pub spec: JobSpec,
    pub plan: Plan,
    pub cluster: Cluster,
    pub status: JobStatus,
    pub files: Vec<PathBuf>,
}

/// Renders `sequence` of the scene `render` names, with its options, through a cluster, and
/// fetches every frame's files into `render.out`. `--in-process` is refused: `what` says what
/// it would have made.
pub fn render_sequence(render: &RenderArgs, sequence: &Sequence, what: &str) -> Result<Rendered> {
    if render.run.in_process {
        bail!("--in-process makes {what} at one time; a sequence runs on a cluster (leave it out)");
    }
    let limits: Limits = (&render.run.limits).into();
    let (bundle, plan) = checked_bundle(render)?;
    // The frames are expanded from the scene as the file says it (before its origin recentres
    // it), as a frame's scene is the bundle's with the frame's changes.
    let frames = sequence
        .frames(&bundle.scene, &render.scene, &limits)
        .with_context(|| format!("the sequence of {}", render.scene.display()))?;
    let mut spec = job_spec(render, 0)?;
    spec.frames = frames;
    let spec = spec.checked().map_err(|e| anyhow::anyhow!("{e}"))?;
    let cluster = Cluster::open(render)?;
    let (status, files) = cluster.run(&bundle, &spec, &render.scene, &render.out)?;
    Ok(Rendered { spec, plan, cluster, status, files })
}

pub fn run(args: &SequenceArgs) -> Result<String> {
    let started = Instant::now();
    let sequence = sequence(args)?;
    let render = RenderArgs { variants: Vec::new(), ..args.render.clone() };
    let Rendered { spec, plan, cluster, status, files } =
        render_sequence(&render, &sequence, "one image")?;
    let count = spec.frames.len();
    let seconds = started.elapsed().as_secs_f64();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "rendered {} as {count} frames ({}×{}, {}, {} spp, {} tiles) through {} in {seconds:.1} \
         s, {:.0} frames an hour (job {})",
        render.scene.display(),
        plan.width,
        plan.height,
        plan.integrator,
        plan.samples_per_pixel,
        status.tiles_total,
        cluster.description(&render),
        count as f64 * 3600.0 / seconds.max(1e-9),
        status.id
    );
    for (index, frame) in spec.frames.iter().enumerate() {
        let _ = writeln!(s, "frame {index:04}: {}", frame.label);
    }
    let _ = writeln!(s, "wrote {} files into {}", files.len(), render.out.display());
    let stem = spec.name.file_stem();
    // The seen frames; a coordinator that runs no Retinex (`--no-retinex`) writes none.
    let seen = render.out.join(format!("{stem}-0000-retinex.png")).is_file();
    let (suffix, how) = if seen { ("-retinex", "as seen") } else { ("", "as rendered") };
    let seen: Vec<(PathBuf, String)> = spec
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| (render.out.join(format!("{stem}-{i:04}{suffix}.png")), f.label.clone()))
        .collect();
    let sheet = render.out.join(format!("{stem}-sheet.png"));
    let title = format!("{}, {how}", render.scene.display());
    sheet::write_sheet(&sheet, &title, &seen)?;
    let _ = writeln!(s, "wrote {} (the contact sheet)", sheet.display());
    let video = render.out.join(format!("{stem}.apng"));
    let paths: Vec<PathBuf> = seen.into_iter().map(|(p, _)| p).collect();
    video::write_apng(&video, &paths, video_fps(args, &sequence))?;
    let _ = writeln!(s, "wrote {} (the video, APNG)", video.display());
    Ok(s)
}

/// The video's frames a second: a walk's own rate; otherwise `--video-fps`.
fn video_fps(args: &SequenceArgs, sequence: &Sequence) -> f64 {
    match sequence {
        Sequence::Walk { fps, .. } => *fps,
        _ => args.video_fps,
    }
}
