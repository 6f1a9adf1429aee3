//! A sequence started in the studio: a sun study of a day, or a walk through saved views, of
//! the revision the page shows, from the page's camera, for one hypothesis or two. The page says
//! what it wants in a person's words (clock times, a step such as `15m`, view names, frames a
//! second, metres a second); the frames are expanded here from the revision's scene by
//! [`Sequence::frames`], exactly as `restauro sequence` expands them, so the refusals are its
//! own. Each hypothesis is one farm job of the same frames: frame *n* of two jobs is the same
//! time (or the same place on the walk) in two hypotheses, which the page compares on its
//! before/after slider.
//!
//! A sequence's frames are fetchable as each is ready ([`frames`]), long before the job ends.

use super::Studio;
use super::api::{parse, query_value, scene_id};
use super::snapshot::{job_spec, manifest_json, refuse, scene_name, scene_seen_from};
use crate::error::{Result, StudioError};
use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, RawQuery, State};
use restauro_farm::ids::JobId;
use restauro_farm::job::JobStatus;
use restauro_scene::plan::RenderOptions;
use restauro_scene::scene_file::{Pose, SceneFile};
use restauro_scene::sequence::{Sequence, parse_every};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The most hypotheses one request renders: the slider compares two.
pub const MAX_HYPOTHESES: usize = 2;

/// What the page asks for.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceRequest {
    /// The day or the walk.
    pub sequence: Asked,
    /// The page's camera (Y up, relative to the preview's offset): a day is seen from it; a walk
    /// moves the camera itself. The scene's own camera when absent.
    #[serde(default)]
    pub camera: Option<Pose>,
    /// The render's options, read as a job's are (`render.width`, …); the hypothesis is not
    /// one of them but in `hypotheses`.
    #[serde(default)]
    pub render: RenderOptions,
    /// The hypotheses, one job each of the same frames: a variant's name, or `null` for the
    /// scene as it is. One, or two to compare.
    pub hypotheses: Vec<Option<String>>,
    /// The scene's revision the page shows (the latest when absent).
    #[serde(default)]
    pub revision: Option<u32>,
}

/// A sequence as the page words it.
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Asked {
    /// From `from` to `to` (clock times of the scene's site, `HH:MM`) every `every` (`15m`,
    /// `1h`, `90s`), on `date` (`YYYY-MM-DD`; the scene's own date when absent).
    Day {
        from: String,
        to: String,
        every: String,
        #[serde(default)]
        date: Option<String>,
    },
    /// Through the saved views named, in order, at `speed_m_s`, `fps` frames a second.
    Walk { views: Vec<String>, fps: f64, speed_m_s: f64 },
}

/// A clock time as the page's time input gives it (`08:00`, or `08:00:30`).
fn clock_time(field: &str, text: &str) -> Result<chrono::NaiveTime> {
    chrono::NaiveTime::parse_from_str(text, "%H:%M")
        .or_else(|_| chrono::NaiveTime::parse_from_str(text, "%H:%M:%S"))
        .map_err(|_| {
            refuse(
                field,
                format!("`{}` is not a clock time; write it as HH:MM, e.g. 08:00", short(text)),
            )
        })
}

fn short(text: &str) -> String {
    text.chars().take(40).collect::<String>().escape_debug().to_string()
}

impl Asked {
    /// The sequence, its fields read; what [`Sequence::frames`] checks is left to it.
    fn sequence(&self) -> Result<Sequence> {
        Ok(match self {
            Asked::Day { from, to, every, date } => Sequence::Day {
                date: match date.as_deref().map(str::trim).filter(|d| !d.is_empty()) {
                    None => None,
                    Some(d) => {
                        Some(chrono::NaiveDate::parse_from_str(d, "%Y-%m-%d").map_err(|_| {
                            refuse(
                                "sequence.date",
                                format!("`{}` is not a date; write it as YYYY-MM-DD", short(d)),
                            )
                        })?)
                    }
                },
                from: clock_time("sequence.from", from)?,
                to: clock_time("sequence.to", to)?,
                every: parse_every(every).map_err(|e| refuse("sequence.every", e))?,
            },
            Asked::Walk { views, fps, speed_m_s } => {
                Sequence::Walk { views: views.clone(), fps: *fps, speed_m_s: *speed_m_s }
            }
        })
    }

    /// What the jobs are called after (`aosta-day`, `aosta-walk`).
    fn kind(&self) -> &'static str {
        match self {
            Asked::Day { .. } => "day",
            Asked::Walk { .. } => "walk",
        }
    }
}

/// Refuses hypotheses the page cannot compare or the scene does not have, before any job is
/// submitted (so that no first job is left running when the second is refused).
fn check_hypotheses(scene: &SceneFile, hypotheses: &[Option<String>]) -> Result<()> {
    if hypotheses.is_empty() || hypotheses.len() > MAX_HYPOTHESES {
        return Err(refuse(
            "hypotheses",
            format!(
                "{} given; give one (the hypothesis shown) or two to compare",
                hypotheses.len()
            ),
        ));
    }
    if hypotheses.len() == 2 && hypotheses[0] == hypotheses[1] {
        return Err(refuse("hypotheses", "the same hypothesis twice; compare two different ones"));
    }
    for name in hypotheses.iter().flatten() {
        if !scene.variants.contains_key(name) {
            let known: Vec<&str> = scene.variants.keys().map(String::as_str).collect();
            return Err(refuse(
                "hypotheses",
                format!(
                    "the scene has no variant `{}`; it has {}",
                    short(name),
                    match known.is_empty() {
                        true => "none".to_owned(),
                        false => known.join(", "),
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// The sequence's jobs, one per hypothesis in the order asked, and its frames' labels.
#[derive(Serialize)]
pub struct Started {
    pub jobs: Vec<JobStatus>,
    pub labels: Vec<String>,
}

/// `POST /api/scenes/{id}/sequences`: starts the sequence on the farm; its jobs, which the
/// events then follow.
pub async fn start(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Bytes,
) -> Result<Json<Started>> {
    let id = scene_id(&id)?;
    let request: SequenceRequest = parse(&body, "the sequence request")?;
    if request.render.variant.is_some() {
        return Err(refuse(
            "render.variant",
            "a sequence's hypotheses are given as `hypotheses`, one job each",
        ));
    }
    let farm = &studio.farm;
    let preview = studio.previews.get(farm, id, request.revision).await?;
    let scene = scene_seen_from(farm, id, &preview, request.camera.as_ref())?;
    check_hypotheses(&scene, &request.hypotheses)?;
    let stem = format!("{}-{}", scene_name(farm, id), request.sequence.kind());
    let sequence = request.sequence.sequence()?;
    // The refusals of the expansion (a step of zero, an unknown view, the sun never up, more
    // frames than --max-frames) are the page's to mend: each is a bad request, in its words.
    let frames = sequence
        .frames(&scene, std::path::Path::new(&stem), farm.limits())
        .map_err(StudioError::Sequence)?;
    let labels = frames.iter().map(|f| f.label.clone()).collect();
    let manifest = manifest_json(&scene)?;
    let mut jobs: Vec<JobStatus> = Vec::with_capacity(request.hypotheses.len());
    for hypothesis in &request.hypotheses {
        let name = match hypothesis {
            Some(v) => format!("{stem}-{v}"),
            None => stem.clone(),
        };
        let render = RenderOptions { variant: hypothesis.clone(), ..request.render.clone() };
        let submitted = match job_spec(&name, render, frames.clone()) {
            Ok(spec) => farm.submit(manifest.clone(), spec).await.map_err(StudioError::from),
            Err(e) => Err(e),
        };
        match submitted {
            Ok(status) => jobs.push(status),
            Err(e) => {
                // Half a comparison is not what was asked for: the first job goes too.
                for job in &jobs {
                    if let Err(cancel) = farm.cancel(&job.id) {
                        tracing::warn!(job = %job.id, "the sequence's first job stays: {cancel}");
                    }
                }
                return Err(e);
            }
        }
    }
    Ok(Json(Started { jobs, labels }))
}

/// One frame of a sequence's job, as the page's timeline shows it.
#[derive(Serialize)]
pub struct FrameView {
    pub index: u32,
    pub label: String,
    /// Its files once it is ready (`<name>-0003.png`, `-0003-retinex.png`, …); none before.
    pub files: Vec<String>,
}

#[derive(Serialize)]
pub struct FramesView {
    pub job: String,
    pub name: String,
    pub frames_ready: u32,
    pub frames: Vec<FrameView>,
}

/// `GET /api/jobs/{id}/frames[?from=N]`: a sequence's frames (from frame `N`, 0 first), each
/// with its label and, once ready, its files (fetched from `/api/jobs/{id}/results/{name}` while
/// the job runs). A page that has the frames before `N` asks only for the rest, so that a long
/// sequence is not sent whole again at each frame.
pub async fn frames(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Json<FramesView>> {
    let id = JobId::parse(&id)?;
    let from = match query_value(query.as_deref(), "from") {
        None => 0,
        Some(text) => text.parse::<usize>().map_err(|_| {
            refuse("from", format!("`{}` is not a frame number (0, 1, 2, …)", short(&text)))
        })?,
    };
    let record = studio
        .farm
        .jobs_record(&id)
        .ok_or_else(|| StudioError::Farm(restauro_farm::error::FarmError::NoSuchJob(id.clone())))?;
    if !record.is_sequence() {
        return Err(StudioError::Request(format!(
            "job {id} ({}) is a still, not a sequence: its files are its results",
            record.spec.name
        )));
    }
    let stem = record.spec.name.file_stem();
    let frames = record
        .spec
        .frames
        .iter()
        .enumerate()
        .skip(from)
        .map(|(index, frame)| {
            let own = format!("{stem}-{index:04}");
            // `<own>.png`, `<own>-retinex.png`: not `<own>0…` of a longer number.
            let files = record
                .results
                .iter()
                .filter(|f| f.strip_prefix(&own).is_some_and(|r| r.starts_with(['.', '-'])))
                .cloned()
                .collect();
            FrameView { index: index as u32, label: frame.label.clone(), files }
        })
        .collect();
    Ok(Json(FramesView {
        job: id.to_string(),
        name: record.spec.name.to_string(),
        frames_ready: record.frames_ready,
        frames,
    }))
}
