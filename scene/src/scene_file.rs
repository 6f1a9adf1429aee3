//! The scene file: TOML, read with serde, unknown fields refused, with a `format` version.
//!
//! World frame: +X east, +Y north, +Z up, metres. Angles in degrees. Every file path is
//! relative to the scene file and must stay inside its folder.
//!
//! ```toml
//! format = 1
//!
//! [camera]
//! position = [0.0, -40.0, 1.7]
//! target = [0.0, 0.0, 8.0]
//! vertical_fov_deg = 45.0
//! width = 1280
//! height = 720
//!
//! [render]
//! integrator = "path"          # or "whitted"
//! samples_per_pixel = 16
//! max_depth = 5
//! seed = 1
//!
//! [spectra]
//! travertine = "travertine_tufa_solid__eco_ward73"   # a shipped spectrum
//! lamp = { file = "spectra/lamp.csv" }               # a CSV file
//! daylight = { illuminant = "D65" }                  # a CIE illuminant
//!
//! [materials.stone]
//! model = "lambert"
//! reflectance = "travertine"
//! degraded = { reflectance = "travertine_soiled" }
//!
//! [[objects]]
//! name = "facade"
//! mesh = "meshes/facade.obj"
//! material = "stone"
//!
//! [[lights]]
//! kind = "sun"
//! preset = "sun"                # 100 000 lux, 50° above the horizon
//! spectrum = "daylight"
//!
//! [[lights]]
//! kind = "sky"
//! preset = "overcast"           # the CIE overcast sky, 10 000 lux on the horizontal
//! spectrum = "daylight"
//!
//! [variants.as-found]
//! state = "degraded"
//! ```

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The scene file format this build reads.
pub const FORMAT: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// The version of this schema; must be [`FORMAT`].
    pub format: u32,
    /// A georeferenced scene's working origin (m), in the coordinates its files and positions
    /// are given in (UTM, say): every position is moved by −origin before it is rendered, so
    /// that millimetres survive 32-bit arithmetic far from zero (see [`crate::origin`]). Not
    /// written when absent.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "vec3::opt_origin"
    )]
    pub origin: Option<[f64; 3]>,
    pub camera: Camera,
    #[serde(default)]
    pub render: Render,
    /// Spectra by name, for materials and lights.
    #[serde(default)]
    pub spectra: BTreeMap<String, SpectrumSource>,
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    #[serde(default)]
    pub objects: Vec<Object>,
    #[serde(default)]
    pub lights: Vec<Light>,
    /// Restoration hypotheses by name.
    #[serde(default)]
    pub variants: BTreeMap<String, Variant>,
    /// Saved poses of the camera, by name (the studio's views). Not written when there are none,
    /// so a scene without views keeps the identity it had before views existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub views: Vec<View>,
    /// Notes pinned to the model (the studio's annotations). Not written when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub annotations: Vec<Annotation>,
    /// Calculation grids: the points whose illuminance `restauro illuminance` computes. Not
    /// written when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grids: Vec<Grid>,
    /// Degradation maps: where on the building each form of decay is, as a restorer records
    /// it. Not written when there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub maps: Vec<DegradationMap>,
    /// The content hash of every file the scene names by URL (`https://…`), by URL: what makes
    /// a render from remote files reproducible (see [`crate::pins`]; restauro-assets fetches them). Bundles name files by
    /// hash and carry none. Not written when there are none.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub pins: BTreeMap<String, Pin>,
    /// Written by bundles: the files that the scene's files name inside themselves (the worlds
    /// VRML97 `Inline`s draw, an OBJ's material library and its photos), by hash, so that a
    /// bundle names every file it carries. A scene you write leaves it out. Not written when
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub included: Vec<String>,
}

/// The content a URL must serve: its SHA-256 (what `sha256sum` prints) or its BLAKE3 (what
/// `b3sum` prints) in hexadecimal, one of the two.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pin {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sha256: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blake3: Option<String>,
}

/// Exposure-driven soiling: a deposit (`spectrum`, soot for black crusts) covering up to
/// `max_fraction` of the surface where neither the open sky nor driving rain reaches it. The
/// tracer estimates, at each point it shades, the share washed,
/// W = min(1, `sky_weight`·v_sky + `rain_weight`·v_rain·cos θ/sin θ_rain), from one
/// cosine-distributed direction (v_sky: 1 if it reaches the sky above the horizon) and one
/// direction into the driving rain (v_rain: 1 if the rain reaches the point from there;
/// θ its angle to the surface's normal); the deposit covers s = `max_fraction`·(1 − W) of the
/// surface, so the state's reflectance is (1 − s)·ρ + s·ρ_deposit, averaged by the pixel's
/// samples. Sheltered zones (under cornices, in recesses) come out dark, faces the rain washes
/// light.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Soiling {
    /// The deposit's reflectance: a name in `[spectra]`.
    pub spectrum: String,
    /// The share of the surface it covers where nothing washes it, 0 to 1.
    pub max_fraction: f64,
    /// Where the driving rain comes from: an azimuth (0° north, 90° east), 225 (south-west)
    /// unless given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rain_azimuth_deg: Option<f64>,
    /// How far from vertical the rain falls, 30 unless given (0 to 80).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rain_angle_deg: Option<f64>,
    /// The weight of the open sky in washing, 0.5 unless given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky_weight: Option<f64>,
    /// The weight of driving rain in washing, 1 unless given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rain_weight: Option<f64>,
}

impl Soiling {
    pub const DEFAULT_RAIN_AZIMUTH_DEG: f64 = 225.0;
    pub const DEFAULT_RAIN_ANGLE_DEG: f64 = 30.0;
    pub const DEFAULT_SKY_WEIGHT: f64 = 0.5;
    pub const DEFAULT_RAIN_WEIGHT: f64 = 1.0;
}

/// A degradation map (ICOMOS-ISCS glossary, UNI 11182): an image of classes, one flat colour
/// per form of decay, laid over a rectangle of the building (an elevation drawing, an
/// orthophoto's mapping) and projected onto the model square to it. A material's state that
/// names the map takes each class's spectrum where that class is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DegradationMap {
    /// Its name, which material states refer to.
    pub name: String,
    /// The image: PNG (lossless, so its class colours stay exact).
    pub image: String,
    /// The rectangle's corner under the image's bottom-left corner (m).
    #[serde(deserialize_with = "vec3::corner")]
    pub corner: [f64; 3],
    /// The image's bottom edge, left to right (m).
    #[serde(deserialize_with = "vec3::u")]
    pub u: [f64; 3],
    /// The image's left edge, bottom to top (m).
    #[serde(deserialize_with = "vec3::v")]
    pub v: [f64; 3],
    /// The forms of decay, each with its colour in the image and its spectrum.
    pub classes: Vec<DegradationClass>,
}

/// One form of decay on a map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DegradationClass {
    /// Its name (`black-crust`, `biological-colonisation`, `efflorescence`, …).
    pub name: String,
    /// Its colour in the image, 8-bit sRGB.
    pub colour: [u8; 3],
    /// The reflectance of the surface where it is: a name in `[spectra]`.
    pub spectrum: String,
}

/// A calculation grid (a lighting designer's calculation surface): virtual sensors that cast
/// no shadow and that the camera does not see. Either a rectangle (`origin`, `u`, `v`,
/// `divisions`: a point at the centre of each cell) or a list of `points`; the illuminance is
/// computed on the side `normal` faces (by default u × v).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Its name, one per grid (it names its output files).
    pub name: String,
    /// One corner of the rectangle (m).
    #[serde(default, deserialize_with = "vec3::opt_origin")]
    pub origin: Option<[f64; 3]>,
    /// One edge of the rectangle, from `origin` (m).
    #[serde(default, deserialize_with = "vec3::opt_u")]
    pub u: Option<[f64; 3]>,
    /// The other edge, from `origin` (m).
    #[serde(default, deserialize_with = "vec3::opt_v")]
    pub v: Option<[f64; 3]>,
    /// The cells along `u` and along `v`.
    #[serde(default)]
    pub divisions: Option<Vec<u32>>,
    /// Instead of a rectangle: the points themselves (m).
    #[serde(default, deserialize_with = "vec3::opt_points")]
    pub points: Option<Vec<[f64; 3]>>,
    /// The direction the sensors face (required with `points`).
    #[serde(default, deserialize_with = "vec3::opt_normal")]
    pub normal: Option<[f64; 3]>,
}

/// A note pinned to a point of the model, or to a part: what a surveyor or a restorer wrote
/// there, with links to the documents about it (survey reports, photographs, charts) and the
/// pose to look at it from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Annotation {
    /// Its name, one per note.
    pub title: String,
    #[serde(default)]
    pub text: String,
    /// Where the pin stands (m).
    #[serde(deserialize_with = "vec3::position")]
    pub position: [f64; 3],
    /// What it is about: an object's `name`, or `object/part`.
    #[serde(default)]
    pub part: Option<String>,
    /// Documents about it: `https://` (or `http://`) addresses.
    #[serde(default)]
    pub links: Vec<String>,
    /// Photographs and charts kept with it: PNG or JPEG files beside the scene file. Not
    /// written when there are none, so a note keeps the identity it had before images existed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub images: Vec<String>,
    /// Where to look at it from.
    #[serde(default)]
    pub pose: Option<Pose>,
}

/// Where an eye stands and where it looks: the one pose of the camera, a saved view, a note's
/// viewpoint and the studio's page (which sends its own, in the preview's coordinates).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// Where the eye is (m).
    #[serde(deserialize_with = "vec3::position")]
    pub position: [f64; 3],
    /// The point looked at (m).
    #[serde(deserialize_with = "vec3::target")]
    pub target: [f64; 3],
    #[serde(default = "default_up", deserialize_with = "vec3::up")]
    pub up: [f64; 3],
    /// The vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub vertical_fov_deg: f64,
}

/// A named pose of the camera: where a restorer stood to look at something. The studio lists
/// these beside the scene's camera and the meshes' viewpoints, and flies to one when chosen; a
/// snapshot taken there renders from that pose.
///
/// Its fields are a [`Pose`]'s written out beside the name, not a nested pose, because the file
/// refuses unknown keys and serde cannot do that through a flattened struct.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct View {
    pub name: String,
    /// Where the eye is (m).
    #[serde(deserialize_with = "vec3::position")]
    pub position: [f64; 3],
    /// The point looked at (m).
    #[serde(deserialize_with = "vec3::target")]
    pub target: [f64; 3],
    #[serde(default = "default_up", deserialize_with = "vec3::up")]
    pub up: [f64; 3],
    /// The vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub vertical_fov_deg: f64,
}

impl View {
    /// The view's pose.
    pub fn pose(&self) -> Pose {
        Pose {
            position: self.position,
            target: self.target,
            up: self.up,
            vertical_fov_deg: self.vertical_fov_deg,
        }
    }

    /// A view named `name` at `pose`.
    pub fn at(name: String, pose: Pose) -> Self {
        let Pose { position, target, up, vertical_fov_deg } = pose;
        Self { name, position, target, up, vertical_fov_deg }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Where the eye is (m). With `viewpoint`, taken from the mesh instead.
    #[serde(default, deserialize_with = "vec3::opt_position")]
    pub position: Option<[f64; 3]>,
    /// The point looked at (m).
    #[serde(default, deserialize_with = "vec3::opt_target")]
    pub target: Option<[f64; 3]>,
    #[serde(default = "default_up", deserialize_with = "vec3::up")]
    pub up: [f64; 3],
    /// The vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub vertical_fov_deg: f64,
    pub width: u32,
    pub height: u32,
    /// Use a camera of an object's mesh (a VRML97 Viewpoint or a glTF perspective camera).
    #[serde(default)]
    pub viewpoint: Option<ViewpointRef>,
}

fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

fn default_fov() -> f64 {
    45.0
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewpointRef {
    /// The object whose mesh (a `.wrl`, `.gltf` or `.glb`) holds the viewpoint.
    pub object: String,
    /// Which viewpoint, in file order (when no `name` is given).
    #[serde(default)]
    pub index: usize,
    /// Which viewpoint, by its name (a VRML `description`, a glTF camera's or node's name).
    #[serde(default)]
    pub name: Option<String>,
}

/// How light is gathered: the scene file's `render.integrator`, a job's option and, with the
/// `cli` feature, the command line's `--integrator` value, one type for all three.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Direct light with shadows plus specular reflection: the paper's method.
    Whitted,
    /// Unidirectional path tracing with next-event estimation.
    Path,
}

impl Integrator {
    /// The word for it in a scene file and on the command line (`whitted`, `path`), as the
    /// files' headers record it.
    pub fn keyword(self) -> &'static str {
        match self {
            Integrator::Whitted => "whitted",
            Integrator::Path => "path",
        }
    }
}

/// What a person reads: "Whitted ray tracing", "path tracing".
impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(match self {
            Integrator::Whitted => "Whitted ray tracing",
            Integrator::Path => "path tracing",
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Render {
    #[serde(default = "default_integrator")]
    pub integrator: Integrator,
    #[serde(default = "default_spp")]
    pub samples_per_pixel: u32,
    /// The most surfaces one path meets; 0: no cap, paths end by Russian roulette alone.
    #[serde(default = "default_depth")]
    pub max_depth: u32,
    #[serde(default)]
    pub seed: u64,
    /// Adaptive sampling: a pixel stops taking samples once the standard error of its mean
    /// (X, Y and Z alike) is below this fraction of its luminance, `samples_per_pixel` being
    /// the cap (see `restauro_render::adaptive`). 0, the default: every pixel takes
    /// `samples_per_pixel`.
    #[serde(default)]
    pub noise_target: f32,
}

/// The largest noise target: a pixel whose standard error is half its value is noise.
pub const MAX_NOISE_TARGET: f32 = 0.5;

/// Checks a noise target (a fraction of a pixel's luminance): finite, 0 (off) or positive, at
/// most [`MAX_NOISE_TARGET`]. The problem, in words that say the fix, when it is not.
pub fn check_noise_target(target: f32) -> std::result::Result<(), String> {
    if target.is_finite() && (0.0..=MAX_NOISE_TARGET).contains(&target) {
        return Ok(());
    }
    Err(format!(
        "{target} is not a noise target; give the standard error a pixel may keep as a fraction \
         of its luminance, from 0.001 (0.1 %) to {MAX_NOISE_TARGET}, or 0 to take every sample"
    ))
}

fn default_integrator() -> Integrator {
    Integrator::Path
}
fn default_spp() -> u32 {
    16
}
fn default_depth() -> u32 {
    5
}

impl Default for Render {
    fn default() -> Self {
        Self {
            integrator: default_integrator(),
            samples_per_pixel: default_spp(),
            max_depth: default_depth(),
            seed: 0,
            noise_target: 0.0,
        }
    }
}

/// Where a spectrum comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum SpectrumSource {
    /// A shipped spectrum by file stem (`restauro color --list`).
    Library(String),
    File {
        file: String,
        /// Hold the end values where the file stops short of 380 or 780 nm (reported).
        #[serde(default)]
        extrapolate: bool,
    },
    Illuminant {
        /// A CIE name: A, B, C, D50 … D75, E, F1–F12, daylight:<K>, blackbody:<K>.
        illuminant: String,
    },
    /// An areal mixture of named spectra, weights summing to 1: e.g. a stone and soot.
    Mix { mix: Vec<MixPart> },
    /// The same value at every wavelength: a reflectance given as a number (0 to 1, as
    /// validation rooms are specified; 0 is a black surface), or an equal-energy light.
    Constant { constant: f64 },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MixPart {
    pub spectrum: String,
    pub weight: f64,
}

/// How a material's photo texture varies its measured reflectance ρₘ(λ) (a photo carries the
/// light it was taken under and an unknown white balance, so it is used relatively).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Detail {
    /// ρ(λ, x) = ρₘ(λ)·Y(x)/Ȳ, at most 1: the photo's lightness only.
    #[default]
    Luminance,
    /// ρ(λ, x) = ρₘ(λ)·S_x(λ)/S̄(λ), at most 1, with S_x and S̄ smooth spectra fitted to the
    /// texel's colour and to the mean colour (Jakob & Hanika 2019): stains keep their hue.
    Chromatic,
    /// No detail: the mesh file's own photo of the part is not used (the surface is uniform).
    None,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialModel {
    Lambert,
    CookTorrance,
    /// Thin clear glazing: Fresnel reflection and transmission at its two faces, absorption
    /// through its thickness (see `thickness_mm`, `transmittance`, `ior`).
    Glass,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub model: MaterialModel,
    /// The spectral hemispherical reflectance ρ(λ), by spectrum name (none for glass).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub reflectance: String,
    /// Glass: the pane's thickness, mm (6 unless given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_mm: Option<f64>,
    /// Glass: its transmittance at normal incidence, one number for clear glass or a spectrum
    /// for tinted glass (0.88 for 6 mm of clear float glass, scaled by absorption to another
    /// thickness, unless given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmittance: Option<Transmittance>,
    /// Cook–Torrance: Beckmann roughness m (rms slope), 0 < m ≤ 1.
    #[serde(default)]
    pub roughness: Option<f64>,
    /// Cook–Torrance: the specular reflectance at normal incidence F0 (0–1), or …
    #[serde(default)]
    pub specular: Option<f64>,
    /// … the index of refraction n, from which F0 = ((n − 1)/(n + 1))².
    #[serde(default)]
    pub ior: Option<f64>,
    /// A photo of the surface (PNG or JPEG), laid on by the mesh's texture coordinates: not a
    /// colour but a relative detail map over `reflectance` (see `detail`). Not written when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<String>,
    /// How `texture` varies the measured reflectance: `luminance` (the default) or `chromatic`.
    /// Not written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detail: Option<Detail>,
    /// Where a grey card (or a ColorChecker's neutral patch) lies in `texture`, or in the
    /// parts' own photos when the material names none: the photo is white-balanced so that the
    /// patch comes out neutral. Not written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub white_patch: Option<PixelRect>,
    /// The surface as found (soiled, weathered).
    #[serde(default)]
    pub degraded: Option<SurfaceOverride>,
    /// The surface after cleaning.
    #[serde(default)]
    pub cleaned: Option<SurfaceOverride>,
}

impl Material {
    /// The surface of the base state: its own fields. Glass names no reflectance, so an empty
    /// one is absent there (and only there: elsewhere the check names the missing spectrum).
    pub fn base_surface(&self) -> Surface<'_> {
        Surface {
            reflectance: Some(self.reflectance.as_str())
                .filter(|r| self.model != MaterialModel::Glass || !r.is_empty()),
            roughness: self.roughness,
            specular: self.specular,
            ior: self.ior,
            texture: self.texture.as_deref(),
            white_patch: self.white_patch,
        }
    }

    /// The surface in `state`: the state's fields over the base ones.
    pub fn surface(&self, state: &str) -> Surface<'_> {
        let base = self.base_surface();
        self.state(state).map_or(base, |o| o.surface().over(base))
    }

    /// The photo texture of `state`: the state's own, or the base one.
    pub fn texture_of(&self, state: &str) -> Option<&str> {
        self.surface(state).texture
    }

    /// Whether a part bound to this material in `state` shows what its mesh file lays on it
    /// (its photo, else its vertex colours): the material gives no texture of its own for the
    /// state and does not say `detail = "none"`.
    pub fn shows_file_detail(&self, state: &str) -> bool {
        self.texture_of(state).is_none() && self.detail != Some(Detail::None)
    }

    /// The grey patch of the photo `state` shows: beside the texture it lies in (a state with
    /// its own photo gives its own patch, if any).
    pub fn white_patch_of(&self, state: &str) -> Option<PixelRect> {
        self.surface(state).white_patch
    }

    /// The fields that `state` changes: `None` for `base`, and for a state the material does
    /// not define (it then keeps its base surface).
    pub fn state(&self, state: &str) -> Option<&SurfaceOverride> {
        match state {
            "degraded" => self.degraded.as_ref(),
            "cleaned" => self.cleaned.as_ref(),
            _ => None,
        }
    }

    /// Whether the material defines `state` (`base` always exists).
    pub fn has_state(&self, state: &str) -> bool {
        state == "base" || self.state(state).is_some()
    }
}

/// A rectangle of a photo's pixels, `x` from the left and `y` from the top edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PixelRect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// A state of a material: the fields it changes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceOverride {
    #[serde(default)]
    pub reflectance: Option<String>,
    /// A degradation map (`[[maps]]`) whose classes vary this state over the surface. Not
    /// written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<String>,
    /// The map's classes this state shows (all of them unless given): a cleaning that removes
    /// some forms of decay and leaves others lists those left. Not written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub classes: Option<Vec<String>>,
    /// Soiling where the weather leaves it: a deposit that covers the surface where rain does
    /// not wash it (see [`Soiling`]). Not written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub soiling: Option<Soiling>,
    /// The state's own photo (the soiled stone photographed as found), in place of the base
    /// one. Not written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<String>,
    /// The grey patch in this state's own `texture` (see [`Material::white_patch`]). Not
    /// written when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub white_patch: Option<PixelRect>,
    #[serde(default)]
    pub roughness: Option<f64>,
    #[serde(default)]
    pub specular: Option<f64>,
    #[serde(default)]
    pub ior: Option<f64>,
}

impl SurfaceOverride {
    /// The fields of the surface this state gives (those it leaves out are the base's).
    pub fn surface(&self) -> Surface<'_> {
        Surface {
            reflectance: self.reflectance.as_deref(),
            roughness: self.roughness,
            specular: self.specular,
            ior: self.ior,
            texture: self.texture.as_deref(),
            white_patch: self.white_patch,
        }
    }
}

/// A material's surface: the one set of fields that its base state (a `[materials.X]` table)
/// and each other state (`[materials.X.degraded]`, …) give, read through [`Material::surface`]
/// and [`SurfaceOverride::surface`] by the scene's checks, the tracer and the studio alike. The
/// file's tables spell the fields out rather than nest this struct because the file refuses
/// unknown keys, which serde cannot do through a flattened struct.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Surface<'a> {
    /// The spectral reflectance ρ(λ), by spectrum name.
    pub reflectance: Option<&'a str>,
    /// Cook–Torrance: Beckmann roughness m.
    pub roughness: Option<f64>,
    /// Cook–Torrance: F0, or …
    pub specular: Option<f64>,
    /// … the index of refraction n.
    pub ior: Option<f64>,
    /// The surface's photo.
    pub texture: Option<&'a str>,
    /// The grey patch in `texture`.
    pub white_patch: Option<PixelRect>,
}

impl<'a> Surface<'a> {
    /// These fields over `base`'s: each one given wins, and a grey patch goes with its photo
    /// (a state with a photo of its own takes only its own patch).
    pub fn over(self, base: Surface<'a>) -> Surface<'a> {
        Surface {
            reflectance: self.reflectance.or(base.reflectance),
            roughness: self.roughness.or(base.roughness),
            specular: self.specular.or(base.specular),
            ior: self.ior.or(base.ior),
            texture: self.texture.or(base.texture),
            white_patch: if self.texture.is_some() { self.white_patch } else { base.white_patch },
        }
    }
}

#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    #[serde(default, deserialize_with = "vec3::opt_translate")]
    pub translate: Option<[f64; 3]>,
    /// Rotations about X, then Y, then Z (degrees).
    #[serde(default, deserialize_with = "vec3::opt_rotate_deg")]
    pub rotate_deg: Option<[f64; 3]>,
    /// A uniform scale, or one per axis.
    #[serde(default)]
    pub scale: Option<Scale>,
}

/// A pane's transmittance at normal incidence: the same in every band (clear glass), or by
/// wavelength, a spectrum named in `[spectra]` (tinted or coated glass).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Transmittance {
    Neutral(f64),
    Spectral(String),
}

/// A number or a spectrum name, refused otherwise with what to give.
impl<'de> Deserialize<'de> for Transmittance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct TransmittanceVisitor;
        impl<'de> Visitor<'de> for TransmittanceVisitor {
            type Value = Transmittance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number 0–1 (clear glass) or the name of a spectrum (tinted glass)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Transmittance, E> {
                Ok(Transmittance::Neutral(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Transmittance, E> {
                Ok(Transmittance::Neutral(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Transmittance, E> {
                Ok(Transmittance::Neutral(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Transmittance, E> {
                Ok(Transmittance::Spectral(v.to_owned()))
            }
        }
        d.deserialize_any(TransmittanceVisitor)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

/// A number, or exactly three; any other length is refused with the field's name (serde's
/// derived untagged form would say only that no variant matched).
impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct ScaleVisitor;
        impl<'de> Visitor<'de> for ScaleVisitor {
            type Value = Scale;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, or 3 numbers [x, y, z]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scale, E> {
                Ok(Scale::Uniform(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Scale, A::Error> {
                vec3::exactly_three(seq, "scale", "give one number, or exactly 3 [x, y, z]")
                    .map(Scale::PerAxis)
            }
        }
        d.deserialize_any(ScaleVisitor)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    Y,
    Z,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    pub name: String,
    /// A mesh file: `.obj`, `.gltf`/`.glb`, `.ply` or `.wrl`.
    pub mesh: String,
    /// The material of every part not named in `materials`.
    #[serde(default)]
    pub material: Option<String>,
    /// The mesh's own group or material names → scene materials.
    #[serde(default)]
    pub materials: BTreeMap<String, String>,
    #[serde(default)]
    pub transform: Transform,
    /// The file's up axis; glTF is Y-up by its specification, other formats are read as Z-up
    /// unless this says otherwise.
    #[serde(default)]
    pub up_axis: Option<UpAxis>,
    /// Level of detail: this object replaces these parts of another object.
    #[serde(default)]
    pub replaces: Option<Replaces>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Replaces {
    pub object: String,
    /// The other object's mesh groups that are hidden.
    pub groups: Vec<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SunPreset {
    /// 100 000 lux, 50° above the horizon.
    Sun,
    /// 10 000 lux, an overcast day.
    Cloudy,
    /// 0.2 lux, the full moon.
    FullMoon,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SiteTime {
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    #[serde(default)]
    pub height_m: f64,
    /// RFC 3339 with a UTC offset, e.g. `2026-07-15T16:30:00+02:00`.
    pub datetime: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Light {
    /// A luminaire radiating from a point: its luminous intensity in candela, or, with an IES or
    /// EULUMDAT file, the file's own absolute photometry (then `intensity_cd`, if given,
    /// overrides it: the file's peak is scaled to it).
    Point {
        #[serde(deserialize_with = "vec3::position")]
        position: [f64; 3],
        #[serde(default)]
        intensity_cd: Option<f64>,
        /// Its luminous flux instead of its intensity: what a lamp's data sheet gives.
        #[serde(default)]
        flux_lm: Option<f64>,
        spectrum: String,
        #[serde(default)]
        ies: Option<String>,
        /// The point the luminaire's nadir (photometric γ = 0) aims at.
        #[serde(default, deserialize_with = "vec3::opt_aim")]
        aim: Option<[f64; 3]>,
    },
    /// A point luminaire with a cone: full intensity inside `cone_deg`, falling to zero at
    /// `cone_deg + falloff_deg` (half-angles).
    Spot {
        #[serde(deserialize_with = "vec3::position")]
        position: [f64; 3],
        #[serde(default)]
        intensity_cd: Option<f64>,
        /// Its luminous flux (all of it, the falloff included) instead of its intensity.
        #[serde(default)]
        flux_lm: Option<f64>,
        spectrum: String,
        #[serde(deserialize_with = "vec3::aim")]
        aim: [f64; 3],
        cone_deg: f64,
        #[serde(default)]
        falloff_deg: f64,
        #[serde(default)]
        ies: Option<String>,
    },
    /// A distant source given by its illuminance on a surface normal to it.
    Sun {
        #[serde(default)]
        illuminance_lux: Option<f64>,
        #[serde(default)]
        preset: Option<SunPreset>,
        #[serde(default)]
        azimuth_deg: Option<f64>,
        #[serde(default)]
        elevation_deg: Option<f64>,
        #[serde(default)]
        site: Option<SiteTime>,
        spectrum: String,
    },
    /// The sky dome: light from every direction above the horizon, given by the illuminance it
    /// gives a horizontal surface open to the whole sky (its diffuse horizontal illuminance).
    Sky {
        #[serde(default)]
        illuminance_lux: Option<f64>,
        /// `overcast` (10 000 lux, the CIE overcast sky) or `clear` (15 000 lux of diffuse
        /// skylight beside a summer sun, uniform).
        #[serde(default)]
        preset: Option<SkyPreset>,
        /// How luminance varies over the dome; `cie-overcast` unless given (`uniform` for the
        /// `clear` preset).
        #[serde(default)]
        model: Option<SkyModel>,
        /// Its spectral shape; CIE D65 when not given (not written then).
        #[serde(default, skip_serializing_if = "String::is_empty")]
        spectrum: String,
        // The keys below are not written when absent, so a sky without them keeps the
        // identity it had before they existed.
        /// With `model = "cie-general"`: the standard's sky type, 1 to 15.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        cie_type: Option<u8>,
        /// Where the sun stands for the sky's shape, when the scene has no sun light (the sun
        /// is then not a light: a sky component with the sun excluded).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sun_elevation_deg: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sun_azimuth_deg: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        site: Option<SiteTime>,
        /// A ground below the horizon, for open scenes: its reflectance, seen at the uniform
        /// luminance ρ·E_h/π (E_h the horizontal illuminance of the sky and sun together).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ground_reflectance: Option<f64>,
    },
    /// A Lambertian emitting rectangle (a light panel, a luminous ceiling, a lit opening): the
    /// same luminance in every direction on its emitting side, given by `luminance_cd_m2` or
    /// by its whole `flux_lm` (Φ = π L A). The camera sees it.
    Area {
        /// One corner (m).
        #[serde(deserialize_with = "vec3::corner")]
        corner: [f64; 3],
        /// One edge, from `corner` (m).
        #[serde(deserialize_with = "vec3::u")]
        u: [f64; 3],
        /// The other edge, from `corner`, at a right angle to `u` (m).
        #[serde(deserialize_with = "vec3::v")]
        v: [f64; 3],
        /// The side it emits from: u × v unless this points the other way.
        #[serde(default, deserialize_with = "vec3::opt_normal")]
        normal: Option<[f64; 3]>,
        #[serde(default)]
        luminance_cd_m2: Option<f64>,
        #[serde(default)]
        flux_lm: Option<f64>,
        spectrum: String,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyPreset {
    /// 10 000 lux, the CIE standard overcast sky.
    Overcast,
    /// 15 000 lux of diffuse skylight, uniform: the sky beside a summer sun.
    Clear,
}

/// The luminance distribution of a sky, over zenith angle θ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyModel {
    /// The same luminance in every direction: L = E_h / π.
    Uniform,
    /// The CIE standard overcast sky (Moon & Spencer 1942; CIE S 011/E:2003, type 1):
    /// L(θ) = L_z (1 + 2 cos θ) / 3, three times brighter at the zenith than at the horizon,
    /// with E_h = 7π L_z / 9.
    CieOvercast,
    /// The CIE standard general sky (ISO 15469:2004), one of its 15 types (`cie_type`), shaped
    /// by the sun's position.
    CieGeneral,
}

/// What a person reads, a name for the sky: "uniform sky", "CIE overcast sky".
impl std::fmt::Display for SkyModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(match self {
            SkyModel::Uniform => "uniform sky",
            SkyModel::CieOvercast => "CIE overcast sky",
            SkyModel::CieGeneral => "CIE general sky",
        })
    }
}

/// A restoration hypothesis: which state each object (or each part of an object) is in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// The state of everything not named below: `base`, `degraded` or `cleaned`.
    #[serde(default = "default_state")]
    pub state: String,
    /// Per object name, or per `object/group`, the state.
    #[serde(default)]
    pub states: BTreeMap<String, String>,
}

impl Variant {
    /// The state this variant gives part `group` of `object`: an `object/group` entry first,
    /// then the object's, then the default.
    pub fn state_for(&self, object: &str, group: &str) -> &str {
        self.states
            .get(&format!("{object}/{group}"))
            .or_else(|| self.states.get(object))
            .unwrap_or(&self.state)
    }
}

fn default_state() -> String {
    "base".to_owned()
}

/// Deserialisers for `[x, y, z]` fields that refuse any other number of elements, naming the
/// field. serde's own `[f64; 3]` takes the first three numbers of a longer TOML array and drops
/// the rest without a word, so `position = [1, 2, 3, 4]` would load as `[1, 2, 3]`.
mod vec3 {
    use super::*;

    /// Three numbers from a sequence, or an error naming `field` and what to give.
    pub(super) fn exactly_three<'de, A: SeqAccess<'de>>(
        mut seq: A,
        field: &str,
        fix: &str,
    ) -> Result<[f64; 3], A::Error> {
        let mut out = [0.0; 3];
        let mut count = 0usize;
        while let Some(v) = seq.next_element::<f64>()? {
            if let Some(slot) = out.get_mut(count) {
                *slot = v;
            }
            count += 1;
        }
        if count == 3 {
            Ok(out)
        } else {
            Err(de::Error::custom(format!(
                "`{field}` has {count} number{}; {fix}",
                if count == 1 { "" } else { "s" }
            )))
        }
    }

    struct Three(&'static str);

    impl<'de> Visitor<'de> for Three {
        type Value = [f64; 3];
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "3 numbers [x, y, z] for `{}`", self.0)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<[f64; 3], A::Error> {
            exactly_three(seq, self.0, "give exactly 3, [x, y, z]")
        }
    }

    /// A present optional field: `null` (how a bundle's JSON writes an absent one) or three.
    struct MaybeThree(&'static str);

    impl<'de> Visitor<'de> for MaybeThree {
        type Value = Option<[f64; 3]>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "3 numbers [x, y, z] for `{}`", self.0)
        }
        fn visit_none<E: de::Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_seq(Three(self.0)).map(Some)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Three(self.0).visit_seq(seq).map(Some)
        }
    }

    macro_rules! fields {
        ($($name:ident, $opt:ident => $field:literal;)*) => {$(
            #[allow(dead_code)]
            pub(super) fn $name<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
                d.deserialize_seq(Three($field))
            }
            #[allow(dead_code)]
            pub(super) fn $opt<'de, D: Deserializer<'de>>(
                d: D,
            ) -> Result<Option<[f64; 3]>, D::Error> {
                d.deserialize_option(MaybeThree($field))
            }
        )*};
    }

    fields! {
        position, opt_position => "position";
        target, opt_target => "target";
        up, opt_up => "up";
        aim, opt_aim => "aim";
        translate, opt_translate => "translate";
        rotate_deg, opt_rotate_deg => "rotate_deg";
        origin, opt_origin => "origin";
        u, opt_u => "u";
        v, opt_v => "v";
        normal, opt_normal => "normal";
        corner, opt_corner => "corner";
    }

    /// A list of points, each exactly three numbers.
    struct Points;

    impl<'de> Visitor<'de> for Points {
        type Value = Option<Vec<[f64; 3]>>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "a list of points [[x, y, z], …] for `points`")
        }
        fn visit_none<E: de::Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_seq(Points)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            struct Point([f64; 3]);
            impl<'de> Deserialize<'de> for Point {
                fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                    d.deserialize_seq(Three("points")).map(Point)
                }
            }
            let mut out = Vec::new();
            while let Some(Point(p)) = seq.next_element()? {
                out.push(p);
            }
            Ok(Some(out))
        }
    }

    pub(super) fn opt_points<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Vec<[f64; 3]>>, D::Error> {
        d.deserialize_option(Points)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(position: &str) -> Result<Camera, toml::de::Error> {
        toml::from_str(&format!(
            "position = {position}\ntarget = [0, 0, 0]\nwidth = 1\nheight = 1\n"
        ))
    }

    /// serde's own `[f64; 3]` would take the first three of four numbers without a word.
    #[test]
    fn vectors_of_any_other_length_are_refused_with_the_field() {
        assert_eq!(camera("[1, 2, 3]").unwrap().position, Some([1.0, 2.0, 3.0]));
        assert_eq!(
            camera("[1, 2, 3, 4]").unwrap_err().message(),
            "`position` has 4 numbers; give exactly 3, [x, y, z]"
        );
        assert_eq!(
            camera("[1]").unwrap_err().message(),
            "`position` has 1 number; give exactly 3, [x, y, z]"
        );
        let t: Result<Transform, _> = toml::from_str("scale = [1, 2]");
        assert_eq!(
            t.unwrap_err().message(),
            "`scale` has 2 numbers; give one number, or exactly 3 [x, y, z]"
        );
        let t: Transform = toml::from_str("scale = 2").unwrap();
        assert_eq!(t.scale, Some(Scale::Uniform(2.0)));
        // A bundle's JSON writes absent vectors as null, and reads them back.
        let c = Camera { position: None, ..camera("[1, 2, 3]").unwrap() };
        let back: Camera = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
    }
}
