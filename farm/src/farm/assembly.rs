//! A job whose tiles are all stored becomes its result files: the tiles placed in the
//! framebuffer, the Retinex run on the whole image, the EXRs and PNGs written. Each step is a
//! move of the job's lifecycle, so a job cancelled meanwhile stops at the next step, and its
//! partial files are removed rather than left for a client to find.

use super::Farm;
use super::sequence_frame::FrameStep;
use crate::error::FarmError;
use crate::ids::JobId;
use crate::job::{IllegalTransition, JobRecord, JobState};
use restauro_image::framebuffer::{Framebuffer, TileLayout};
use restauro_image::results::{ResultOptions, Written, write_grid_results, write_results};
use restauro_scene::job::JobSpec;
use restauro_scene::plan::Plan;
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::EyeHistory;
use std::sync::Arc;
use std::time::Instant;
use tracing::{info, warn};

/// Assembles job `id`, which is in the assembling state. Runs on a blocking thread.
pub(super) fn assemble(farm: &Arc<Farm>, id: &JobId) {
    let _span = tracing::info_span!("assemble", job = %id).entered();
    let started = Instant::now();
    let Some(record) = farm.jobs_record(id) else { return };
    let assembled = guarded("assembling the image", || files(farm, &record));
    match assembled {
        Ok(files) => match farm.finish_job(id, files) {
            Ok(()) => info!(seconds = started.elapsed().as_secs_f64(), "job done"),
            Err(e) => {
                info!("{e}; its files are removed");
                remove_results(farm, id);
            }
        },
        Err(Outcome::Ended(e)) => {
            info!("{e}; assembly stopped");
            remove_results(farm, id);
        }
        Err(Outcome::Failed(reason)) => {
            remove_results(farm, id);
            farm.fail_job(id, reason);
        }
    }
}

/// Runs `write`, a job's writing of its files. A panic there is a defect, but it must not leave
/// the job assembling for ever, with every client watching it waiting: it becomes a failure
/// with the panic's words (the panic hook has written where it happened to the log); `doing`
/// says what stopped.
fn guarded<T>(doing: &str, write: impl FnOnce() -> Result<T, Outcome>) -> Result<T, Outcome> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(write)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(Outcome::Failed(format!(
            "{doing} stopped on an internal error ({what}); this is a defect of restauro: please \
             report it with the coordinator's log"
        )))
    })
}

enum Outcome {
    /// The job ended (cancelled) during assembly.
    Ended(FarmError),
    /// Assembly itself failed: the job fails with this reason.
    Failed(String),
}

fn files(farm: &Arc<Farm>, record: &JobRecord) -> Result<Vec<String>, Outcome> {
    let id = &record.id;
    let plan = &record.plan;
    let frame = placed(farm, id, plan, 0)?;
    farm.transition(id, JobRecord::begin_post_processing).map_err(Outcome::Ended)?;
    let stem = record.spec.name.file_stem();
    let page = Page { plan, stem: &stem, info: &record.info(), spec: &record.spec, eye: None };
    Ok(write(farm, id, frame, &page)?.files)
}

/// The framebuffer of `plan` from its tiles in the store, the first of which is the job's tile
/// `first_tile`.
fn placed(
    farm: &Arc<Farm>,
    id: &JobId,
    plan: &Plan,
    first_tile: u32,
) -> Result<Framebuffer, Outcome> {
    let mut frame = Framebuffer::new(plan.width, plan.height, TileLayout::from(plan));
    for (index, rect) in plan.tiles().enumerate() {
        let data = stored_tile(farm, id, first_tile + index as u32)
            .map_err(|e| Outcome::Failed(e.to_string()))?
            .ok_or_else(|| {
                // A job cancelled meanwhile has had its tiles dropped: that is not a failure.
                ended(farm, id).unwrap_or_else(|| {
                    Outcome::Failed(format!("tile {index} is missing from the store"))
                })
            })?;
        frame.place(index as u32, &rect, &data).map_err(|e| Outcome::Failed(e.to_string()))?;
    }
    Ok(frame)
}

/// How long assembly waits for a store that cannot be read (a lost connection to PostgreSQL,
/// its server restarting) before the job fails.
const STORE_PATIENCE: std::time::Duration = std::time::Duration::from_secs(120);

/// A stored tile, read again after a failure of the store until it answers or
/// [`STORE_PATIENCE`] has passed: a store that recovers must not fail a finished job.
fn stored_tile(
    farm: &Farm,
    id: &JobId,
    tile: u32,
) -> Result<Option<Vec<u8>>, crate::store::StoreError> {
    let started = Instant::now();
    let mut wait = std::time::Duration::from_millis(50);
    loop {
        match farm.store.tile(id, tile) {
            Err(e) if started.elapsed() < STORE_PATIENCE => {
                warn!(job = %id, tile, "reading a tile to assemble: {e}; trying again");
                std::thread::sleep(wait);
                wait = (wait * 2).min(std::time::Duration::from_secs(2));
            }
            other => return other,
        }
    }
}

/// What a framebuffer is written as: rendered by `plan`, under `stem` with the header `info`,
/// for the job `spec`; a sequence's frame seen by the eye `eye` brings.
struct Page<'a> {
    plan: &'a Plan,
    stem: &'a str,
    info: &'a str,
    spec: &'a JobSpec,
    eye: Option<EyeHistory>,
}

/// Writes the files of `frame` as `page` says.
fn write(
    farm: &Arc<Farm>,
    id: &JobId,
    frame: Framebuffer,
    page: &Page<'_>,
) -> Result<Written, Outcome> {
    let written = write_here(farm, id, frame, page)?;
    // In the object store before the job or frame is done, so a coordinator taking over
    // serves them.
    let dir = farm.results_dir(id);
    for file in &written.files {
        put_result(farm, id, &crate::objects::result_key(id.as_str(), file), &dir.join(file))?;
    }
    Ok(written)
}

/// The longest wait between two puts of a result the object store refused.
const OBJECTS_RETRY_MAX: std::time::Duration = std::time::Duration::from_secs(5);

/// Puts one result file in the object store, again and again while it refuses it (a full
/// bucket, a server down: `Objects::problem` says so meanwhile, in `restauro jobs`, the
/// metrics and `/readyz`) — the job waits in assembly, its tiles kept, rather than fail and
/// have to be rendered again — until the file is in or the job has ended (cancelled).
fn put_result(
    farm: &Arc<Farm>,
    id: &JobId,
    key: &str,
    path: &std::path::Path,
) -> Result<(), Outcome> {
    let mut wait = std::time::Duration::from_millis(100);
    loop {
        let Err(e) = farm.objects.put_file(key, path) else { return Ok(()) };
        if let Some(ended) = ended(farm, id) {
            return Err(ended);
        }
        if wait < OBJECTS_RETRY_MAX / 16 {
            warn!(job = %id, "{e}; the job waits, putting its results again until they are in");
        }
        std::thread::sleep(wait);
        wait = (wait * 2).min(OBJECTS_RETRY_MAX);
    }
}

/// The outcome for a job that has ended (cancelled) while it was being assembled, if it has.
fn ended(farm: &Arc<Farm>, id: &JobId) -> Option<Outcome> {
    match farm.transition(id, |_| Ok(())) {
        Ok((_, r)) if r.state().is_final() => {
            Some(Outcome::Ended(FarmError::from(IllegalTransition {
                job: id.clone(),
                from: r.state(),
                to: JobState::PostProcessing,
            })))
        }
        _ => None,
    }
}

/// Writes the files of `frame` into the job's results folder.
fn write_here(
    farm: &Arc<Farm>,
    id: &JobId,
    frame: Framebuffer,
    page: &Page<'_>,
) -> Result<Written, Outcome> {
    let Page { plan, stem, info, spec, eye } = *page;
    let dir = farm.results_dir(id);
    std::fs::create_dir_all(&dir)
        .map_err(|e| Outcome::Failed(format!("{}: {e}", dir.display())))?;
    if plan.grids {
        let written = write_grid_results(&dir, frame, stem, info)
            .map_err(|e| Outcome::Failed(e.to_string()))?;
        info!("grids written");
        return Ok(written);
    }
    let retinex = farm.config.retinex.then(|| RetinexParams {
        paths: spec.retinex.paths,
        seed: spec.retinex.seed,
        ..RetinexParams::default()
    });
    let options = ResultOptions { name: stem, info, exposure: spec.exposure, retinex, eye };
    let written =
        write_results(&dir, frame, &options).map_err(|e| Outcome::Failed(e.to_string()))?;
    info!(retinex_s = written.retinex_s, "results written");
    if farm.config.retinex {
        farm.metrics.retinex_seconds.observe(written.retinex_s);
    }
    Ok(written)
}

/// Writes the frames of sequence `id` whose tiles are all stored, in order, and finishes the
/// job after its last frame (see `sequence_frame`). Runs on a thread of its own.
pub(super) fn assemble_frames(farm: &Arc<Farm>, id: &JobId) {
    let _span = tracing::info_span!("frames", job = %id).entered();
    loop {
        match farm.next_frame_step(id) {
            FrameStep::Stop => return,
            FrameStep::Finish => {
                let files = farm.jobs_record(id).map(|r| r.results).unwrap_or_default();
                let finished = farm
                    .transition(id, JobRecord::begin_post_processing)
                    .and_then(|_| farm.finish_job(id, files));
                match finished {
                    Ok(()) => info!("sequence done"),
                    Err(e) => info!("{e}; the sequence stops"),
                }
                farm.next_frame_step(id);
                return;
            }
            FrameStep::Frame(work) => {
                let started = Instant::now();
                let written = guarded("writing the frame", || {
                    let frame = placed(farm, id, &work.plan, work.tiles.start)?;
                    let page = Page {
                        plan: &work.plan,
                        stem: &work.stem,
                        info: &work.info,
                        spec: &work.spec,
                        eye: work.eye,
                    };
                    write(farm, id, frame, &page)
                });
                match written {
                    Ok(w) if farm.frame_ready(id, work.frame, &w.files, w.eye) => {
                        info!(
                            frame = work.frame,
                            seconds = started.elapsed().as_secs_f64(),
                            "frame ready"
                        );
                        if let Err(e) = farm.store.remove_tile_range(id, work.tiles.clone()) {
                            warn!(frame = work.frame, "could not drop the frame's tiles: {e}");
                        }
                    }
                    Ok(w) => {
                        remove_files(farm, id, &w.files);
                        farm.next_frame_step(id);
                        return;
                    }
                    Err(Outcome::Ended(e)) => {
                        info!("{e}; the frames stop");
                        farm.next_frame_step(id);
                        return;
                    }
                    Err(Outcome::Failed(reason)) => {
                        farm.fail_job(id, format!("frame {}: {reason}", work.frame));
                        farm.next_frame_step(id);
                        return;
                    }
                }
            }
        }
    }
}

/// Removes files of a job that no record lists (a frame written as its job was cancelled).
fn remove_files(farm: &Farm, id: &JobId, files: &[String]) {
    let dir = farm.results_dir(id);
    for file in files {
        if let Err(e) = std::fs::remove_file(dir.join(file)) {
            warn!(file, "could not remove a frame's file: {e}");
        }
    }
}

fn remove_results(farm: &Farm, id: &JobId) {
    let dir = farm.results_dir(id);
    if dir.exists()
        && let Err(e) = std::fs::remove_dir_all(&dir)
    {
        warn!(dir = %dir.display(), "could not remove the job's files: {e}");
    }
}
