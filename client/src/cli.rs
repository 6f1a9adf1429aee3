//! The command-line interface: argument definitions only. Each subcommand's work is a library
//! function the tests call directly.

use clap::{Args, Parser, Subcommand, ValueEnum};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Observer;
use restauro_spectral::adaptation::ConeSpace;
use std::num::NonZeroU32;
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "restauro",
    version,
    about = "How an ancient building looks to a person standing in front of it: \
spectral rendering from measured stone reflectances and photometric light sources."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// How long commands show their progress on standard error: auto (a bar on a terminal,
    /// plain lines every 10 s otherwise: a log file, nohup, CI), bar, plain or none.
    #[arg(long, global = true, value_enum, default_value_t = restauro_cluster::progress::ProgressMode::Auto)]
    pub progress: restauro_cluster::progress::ProgressMode,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// The colour of a measured material under a light: XYZ, xy, L*a*b*, RGB and hex, and with
    /// --compare the CIEDE2000 difference between two materials.
    Color(ColorArgs),
    /// Render the demo on an embedded local cluster: the Aosta facade as found and cleaned under
    /// a summer sun, an overcast sky and the CIE clear sky, the paper's stone experiment
    /// (Fig. 12) under CIE A, B, C and D65, each with and without Retinex, a CIEDE2000 map, the
    /// facade floodlit at night with the illuminance over one bay, contact sheets and a report.
    Demo(DemoArgs),
    /// Render a scene through a cluster — an embedded local one (a coordinator and two workers
    /// on loopback) unless --coordinator is given: absolute XYZ (and spectral radiance) to
    /// OpenEXR and a PNG, each also after the Retinex.
    Render(RenderArgs),
    /// Render a sequence of one scene through a cluster: the day at the scene's site from one
    /// hour to another (--sun-from 06:00 --to 21:00 --every 15m), one hour on several dates
    /// (--dates … --at 12:00), a walk through saved views (--path VIEW,VIEW,… --fps 25) or the
    /// hypotheses (--variants as-found,cleaned). One job on the farm; each frame's EXRs and PNGs,
    /// each frame bit-identical to the same scene rendered alone.
    Sequence(SequenceArgs),
    /// The illuminance (lux) at a scene's calculation grids, direct and indirect, computed
    /// spectrally through a cluster (or in-process): a CSV and a false-colour PNG per grid, and
    /// a JSON document with each grid's minimum, mean, maximum and uniformity.
    Illuminance(IlluminanceArgs),
    /// Submit a scene to a coordinator and print the job id.
    Submit(SubmitArgs),
    /// Follow a job with a progress bar until it ends.
    Watch(JobArgs),
    /// Download a finished job's result files.
    Fetch(FetchArgs),
    /// Cancel a job.
    Cancel(JobArgs),
    /// List the coordinator's jobs.
    Jobs(ConnectArgs),
    /// List the workers connected to the coordinator.
    Workers(ConnectArgs),
    /// Run a coordinator (as `restauro-coordinator` does).
    Coordinator(restauro_coordinator::server::CoordinatorArgs),
    /// Run a worker (as `restauro-worker` does).
    Worker(restauro_worker::process::WorkerArgs),
    /// What a person standing there sees: the Marini–Rizzi Retinex of an XYZ or RGB OpenEXR
    /// image, written as a PNG (and optionally an EXR).
    Retinex(RetinexArgs),
    /// Show an XYZ or RGB OpenEXR image on a display: exposure, gamut mapping, encoding to PNG.
    Display(DisplayArgs),
    /// How two images differ as a person judges colour: a CIEDE2000 map with its scale and
    /// statistics, side-by-side and split images, and a JSON summary.
    Compare(CompareArgs),
    /// The studio, the restorer's web page: starts an embedded local cluster whose coordinator
    /// serves it, prints its address, and runs until interrupted (Ctrl-C).
    Studio(StudioArgs),
    /// Scenes: generate the Aosta theatre, check a scene, bundle it.
    #[command(subcommand)]
    Scene(SceneCommand),
    /// Measure speed and print it as JSON.
    Bench(restauro_bench::BenchArgs),
}

#[derive(Debug, Subcommand)]
pub enum SceneCommand {
    /// Write the south facade of the Roman theatre of Aosta as a complete, renderable scene.
    Aosta {
        /// The folder to write `aosta.toml`, `aosta-overcast.toml` and `meshes/facade.obj` into.
        #[arg(long, default_value = "out/aosta")]
        out: PathBuf,
        /// The camera's image width, in pixels.
        #[arg(long, default_value_t = 1280)]
        width: u32,
        /// The camera's image height, in pixels.
        #[arg(long, default_value_t = 720)]
        height: u32,
        /// The seed of the block pattern.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Write a starter scene for your own model: its parts bound to a placeholder stone, a
    /// camera framing it, the sun of the site and a sky; it renders at once.
    New(SceneNewArgs),
    /// Validate a scene file and everything it refers to, and summarise it.
    Check {
        /// The scene file (`.toml`), or a bundle archive (`.tar`), to check.
        scene: PathBuf,
        #[command(flatten)]
        limits: LimitArgs,
    },
    /// Bundle a scene with its files by content hash, and print the bundle's identity; with
    /// --out, write it as one archive to share.
    Bundle {
        /// The scene file (`.toml`) to bundle.
        scene: PathBuf,
        /// Write the bundle as one file (a .tar holding the scene, every file it names and its
        /// identity), which `scene check`, `render` and `submit` take in place of the scene.
        #[arg(long)]
        out: Option<PathBuf>,
        #[command(flatten)]
        limits: LimitArgs,
    },
}

pub use restauro_scene::limits::LimitArgs;

#[derive(Debug, Args)]
pub struct SceneNewArgs {
    /// Your model: .obj, .gltf (with its .bin), .glb, .ply or .wrl.
    #[arg(long)]
    pub mesh: PathBuf,
    /// The site, `LAT,LON` in degrees (north and east positive), for the sun of a summer
    /// afternoon there; without it the sun is set by direction.
    #[arg(long)]
    pub site: Option<String>,
    /// The scene's folder (default: the model's own); the model is copied into its `meshes/`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write over a scene file of the same name.
    #[arg(long)]
    pub force: bool,
}

#[derive(Clone, Debug, Args)]
pub struct RenderArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// The folder for the results.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// The restoration hypothesis (a variant of the scene).
    #[arg(long)]
    pub variant: Option<String>,
    /// Render each of these variants (comma-separated, e.g. as-found,cleaned) and compare the
    /// first with each other one: a ΔE00 map, side-by-side and split images and a JSON summary,
    /// as rendered and as seen, in `<out>/compare-<first>-vs-<other>/`.
    #[arg(long, value_delimiter = ',', conflicts_with = "variant")]
    pub variants: Vec<String>,
    /// Override the scene's integrator.
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// Override the scene's samples per pixel (with --noise, the most a pixel takes).
    #[arg(long, value_parser = option_count)]
    pub spp: Option<NonZeroU32>,
    /// Adaptive sampling: each pixel stops once the standard error of its mean is below this
    /// fraction of its luminance (0.02: 2 %), --spp being the cap; 0 takes every sample.
    /// Default: the scene's render.noise_target.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    pub noise: Option<f32>,
    /// Override the image width (pixels).
    #[arg(long, value_parser = option_count)]
    pub width: Option<NonZeroU32>,
    /// Override the image height (pixels).
    #[arg(long, value_parser = option_count)]
    pub height: Option<NonZeroU32>,
    /// Also write the 81-band spectral radiance into the EXR.
    #[arg(long)]
    pub spectral: bool,
    /// Tile edge in pixels (by default chosen so every worker gets several tiles).
    #[arg(long, value_parser = option_count)]
    pub tile: Option<NonZeroU32>,
    /// The PNG's exposure: auto[:KEY], absolute:<cd/m²> or relative.
    #[arg(long, default_value = "auto")]
    pub exposure: String,
    /// Retinex path samples per pixel (1–4096).
    #[arg(long, default_value_t = restauro_scene::job::RetinexOptions::default().paths)]
    pub retinex_paths: u32,
    /// The Retinex's random seed.
    #[arg(long, default_value_t = 0)]
    pub retinex_seed: u64,
    #[command(flatten)]
    pub run: RunArgs,
    /// Compute the scene's calculation grids instead of its image (`restauro illuminance`).
    #[arg(skip)]
    pub grids: bool,
}

#[derive(Clone, Debug, Args)]
pub struct SequenceArgs {
    /// The scene, where it runs and how each frame renders, as `render` takes them (--variants
    /// makes a sequence of the hypotheses).
    #[command(flatten)]
    pub render: RenderArgs,
    #[command(flatten)]
    pub sun: SunTimeArgs,
    /// A walk through these saved views of the scene, in order (at least two).
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["sun_from", "dates"])]
    pub path: Vec<String>,
    /// Frames a second of the walk.
    #[arg(long, default_value_t = 25.0)]
    pub fps: f64,
    /// The walking speed, m/s.
    #[arg(long, default_value_t = restauro_scene::sequence::WALKING_SPEED_M_S)]
    pub speed: f64,
    /// Frames a second of the video of a day, dates or hypotheses (a walk's video plays at
    /// --fps).
    #[arg(long, default_value_t = 2.0, value_parser = video_rate)]
    pub video_fps: f64,
}

/// A video's frame rate: above 0, at most 240.
fn video_rate(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(fps) if fps > 0.0 && fps <= 240.0 => Ok(fps),
        _ => Err(format!("`{text}`: give frames a second between 0 and 240, e.g. 2")),
    }
}

/// A clock time as HH:MM (or HH:MM:SS).
fn clock_time(text: &str) -> Result<chrono::NaiveTime, String> {
    chrono::NaiveTime::parse_from_str(text, "%H:%M")
        .or_else(|_| chrono::NaiveTime::parse_from_str(text, "%H:%M:%S"))
        .map_err(|_| format!("`{text}` is not a clock time; write it as HH:MM, e.g. 06:00"))
}

/// A sequence of the sun's times: a day, or one hour on several dates.
#[derive(Clone, Debug, Default, Args)]
pub struct SunTimeArgs {
    /// The day's first frame: a clock time at the scene's site (HH:MM, in the UTC offset of the
    /// scene's own date-time), with --to and --every.
    #[arg(long, value_name = "HH:MM", value_parser = clock_time, requires_all = ["to", "every"])]
    pub sun_from: Option<chrono::NaiveTime>,
    /// The day's last frame at most (HH:MM).
    #[arg(long, value_name = "HH:MM", value_parser = clock_time, requires = "sun_from")]
    pub to: Option<chrono::NaiveTime>,
    /// The step between frames of the day: 15m, 1h, 90s, 1h30m.
    #[arg(long, value_parser = restauro_scene::sequence::parse_every, requires = "sun_from")]
    pub every: Option<restauro_scene::sequence::Every>,
    /// The day (YYYY-MM-DD); the scene's own date unless given.
    #[arg(long, requires = "sun_from")]
    pub date: Option<chrono::NaiveDate>,
    /// The same hour (--at) on each of these dates: 2026-03-20,2026-06-21,2026-12-21.
    #[arg(long, value_delimiter = ',', requires = "at", conflicts_with = "sun_from")]
    pub dates: Vec<chrono::NaiveDate>,
    /// The hour of --dates (HH:MM).
    #[arg(long, value_name = "HH:MM", value_parser = clock_time, requires = "dates")]
    pub at: Option<chrono::NaiveTime>,
}

impl SunTimeArgs {
    /// The sequence these flags ask for, if any.
    pub fn sequence(&self) -> Option<restauro_scene::sequence::Sequence> {
        use restauro_scene::sequence::Sequence;
        if let (Some(from), Some(to), Some(every)) = (self.sun_from, self.to, self.every) {
            return Some(Sequence::Day { date: self.date, from, to, every });
        }
        let at = self.at?;
        Some(Sequence::Dates { dates: self.dates.clone(), at })
    }
}

#[derive(Clone, Debug, Args)]
pub struct IlluminanceArgs {
    /// The scene file, with its calculation grids (`[[grids]]`).
    pub scene: PathBuf,
    /// The folder for the results: the grids' EXR, a CSV and a false-colour PNG per grid, and
    /// illuminance.json.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// The restoration hypothesis (a variant of the scene): its reflectances change the
    /// indirect light.
    #[arg(long)]
    pub variant: Option<String>,
    /// Override the scene's integrator: whitted computes the direct light only, path the
    /// inter-reflected light too.
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// Samples per point (by default the scene's samples per pixel).
    #[arg(long, value_parser = option_count)]
    pub spp: Option<NonZeroU32>,
    /// Print the JSON document (schema restauro.illuminance/1) instead of a summary.
    #[arg(long, conflicts_with_all = ["sun_from", "dates"])]
    pub json: bool,
    /// Through a day or on several dates: each point's illuminance at each time, as a CSV and
    /// a chart per grid.
    #[command(flatten)]
    pub sun: SunTimeArgs,
    #[command(flatten)]
    pub run: RunArgs,
}

/// Where a render or a grid computation runs: an embedded local cluster (the default), the
/// coordinator named, or this process; and the limits the scene is checked against.
#[derive(Clone, Debug, Args)]
pub struct RunArgs {
    /// Compute in this process, without a cluster.
    #[arg(long, conflicts_with = "coordinator")]
    pub in_process: bool,
    /// Workers of the embedded local cluster.
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Keep the embedded cluster's logs (RUST_LOG filters them) in this folder.
    #[arg(long, conflicts_with = "coordinator")]
    pub cluster_logs: Option<PathBuf>,
    #[command(flatten)]
    pub connect: OptionalConnectArgs,
    #[command(flatten)]
    pub limits: LimitArgs,
}

/// Where the coordinator is and the client token; without a coordinator, `render` starts an
/// embedded one.
#[derive(Clone, Debug, Args)]
pub struct OptionalConnectArgs {
    /// The coordinator's URL, or several separated by commas (coordinators taking turns to
    /// lead on one PostgreSQL store: calls go to the one leading) (else RESTAURO_COORDINATOR; else an embedded local cluster).
    #[arg(long, env = "RESTAURO_COORDINATOR")]
    pub coordinator: Option<String>,
    /// A file holding the client token (else RESTAURO_TOKEN).
    #[arg(long)]
    pub token_file: Option<PathBuf>,
    /// For an https:// coordinator: a PEM file of the certificate authority to trust besides
    /// the system's (else RESTAURO_TLS_CA).
    #[arg(long, env = "RESTAURO_TLS_CA")]
    pub tls_ca: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct ConnectArgs {
    /// The coordinator's URL, or several separated by commas (coordinators taking turns to
    /// lead on one PostgreSQL store: calls go to the one leading) (else RESTAURO_COORDINATOR).
    #[arg(long, env = "RESTAURO_COORDINATOR")]
    pub coordinator: String,
    /// A file holding the client token (else RESTAURO_TOKEN).
    #[arg(long)]
    pub token_file: Option<PathBuf>,
    /// For an https:// coordinator: a PEM file of the certificate authority to trust besides
    /// the system's (else RESTAURO_TLS_CA).
    #[arg(long, env = "RESTAURO_TLS_CA")]
    pub tls_ca: Option<PathBuf>,
    /// Speak another protocol version (for testing the coordinator's refusal).
    #[arg(long, hide = true, default_value_t = restauro_proto::PROTOCOL_VERSION)]
    pub protocol_version: u32,
}

#[derive(Debug, Args)]
pub struct SubmitArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    /// Higher priorities are served first.
    #[arg(long, default_value_t = 0)]
    pub priority: i32,
    /// Wait for the job, with a progress bar, and fetch its results into --out.
    #[arg(long)]
    pub wait: bool,
}

#[derive(Debug, Args)]
pub struct JobArgs {
    /// The job id (printed by `submit`).
    pub job: String,
    #[command(flatten)]
    pub connect: ConnectArgs,
}

#[derive(Debug, Args)]
pub struct FetchArgs {
    /// The job id (printed by `submit`).
    pub job: String,
    /// The folder for the files.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub connect: ConnectArgs,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The reference image: an OpenEXR file (XYZ or RGB, linear).
    pub a: PathBuf,
    /// The image compared with it, of the same size.
    pub b: PathBuf,
    /// The folder for delta-e.png, side-by-side.png, split.png and compare.json.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// The reference white of CIELAB (and the exposure of the pictures): auto (the display's
    /// for A), absolute:<cd/m²> (for a render: E_h/π of a white horizontal surface), or
    /// relative (Y = 1: images after the Retinex).
    #[arg(long, default_value = "auto")]
    pub white: String,
    /// The ΔE00 above which a pixel counts as changed (about 2 is just noticeable side by side).
    #[arg(long, default_value_t = 2.0)]
    pub threshold: f64,
}

#[derive(Debug, Args)]
pub struct RetinexArgs {
    /// The input: an OpenEXR file with X, Y, Z or R, G, B channels (linear).
    pub input: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// What the eye adapts to: light (the light the renderer measured at each surface, from
    /// the file's white.X/Y/Z/scotopic channels, which restauro's renders write; colour by
    /// CAT16 towards it with CAM16's degree of adaptation and a blue bias, lightness by the
    /// paths from the known white), retinex (the paths alone, channel by channel in --space:
    /// each channel's white is the brightest area they find, as the paper and restauro before
    /// it), or auto (default: light when the file has the channels, retinex otherwise).
    #[arg(long, default_value = "auto", value_parser = ["auto", "light", "retinex"])]
    pub adaptation: String,
    /// With the light: do not model mesopic vision (the colour the rods weaken below 5 cd/m²
    /// of adapting luminance, CIE 191).
    #[arg(long)]
    pub no_mesopic: bool,
    /// N: the least number of path samples per pixel.
    #[arg(long, default_value_t = 20)]
    pub paths: u32,
    /// How far the paths reach, as the RMS distance (in image diagonals) from where a path
    /// starts to where it samples: 3 (the default) adapts to the whole image; below about 0.5
    /// the adaptation is local.
    #[arg(long, default_value_t = restauro_spectral::retinex::DEFAULT_REACH)]
    pub reach: f64,
    /// L: steps per path (default: the length that gives the reach).
    #[arg(long)]
    pub length: Option<u32>,
    /// Log-ratio threshold below which a step is ignored (smooth illumination gradients).
    #[arg(long, default_value_t = 0.01)]
    pub threshold: f32,
    /// The seed of the random paths; the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// With --adaptation retinex, the channels: lms-cat02 (default: the CAT02 cone space,
    /// which predicts Breneman's corresponding colours best of these), lms (= lms-hpe:
    /// Hunt–Pointer–Estévez cones, the paper's l, m, s), lms-cat16, lms-bradford, rgb (linear
    /// sRGB), rgb-p3 or rgb-rec2020.
    #[arg(long, default_value = "lms-cat02")]
    pub space: restauro_spectral::appearance::ChannelSpace,
    /// What may be the white: area (default: a bright area of at least a 2×2 block or most of
    /// a 3×3 window, after averaging the image's own noise, so a firefly, a glint or Monte Carlo
    /// noise is not the white) or paper (the brightest pixel a path crosses, as the paper).
    #[arg(long, default_value = "area")]
    pub white: String,
    /// Light sources in view: pass (default: the pixels the file's `emitter` channel marks — the
    /// sky, a lamp — are passed over by the paths, neither white nor an edge) or keep (they are
    /// surfaces like any other).
    #[arg(long, default_value = "pass")]
    pub light_sources: String,
    /// Frameworks of illumination: lights (default: the pixels the file's `lit_by` channel says
    /// are lit by the same lights — the sunlit stone, the sky-lit shadow — are adapted to their
    /// own light; a file without the channel is one framework) or none (one white for all).
    #[arg(long, default_value = "lights")]
    pub frameworks: String,
    /// The weight (0–1) of a surface's own light in its lightness; the rest is the image's
    /// white. 1: a shadow is as light as the sun; 0: as dark as it is against the sun's white.
    /// Colours are adapted to their own light whatever the weight.
    #[arg(long, default_value_t = restauro_spectral::retinex::DEFAULT_FRAMEWORK_WEIGHT)]
    pub framework_weight: f32,
    /// With the light: the weight (0–1) of the light on a surface's own plane against its
    /// framework's. 1: a wall turned from the light is seen as light as one facing it; 0: as
    /// dark as its light is against the framework's most lit faces.
    #[arg(long, default_value_t = restauro_spectral::seen::DEFAULT_PLANE_WEIGHT)]
    pub plane_weight: f32,
    /// Also write the result as OpenEXR (XYZ relative to a D65 white, Y = 1).
    #[arg(long)]
    pub exr: Option<PathBuf>,
    #[command(flatten)]
    pub display: DisplayTarget,
}

#[derive(Debug, Args)]
pub struct DisplayArgs {
    /// The input: an OpenEXR file with X, Y, Z or R, G, B channels (linear).
    pub input: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// auto[:KEY] (the log-average luminance at KEY of the reference white, 0.18 by default,
    /// the 99th percentile at most at it), absolute:<cd/m²> (that luminance is the reference
    /// white), or relative (Y = 1 is the reference white). The reference white is shown at 0.7
    /// of the display's white; brighter luminances are compressed, not clipped.
    #[arg(long, default_value = "auto")]
    pub exposure: String,
    #[command(flatten)]
    pub display: DisplayTarget,
    /// Draw a quantity in false colour instead of the image: `luminance` (cd/m², the Y of the
    /// absolute XYZ), coloured by viridis, with isolines and a legend strip below the image.
    #[arg(long, value_parser = ["luminance"])]
    pub false_colour: Option<String>,
    /// The false colour's scale: log (equal steps are equal ratios) or linear.
    #[arg(long, default_value = "log", requires = "false_colour",
          value_parser = clap::builder::ValueParser::new(|s: &str| s.parse::<restauro_image::false_colour::Scale>()))]
    pub scale: restauro_image::false_colour::Scale,
    /// The luminances at the ends of the scale, MIN:MAX in cd/m² (by default whole decades
    /// around the 1st and 99th percentiles on a log scale, 0 to the 99th percentile rounded up
    /// on a linear one).
    #[arg(long, requires = "false_colour")]
    pub range: Option<String>,
    /// The bands of the scale: an isoline where the luminance crosses each level between them
    /// (1: no isolines).
    #[arg(long, default_value_t = 10, requires = "false_colour",
          value_parser = clap::value_parser!(u32).range(1..=100))]
    pub bands: u32,
}

#[derive(Debug, Args)]
pub struct DisplayTarget {
    /// The display colour space of the PNG: srgb, p3, rec2020 or adobe-rgb.
    #[arg(long = "display", default_value = "srgb")]
    pub display_space: restauro_spectral::rgb_space::RgbSpace,
    /// Bits per channel of the PNG: 8 or 16.
    #[arg(long, default_value_t = 8, value_parser = clap::builder::ValueParser::new(parse_bits))]
    pub bits: u8,
}

#[derive(Debug, Args)]
pub struct ColorArgs {
    /// A reflectance CSV file (`wavelength_nm,reflectance`), or the name (file stem) of a shipped
    /// spectrum; `--list` prints them.
    #[arg(required_unless_present = "list")]
    pub spectrum: Option<String>,

    /// The light: A, B, C, D50, D55, D65, D75, E, F1–F12, daylight:<CCT K>, blackbody:<T K>, or a
    /// CSV file of relative spectral power.
    #[arg(long, short = 'i', default_value = "D65")]
    pub illuminant: String,

    /// The CIE standard observer: 2 (CIE 1931) or 10 (CIE 1964).
    #[arg(long, value_enum, default_value = "2")]
    pub observer: ObserverArg,

    /// The display colour space for the RGB values: srgb, p3, rec2020 or adobe-rgb.
    #[arg(long, default_value = "srgb")]
    pub space: restauro_spectral::rgb_space::RgbSpace,

    /// How the colour seen under the light is carried to the display's D65 white for RGB:
    /// bradford, cat02, von-kries, or none (show the light's colour cast as a camera balanced
    /// for D65 would).
    #[arg(long, value_enum, default_value = "bradford")]
    pub adapt: AdaptArg,

    /// A second material: print its colour too and the CIEDE2000 difference between the two.
    #[arg(long)]
    pub compare: Option<String>,

    /// Hold the end values of a file that stops short of 380 or 780 nm constant, instead of
    /// refusing it (the extrapolation is reported). Shipped spectra always do this.
    #[arg(long)]
    pub extrapolate: bool,

    /// Print JSON (schema `restauro.color/1`, documented in docs/color-json.md).
    #[arg(long)]
    pub json: bool,

    /// List the shipped spectra and exit.
    #[arg(long)]
    pub list: bool,
}

#[derive(Debug, Args)]
pub struct StudioArgs {
    /// A scene to open (a scene file or a `scene bundle` archive): it is sent to the cluster
    /// with a first, quick preview render (160×90, 1 sample per pixel), so that the studio
    /// holds it and the page opens it.
    pub scene: Option<PathBuf>,
    /// Where the studio listens; port 0 picks a free port. Another machine can reach it only if
    /// this is not a loopback address (and then anyone who can reach it sees the sign-in page).
    #[arg(long, default_value = "127.0.0.1:7880")]
    pub listen: std::net::SocketAddr,
    /// Workers in the embedded cluster (they share this machine's cores).
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Write the cluster's logs (coordinator.log, worker-N.log) into this folder.
    #[arg(long)]
    pub cluster_logs: Option<PathBuf>,
    /// Stop when standard input closes (for tests that start the studio).
    #[arg(long, hide = true)]
    pub exit_with_stdin: bool,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Where to write the results.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Small images and few samples: the whole demo in well under a minute.
    #[arg(long)]
    pub quick: bool,
    /// Workers in the embedded cluster (they share this machine's cores).
    #[arg(long, default_value_t = 2)]
    pub workers: usize,
    /// Write the cluster's logs (coordinator.log, worker-N.log) into this folder.
    #[arg(long)]
    pub cluster_logs: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObserverArg {
    /// CIE 1931 2°.
    #[value(name = "2")]
    Two,
    /// CIE 1964 10°.
    #[value(name = "10")]
    Ten,
}

impl From<ObserverArg> for Observer {
    fn from(o: ObserverArg) -> Observer {
        match o {
            ObserverArg::Two => Observer::Cie1931TwoDegree,
            ObserverArg::Ten => Observer::Cie1964TenDegree,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AdaptArg {
    Bradford,
    Cat02,
    VonKries,
    None,
}

impl AdaptArg {
    /// The chromatic adaptation transform, or `None` for no adaptation.
    pub fn cone_space(self) -> Option<ConeSpace> {
        match self {
            AdaptArg::Bradford => Some(ConeSpace::Bradford),
            AdaptArg::Cat02 => Some(ConeSpace::Cat02),
            AdaptArg::VonKries => Some(ConeSpace::VonKries),
            AdaptArg::None => None,
        }
    }
}

/// A count a render option gives (`--spp`, `--width`, `--height`, `--tile`), checked here where
/// it enters: a zero is refused as the wire and the studio refuse it.
fn option_count(s: &str) -> Result<NonZeroU32, String> {
    let value: u32 = s.parse().map_err(|e| format!("`{s}`: {e}"))?;
    restauro_scene::job::option_count("", value).map_err(|e| e.problem)
}

fn parse_bits(s: &str) -> Result<u8, String> {
    match s {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("`{s}` bits per channel: use 8 or 16")),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_command_line_is_consistent() {
        use clap::CommandFactory;
        super::Cli::command().debug_assert();
    }

    /// `--help` explains every argument of every subcommand (hidden ones aside).
    #[test]
    fn every_argument_has_help() {
        use clap::CommandFactory;
        fn walk(command: &clap::Command, path: &str, missing: &mut Vec<String>) {
            for arg in command.get_arguments() {
                let id = arg.get_id().as_str();
                if arg.is_hide_set() || id == "help" || id == "version" {
                    continue;
                }
                if arg.get_help().is_none() && arg.get_long_help().is_none() {
                    missing.push(format!("{path} {id}"));
                }
            }
            for sub in command.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()), missing);
            }
        }
        let mut missing = Vec::new();
        walk(&super::Cli::command(), "restauro", &mut missing);
        assert!(missing.is_empty(), "arguments without help: {missing:#?}");
    }
}
