//! A job's durable record: what was asked (the scene's manifest and the render options), what
//! was planned (image size and tiles), and where it stands. The coordinator's state machine:
//!
//! ```text
//! queued → running → assembling → post-processing → done
//!    ↘        ↘           ↘              ↘
//!              failed (a tile failed on several workers; an output could not be written)
//!              cancelled (by a client)
//! ```

use restauro_proto as pb;
use restauro_scene::plan::{Rect, RenderOptions, tile_count, tile_rect, tiles};
use restauro_scene::scene_file::Integrator;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum State {
    Queued,
    Running,
    Assembling,
    PostProcessing,
    Done,
    Failed,
    Cancelled,
}

impl State {
    pub fn is_final(self) -> bool {
        matches!(self, State::Done | State::Failed | State::Cancelled)
    }

    pub fn to_proto(self) -> pb::JobState {
        match self {
            State::Queued => pb::JobState::Queued,
            State::Running => pb::JobState::Running,
            State::Assembling => pb::JobState::Assembling,
            State::PostProcessing => pb::JobState::PostProcessing,
            State::Done => pb::JobState::Done,
            State::Failed => pb::JobState::Failed,
            State::Cancelled => pb::JobState::Cancelled,
        }
    }
}

/// The render options as the job keeps them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Options {
    pub variant: Option<String>,
    pub integrator: Option<String>,
    pub samples_per_pixel: Option<u32>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spectral: bool,
    pub tile: Option<u32>,
    pub exposure: String,
    pub retinex_paths: u32,
    pub retinex_seed: u64,
}

fn nonzero(v: u32) -> Option<u32> {
    (v != 0).then_some(v)
}

fn nonempty(s: &str) -> Option<String> {
    (!s.is_empty()).then(|| s.to_owned())
}

impl Options {
    pub fn from_proto(o: &pb::RenderOptions) -> Self {
        Self {
            variant: nonempty(&o.variant),
            integrator: nonempty(&o.integrator),
            samples_per_pixel: nonzero(o.samples_per_pixel),
            width: nonzero(o.width),
            height: nonzero(o.height),
            spectral: o.spectral,
            tile: nonzero(o.tile),
            exposure: o.exposure.clone(),
            retinex_paths: o.retinex_paths,
            retinex_seed: o.retinex_seed,
        }
    }

    pub fn to_proto(&self) -> pb::RenderOptions {
        pb::RenderOptions {
            variant: self.variant.clone().unwrap_or_default(),
            integrator: self.integrator.clone().unwrap_or_default(),
            samples_per_pixel: self.samples_per_pixel.unwrap_or(0),
            width: self.width.unwrap_or(0),
            height: self.height.unwrap_or(0),
            spectral: self.spectral,
            tile: self.tile.unwrap_or(0),
            exposure: self.exposure.clone(),
            retinex_paths: self.retinex_paths,
            retinex_seed: self.retinex_seed,
        }
    }

    /// The scene-level options, refusing an unknown integrator.
    pub fn render_options(&self) -> Result<RenderOptions, String> {
        let integrator = match self.integrator.as_deref() {
            None => None,
            Some("whitted") => Some(Integrator::Whitted),
            Some("path") => Some(Integrator::Path),
            Some(other) => {
                return Err(format!("integrator `{other}`: use `whitted` or `path`"));
            }
        };
        Ok(RenderOptions {
            variant: self.variant.clone(),
            integrator,
            samples_per_pixel: self.samples_per_pixel,
            width: self.width,
            height: self.height,
            spectral: self.spectral,
            tile: self.tile,
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    pub id: String,
    pub name: String,
    pub priority: i32,
    pub manifest_json: String,
    pub options: Options,
    pub state: State,
    pub error: String,
    pub submitted_unix_ms: u64,
    /// The plan: the image size and the tile edge (the tiles follow from them).
    pub width: u32,
    pub height: u32,
    pub tile: u32,
    /// Whether the scene has a sky: its tiles then carry each pixel's sky coverage.
    #[serde(default)]
    pub sky: bool,
    /// What the renders were made with, for the files' headers.
    pub info: String,
    pub results: Vec<String>,
}

impl Record {
    pub fn tiles(&self) -> Vec<Rect> {
        tiles(self.width, self.height, self.tile)
    }

    pub fn tile_count(&self) -> u32 {
        tile_count(self.width, self.height, self.tile)
    }

    /// Tile `index`, without listing them all (leases and reports ask for one at a time).
    pub fn tile(&self, index: u32) -> Option<Rect> {
        tile_rect(self.width, self.height, self.tile, index)
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("a record always serialises")
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, serde_json::Error> {
        serde_json::from_slice(bytes)
    }

    /// The stem of the result files: the job's name, kept to characters safe in a file name.
    pub fn file_stem(&self) -> String {
        let stem: String = self
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
            .collect();
        let stem = stem.trim_start_matches('.');
        if stem.is_empty() { "render".to_owned() } else { stem.to_owned() }
    }
}
