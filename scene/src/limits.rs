//! What a scene and a render may ask of the machine. Every process that loads a scene or plans a
//! render checks the same limits: the client before it uploads, the coordinator when a job is
//! submitted, and the worker with the coordinator's own values (sent with the job), so a job the
//! coordinator accepted is never refused by a worker. Each refusal names the limit and the flag
//! that raises it.
//!
//! | limit | default | flag |
//! |---|---|---|
//! | pixels of an image | 8192 × 8192 | `--max-pixels` |
//! | pixels of an image with spectral layers | 2048 × 2048 | `--max-spectral-pixels` |
//! | tiles of an image | 65 536 | `--max-tiles` |
//! | the smallest tile edge | 8 px | `--min-tile` |
//! | triangles of a scene | 50 000 000 | `--max-triangles` |
//! | samples per pixel | 65 536 | `--max-spp` |
//! | bounces of a path | 64 | `--max-depth` |
//! | a file of the scene | 2048 MiB | `--max-file-mb` |
//! | node instances of one mesh file (VRML97 `USE`, reused glTF nodes) | 20 000 000 | `--max-instances` |
//! | vertices of one polygon | 10 000 | `--max-polygon-vertices` |
//! | frames of a sequence | 4096 | `--max-frames` |
//! | tiles of one job, every frame of a sequence together | 1 048 576 | `--max-job-tiles` |

/// The bounds no flag raises: beyond them a number is a mistake of units, not a bigger scene.
/// The largest coordinate (m, each of x, y and z, after placement) of a vertex, the camera or
/// a light. Survey coordinates run to millions of metres (UTM northings reach 10⁷ m); beyond
/// 10⁹ m a scene is a mistake of units or scale, and the tracer's 32-bit floats (and its BVH
/// builder, which fails on non-finite bounds) are no longer safe.
pub const MAX_COORDINATE_M: f64 = 1e9;
/// The most luminous intensity a luminaire may have (cd): the brightest searchlights reach
/// about 10⁹ cd; more would overflow the 32-bit radiance once multiplied by the spectrum.
pub const MAX_INTENSITY_CD: f64 = 1e9;
/// The most illuminance a sun or sky may give (lux): the sun gives about 1.3 × 10⁵ lx at the
/// top of the atmosphere.
pub const MAX_ILLUMINANCE_LUX: f64 = 1e6;

/// The most classes one degradation map may have (ICOMOS-ISCS names a few dozen forms of
/// decay; a map draws a handful).
pub const MAX_MAP_CLASSES: usize = 32;

/// The limits. `Default` gives the values of the table above.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    pub max_pixels: u64,
    pub max_triangles: u64,
    pub max_samples_per_pixel: u32,
    pub max_depth: u32,
    pub max_file_bytes: u64,
    /// Pixels of an image that keeps its 81 spectral bands (324 bytes a pixel at assembly).
    pub max_spectral_pixels: u64,
    /// Tiles of one image: the scheduler keeps a few dozen bytes per tile.
    pub max_tiles: u32,
    /// The smallest tile edge in pixels (an image narrower than this is one tile wide).
    pub min_tile: u32,
    /// The most node instances one mesh file may expand to, counting every `USE` (VRML97) and
    /// every reuse of a node (glTF): a file of a few hundred bytes whose groups each use the
    /// one before twice stands for 2^40 instances.
    pub max_instances: u64,
    /// The most vertices of one polygon (OBJ, PLY, VRML97 faces): more is a corrupt file, not
    /// a building.
    pub max_polygon_vertices: u64,
    /// The most frames of one sequence.
    pub max_frames: u32,
    /// The most tiles of one job, all its frames together: the scheduler keeps a few dozen
    /// bytes per tile.
    pub max_job_tiles: u32,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            // 67 Mpixel: the absolute XYZ framebuffer alone is 0.8 GB at assembly.
            max_pixels: 8192 * 8192,
            max_triangles: 50_000_000,
            max_samples_per_pixel: 65_536,
            max_depth: 64,
            max_file_bytes: 2 << 30,
            // 4 Mpixel: the spectral planes are 1.4 GB at assembly.
            max_spectral_pixels: 2048 * 2048,
            max_tiles: 65_536,
            min_tile: 8,
            max_instances: 20_000_000,
            max_polygon_vertices: 10_000,
            // A walk of two minutes at 25 frames a second; a day at one frame a minute is 900.
            max_frames: 4096,
            // About 40 MB of the scheduler's memory; 4096 frames of 256 tiles.
            max_job_tiles: 1 << 20,
        }
    }
}

/// The limits as command-line flags (`restauro` and `restauro-coordinator` flatten the same
/// struct, so a flag a message names exists on both).
#[cfg(feature = "cli")]
#[derive(Clone, Debug, clap::Args)]
pub struct LimitArgs {
    /// The most triangles a scene may have.
    #[arg(long, default_value_t = Limits::default().max_triangles)]
    pub max_triangles: u64,
    /// The most pixels an image may have.
    #[arg(long, default_value_t = Limits::default().max_pixels)]
    pub max_pixels: u64,
    /// The most pixels of an image that keeps its spectral layers (--spectral).
    #[arg(long, default_value_t = Limits::default().max_spectral_pixels)]
    pub max_spectral_pixels: u64,
    /// The most tiles an image may be split into.
    #[arg(long, default_value_t = Limits::default().max_tiles)]
    pub max_tiles: u32,
    /// The smallest tile edge, in pixels.
    #[arg(long, default_value_t = Limits::default().min_tile)]
    pub min_tile: u32,
    /// The largest file a scene may refer to, in MiB.
    #[arg(long, default_value_t = Limits::default().max_file_bytes >> 20)]
    pub max_file_mb: u64,
    /// The most samples per pixel.
    #[arg(long, default_value_t = Limits::default().max_samples_per_pixel)]
    pub max_spp: u32,
    /// The most bounces of a path.
    #[arg(long, default_value_t = Limits::default().max_depth)]
    pub max_depth: u32,
    /// The most node instances one mesh file may expand to (VRML97 `USE` copies, glTF nodes
    /// used more than once).
    #[arg(long, default_value_t = Limits::default().max_instances)]
    pub max_instances: u64,
    /// The most vertices of one polygon of a mesh.
    #[arg(long, default_value_t = Limits::default().max_polygon_vertices)]
    pub max_polygon_vertices: u64,
    /// The most frames of one sequence.
    #[arg(long, default_value_t = Limits::default().max_frames)]
    pub max_frames: u32,
    /// The most tiles of one job, all the frames of a sequence together.
    #[arg(long, default_value_t = Limits::default().max_job_tiles)]
    pub max_job_tiles: u32,
}

#[cfg(feature = "cli")]
impl LimitArgs {
    /// The same limits as flags, for a process started with them (the embedded cluster's
    /// coordinator checks a job against the limits its client was given).
    pub fn to_args(&self) -> Vec<String> {
        [
            ("--max-triangles", self.max_triangles.to_string()),
            ("--max-pixels", self.max_pixels.to_string()),
            ("--max-spectral-pixels", self.max_spectral_pixels.to_string()),
            ("--max-tiles", self.max_tiles.to_string()),
            ("--min-tile", self.min_tile.to_string()),
            ("--max-file-mb", self.max_file_mb.to_string()),
            ("--max-spp", self.max_spp.to_string()),
            ("--max-depth", self.max_depth.to_string()),
            ("--max-instances", self.max_instances.to_string()),
            ("--max-polygon-vertices", self.max_polygon_vertices.to_string()),
            ("--max-frames", self.max_frames.to_string()),
            ("--max-job-tiles", self.max_job_tiles.to_string()),
        ]
        .into_iter()
        .flat_map(|(flag, value)| [flag.to_owned(), value])
        .collect()
    }
}

#[cfg(feature = "cli")]
impl From<&LimitArgs> for Limits {
    fn from(a: &LimitArgs) -> Limits {
        Limits {
            max_pixels: a.max_pixels,
            max_triangles: a.max_triangles,
            max_samples_per_pixel: a.max_spp,
            max_depth: a.max_depth,
            max_file_bytes: a.max_file_mb.saturating_mul(1 << 20),
            max_spectral_pixels: a.max_spectral_pixels,
            max_tiles: a.max_tiles,
            min_tile: a.min_tile.max(1),
            max_instances: a.max_instances,
            max_polygon_vertices: a.max_polygon_vertices,
            max_frames: a.max_frames,
            max_job_tiles: a.max_job_tiles,
        }
    }
}
