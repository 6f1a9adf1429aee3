//! The demo's renders: which scenes it writes, under which lights and hypotheses, at what size
//! and with how many samples. [`write_scenes`] writes the scene folders under `out/scenes/` and
//! returns the [`Job`]s to render; the analysis ([`crate::report`]) finds each render again by
//! its [`Kind`].

use crate::error::{DemoError, Result};
use crate::scene_files::write_aosta;
use crate::scenes::{photo_block, samples};
use restauro_image::atomic_file;
use restauro_scene::limits::Limits;
use restauro_scene::sequence::{Frame, Sequence};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The illuminants of the stone experiment, as the paper uses them.
pub const ILLUMINANTS: [&str; 4] = ["A", "B", "C", "D65"];

/// The noise target of the facade, the night and the block (`restauro_render::adaptive`): a
/// pixel stops once the standard error of its mean is within 10 % of its luminance. At a cap of
/// 32 samples, `restauro bench adaptive` measured the same per-pixel error as 32 samples
/// everywhere (RMS 1 % higher, 95th percentile lower) in about 0.7 of the samples
/// (bench/README.md).
pub const FACADE_NOISE_TARGET: f32 = 0.1;

/// Image sizes and samples.
pub struct Size {
    pub facade: (u32, u32),
    /// The most samples a pixel of the facade, the night and the block takes (their noise
    /// target is [`FACADE_NOISE_TARGET`]).
    pub facade_spp: u32,
    pub samples: (u32, u32),
    pub samples_spp: u32,
    /// Samples a point of the floodlit facade's grid.
    pub grid_spp: u32,
    /// The width of a facade image on its contact sheet.
    pub sheet_cell: u32,
    /// The sun study's frames: their size and most samples a pixel (noise target
    /// [`FACADE_NOISE_TARGET`]).
    pub sun_study: (u32, u32),
    pub sun_study_spp: u32,
}

impl Size {
    /// The sizes of `restauro demo`, or of `restauro demo --quick` (small images, few samples).
    pub fn new(quick: bool) -> Self {
        if quick {
            Self {
                facade: (320, 180),
                facade_spp: 4,
                samples: (300, 200),
                samples_spp: 1,
                grid_spp: 16,
                sheet_cell: 320,
                sun_study: (160, 90),
                sun_study_spp: 2,
            }
        } else {
            Self {
                facade: (1280, 720),
                facade_spp: 32,
                samples: (600, 400),
                samples_spp: 4,
                grid_spp: 256,
                sheet_cell: 560,
                // Shown 192 px wide on its sheet: a bigger frame is time the sheet does not show.
                sun_study: (256, 144),
                sun_study_spp: 4,
            }
        }
    }
}

/// The lights the facade is rendered under.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FacadeLight {
    SummerAfternoon,
    Overcast,
    ClearSky,
}

impl FacadeLight {
    /// Every light, in the order of the sheets' rows.
    pub const ALL: [FacadeLight; 3] =
        [FacadeLight::SummerAfternoon, FacadeLight::Overcast, FacadeLight::ClearSky];

    /// The light's name for people (sheets, report, summary).
    pub fn title(self) -> &'static str {
        match self {
            FacadeLight::SummerAfternoon => "summer afternoon",
            FacadeLight::Overcast => "overcast sky",
            FacadeLight::ClearSky => "CIE clear sky",
        }
    }
}

/// What a render of the demo shows.
#[derive(Clone, Debug)]
pub enum Kind {
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
    /// The facade through the summer day ([`SUN_STUDY_HOURS`]), as `variant`.
    SunStudy {
        variant: &'static str,
    },
}

/// The hours of the sun study: every hour from 08:00 to 19:00 of the summer afternoon's day.
pub const SUN_STUDY_HOURS: (u32, u32) = (8, 19);

impl Kind {
    /// The restoration hypothesis rendered.
    pub fn variant(&self) -> Option<String> {
        match self {
            Kind::Facade { variant, .. } | Kind::SunStudy { variant } => Some(variant.to_string()),
            Kind::Night => Some("cleaned".into()),
            Kind::Block => Some(photo_block::VARIANT.into()),
            Kind::Samples { .. } | Kind::Grid => None,
        }
    }
}

/// One render of the demo.
pub struct Job {
    /// The job's name, and the stem of its files.
    pub key: String,
    pub scene: PathBuf,
    pub kind: Kind,
    /// Samples per pixel: with a noise target, the most a pixel takes.
    pub spp: u32,
    pub noise_target: Option<f32>,
    /// A sequence's frames (none for a still).
    pub frames: Vec<Frame>,
    /// The image's size, when not the scene's.
    pub size: Option<(u32, u32)>,
}

/// Writes the facade scene, the photo block and the four sample scenes under `out/scenes/`;
/// returns the renders to make.
pub fn write_scenes(out: &Path, size: &Size) -> Result<Vec<Job>> {
    let aosta = write_aosta(&out.join("scenes/aosta"), size.facade.0, size.facade.1, 1)
        .map_err(DemoError::AostaScene)?;
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
                noise_target: Some(FACADE_NOISE_TARGET),
                frames: Vec::new(),
                size: None,
            });
        }
    }
    jobs.push(Job {
        key: "facade-night-cleaned".into(),
        scene: aosta.floodlit.clone(),
        kind: Kind::Night,
        spp: size.facade_spp,
        noise_target: Some(FACADE_NOISE_TARGET),
        frames: Vec::new(),
        size: None,
    });
    jobs.push(Job {
        key: "floodlit-grid".into(),
        scene: aosta.floodlit.clone(),
        kind: Kind::Grid,
        spp: size.grid_spp,
        noise_target: None,
        frames: Vec::new(),
        size: None,
    });
    jobs.push(Job {
        key: "block".into(),
        scene: write_photo_block(&out.join("scenes/block"), size)?,
        kind: Kind::Block,
        spp: size.facade_spp,
        noise_target: Some(FACADE_NOISE_TARGET),
        frames: Vec::new(),
        size: None,
    });
    jobs.extend(write_sample_scenes(&out.join("scenes/samples"), size)?);
    let frames = sun_study_frames(&aosta.sunny)?;
    for variant in ["as-found", "cleaned"] {
        jobs.push(Job {
            key: format!("sun-study-{variant}"),
            scene: aosta.sunny.clone(),
            kind: Kind::SunStudy { variant },
            spp: size.sun_study_spp,
            noise_target: Some(FACADE_NOISE_TARGET),
            frames: frames.clone(),
            size: Some(size.sun_study),
        });
    }
    Ok(jobs)
}

/// The frames of the sun study of the summer scene at `scene`: every hour of its day.
fn sun_study_frames(scene: &Path) -> Result<Vec<Frame>> {
    let failed = |e| DemoError::SunStudy { path: scene.to_owned(), source: Box::new(e) };
    let file = restauro_scene::load::read_scene_file(scene, &Limits::default()).map_err(failed)?;
    let hour = |h| chrono::NaiveTime::from_hms_opt(h, 0, 0).expect("an hour of the day");
    let every = restauro_scene::sequence::parse_every("1h").expect("one hour");
    let (from, to) = (hour(SUN_STUDY_HOURS.0), hour(SUN_STUDY_HOURS.1));
    let day = Sequence::Day { date: None, from, to, every };
    day.frames(&file, scene, &Limits::default()).map_err(failed)
}

/// The sample board under each of the [`ILLUMINANTS`], in `dir`; returns their renders.
fn write_sample_scenes(dir: &Path, size: &Size) -> Result<Vec<Job>> {
    let mut jobs = Vec::new();
    for illuminant in ILLUMINANTS {
        let g = samples::generate(illuminant, size.samples.0, size.samples.1, size.samples_spp);
        let scene = dir.join(format!("samples-{illuminant}.toml"));
        for (path, text) in [
            (dir.join("board.obj"), &g.board_obj),
            (dir.join("grey.csv"), &g.grey_csv),
            (dir.join("white.csv"), &g.white_csv),
            (scene.clone(), &g.scene_toml),
        ] {
            write_file(&path, text.as_bytes())?;
        }
        jobs.push(Job {
            key: format!("samples-{illuminant}"),
            scene,
            kind: Kind::Samples { illuminant },
            spp: size.samples_spp,
            noise_target: None,
            frames: Vec::new(),
            size: None,
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
                .map_err(|source| DemoError::CreateFolder { path: parent.to_owned(), source })?;
        }
        write_file(&path, bytes)?;
    }
    Ok(scene)
}

/// Writes one file atomically.
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    atomic_file::write(path, bytes)
        .map_err(|source| DemoError::Write { path: path.to_owned(), source })
}
