//! A finished calculation of grids read as illuminance, on demand: the job's scene is loaded
//! again (its grids, placed as the render placed them) and its grids' EXR read with
//! `restauro_image::illuminance`, the code `restauro illuminance` reads one with, so the
//! figures are the command line's by construction. The documents are written once, into the
//! job's results folder under [`FOLDER`], and read from there afterwards.

use super::Farm;
use crate::error::{FarmError, Result};
use crate::ids::JobId;
use restauro_image::illuminance::{DOCUMENT, Document, SCHEMA, grid_results, write_documents};
use restauro_image::image_files::{MAX_PIXELS, read_exr};
use std::path::PathBuf;
use std::sync::Arc;

/// The folder of a job's results where its illuminance documents are written.
pub const FOLDER: &str = "illuminance";

impl Farm {
    /// The illuminance document of job `id`, a finished calculation of grids (written on the
    /// first call).
    pub async fn illuminance(self: &Arc<Self>, id: &JobId) -> Result<Document> {
        let record = self.jobs_record(id).ok_or_else(|| FarmError::NoSuchJob(id.clone()))?;
        if !record.plan.grids {
            return Err(FarmError::Request(format!(
                "job {id} rendered a picture, not the scene's grids; compute the grids first"
            )));
        }
        let exr = self.result_path(id, &format!("{}.exr", record.spec.name.file_stem()))?;
        let dir = self.results_dir(id).join(FOLDER);
        let json = dir.join(DOCUMENT);
        if let Ok(text) = std::fs::read_to_string(&json)
            && let Ok(document) = serde_json::from_str(&text)
        {
            return Ok(document);
        }
        let farm = self.clone();
        self.loading_scene(move || -> Result<Document> {
            let scene = farm.bundle(&record.manifest_json)?.load(&farm.config.limits)?;
            let image = read_exr(&exr, MAX_PIXELS)?;
            let document = Document {
                schema: SCHEMA.into(),
                scene: record.spec.name.to_string(),
                variant: record.plan.variant.clone(),
                grids: grid_results(&scene, &image, &exr)?,
            };
            let text = serde_json::to_string_pretty(&document).map_err(|e| {
                FarmError::Internal(format!("the document does not serialise: {e}"))
            })? + "\n";
            write_documents(&dir, &document, &text)?;
            Ok(document)
        })
        .await
    }

    /// A file of job `id`'s illuminance documents: `<grid>.png`, `<grid>.csv` or the document,
    /// once [`Farm::illuminance`] has written them.
    pub async fn illuminance_file(self: &Arc<Self>, id: &JobId, name: &str) -> Result<PathBuf> {
        let document = self.illuminance(id).await?;
        let known = name == DOCUMENT
            || document.grids.iter().any(|g| {
                name.strip_suffix(".png").or_else(|| name.strip_suffix(".csv")) == Some(&g.name)
            });
        if !known {
            return Err(FarmError::NoSuchResult {
                job: id.clone(),
                name: format!("{FOLDER}/{name}"),
            });
        }
        Ok(self.results_dir(id).join(FOLDER).join(name))
    }
}
