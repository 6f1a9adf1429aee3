//! The renders read back for the analysis: each as a [`Pair`] of images (as rendered and as
//! seen), sorted by what they show — the facade by light and hypothesis, the sample board by
//! illuminant, the photo block.

use super::Finished;
use crate::error::{DemoError, Result};
use crate::plan::{FacadeLight, Job, Kind};
use restauro_image::image_files::{XyzImage, read_exr};
use std::collections::BTreeMap;

/// The two images of a render: as rendered (absolute XYZ) and as seen (relative).
pub struct Pair {
    pub rendered: XyzImage,
    pub seen: XyzImage,
}

impl Pair {
    /// `<job>.exr` and `<job>-retinex.exr` of a finished render.
    fn read(f: &Finished) -> Result<Pair> {
        let read = |name: String| {
            let path = f.dir.join(&name);
            read_exr(&path, usize::MAX).map_err(|source| DemoError::ReadImage { path, source })
        };
        Ok(Pair {
            rendered: read(format!("{}.exr", f.record.job))?,
            seen: read(format!("{}-retinex.exr", f.record.job))?,
        })
    }
}

/// The renders the sheets show, read.
pub struct Renders<'a> {
    /// By light and hypothesis, with the job (whose scene gives the light's illuminance).
    facade: BTreeMap<(FacadeLight, &'static str), (Pair, &'a Job)>,
    /// By illuminant.
    stones: BTreeMap<&'static str, Pair>,
    pub block: Option<Pair>,
}

impl<'a> Renders<'a> {
    /// Reads every render's pair but the night's and the grid's, in the jobs' order.
    pub fn read(jobs: &'a [Job], finished: &[Finished]) -> Result<Renders<'a>> {
        let mut renders = Renders { facade: BTreeMap::new(), stones: BTreeMap::new(), block: None };
        for (job, f) in jobs.iter().zip(finished) {
            match &job.kind {
                Kind::Block => renders.block = Some(Pair::read(f)?),
                Kind::Facade { light, variant } => {
                    renders.facade.insert((*light, variant), (Pair::read(f)?, job));
                }
                Kind::Samples { illuminant } => {
                    renders.stones.insert(illuminant, Pair::read(f)?);
                }
                Kind::Night | Kind::Grid | Kind::SunStudy { .. } => {}
            }
        }
        Ok(renders)
    }

    /// The facade under `light` as `variant` (`as-found`, `cleaned`), and its job.
    pub fn facade(&self, light: FacadeLight, variant: &'static str) -> Result<&(Pair, &'a Job)> {
        self.facade.get(&(light, variant)).ok_or(DemoError::MissingRender(variant))
    }

    /// The sample board under `illuminant`.
    pub fn stones(&self, illuminant: &'static str) -> Result<&Pair> {
        self.stones.get(illuminant).ok_or(DemoError::MissingRender(illuminant))
    }
}
