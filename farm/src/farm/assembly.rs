//! A job whose tiles are all stored becomes its result files: the tiles placed in the
//! framebuffer, the Retinex run on the whole image, the EXRs and PNGs written. Each step is a
//! move of the job's lifecycle, so a job cancelled meanwhile stops at the next step, and its
//! partial files are removed rather than left for a client to find.

use super::Farm;
use crate::error::FarmError;
use crate::ids::JobId;
use crate::job::{IllegalTransition, JobRecord, JobState};
use restauro_image::framebuffer::{Framebuffer, TileLayout};
use restauro_image::results::{ResultOptions, write_grid_results, write_results};
use restauro_spectral::retinex::RetinexParams;
use std::sync::Arc;
use std::time::Instant;
use tracing::{info, warn};

/// Assembles job `id`, which is in the assembling state. Runs on a blocking thread.
pub(super) fn assemble(farm: &Arc<Farm>, id: &JobId) {
    let _span = tracing::info_span!("assemble", job = %id).entered();
    let started = Instant::now();
    let Some(record) = farm.jobs_record(id) else { return };
    // A panic here is a defect, but it must not leave the job assembling for ever, with every
    // client watching it waiting: the job fails with the panic's words (the panic hook has
    // written where it happened to the log).
    let assembled = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| files(farm, &record)))
        .unwrap_or_else(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(Outcome::Failed(format!(
                "assembling the image stopped on an internal error ({what}); this is a defect \
                 of restauro: please report it with the coordinator's log"
            )))
        });
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

enum Outcome {
    /// The job ended (cancelled) during assembly.
    Ended(FarmError),
    /// Assembly itself failed: the job fails with this reason.
    Failed(String),
}

fn files(farm: &Arc<Farm>, record: &JobRecord) -> Result<Vec<String>, Outcome> {
    let id = &record.id;
    let plan = &record.plan;
    let mut frame = Framebuffer::new(plan.width, plan.height, TileLayout::from(plan));
    for (index, rect) in plan.tiles().enumerate() {
        let data = farm
            .store
            .tile(id, index as u32)
            .map_err(|e| Outcome::Failed(e.to_string()))?
            .ok_or_else(|| {
            // A job cancelled meanwhile has had its tiles dropped: that is not a failure.
            match farm.transition(id, |_| Ok(())) {
                Ok((_, r)) if r.state().is_final() => {
                    Outcome::Ended(FarmError::from(IllegalTransition {
                        job: id.clone(),
                        from: r.state(),
                        to: JobState::PostProcessing,
                    }))
                }
                _ => Outcome::Failed(format!("tile {index} is missing from the store")),
            }
        })?;
        frame.place(index as u32, &rect, &data).map_err(|e| Outcome::Failed(e.to_string()))?;
    }
    farm.transition(id, JobRecord::begin_post_processing).map_err(Outcome::Ended)?;
    let dir = farm.results_dir(id);
    std::fs::create_dir_all(&dir)
        .map_err(|e| Outcome::Failed(format!("{}: {e}", dir.display())))?;
    let stem = record.spec.name.file_stem();
    let info = record.info();
    if plan.grids {
        let written = write_grid_results(&dir, frame, &stem, &info)
            .map_err(|e| Outcome::Failed(e.to_string()))?;
        info!("grids written");
        return Ok(written.files);
    }
    let retinex = farm.config.retinex.then(|| RetinexParams {
        paths: record.spec.retinex.paths,
        seed: record.spec.retinex.seed,
        ..RetinexParams::default()
    });
    let options =
        ResultOptions { name: &stem, info: &info, exposure: record.spec.exposure, retinex };
    let written =
        write_results(&dir, frame, &options).map_err(|e| Outcome::Failed(e.to_string()))?;
    info!(retinex_s = written.retinex_s, "results written");
    if farm.config.retinex {
        farm.metrics.retinex_seconds.observe(written.retinex_s);
    }
    Ok(written.files)
}

fn remove_results(farm: &Farm, id: &JobId) {
    let dir = farm.results_dir(id);
    if dir.exists()
        && let Err(e) = std::fs::remove_dir_all(&dir)
    {
        warn!(dir = %dir.display(), "could not remove the job's files: {e}");
    }
}
