//! From a scene file to a validated scene: every number checked to be finite and in range, every
//! name resolved (with the nearest names suggested when one is not), every file read through
//! [`Assets`] (so inside the scene's folder), meshes imported and placed in the world, lights
//! resolved (the sun's position computed), and the limits that protect the machine enforced.
//! Nothing renders until all of it has passed.

use crate::assets::{Assets, FolderAssets, extension, utf8_text};
use crate::error::{Result, SceneError};
use crate::formats::gltf::mesh as gltf_mesh;
use crate::formats::photometric::{self, Photometry};
use crate::formats::{obj, ply, vrml};
use crate::mesh::Mesh;
use crate::scene_file::{
    self, Light, MaterialModel, SceneFile, SkyModel, SkyPreset, SpectrumSource, SunPreset,
    Transmittance, UpAxis,
};
use crate::sun::{Site, SunPosition, direction_to_sun, sun_position};
use crate::upright;
use glam::{DMat3, DMat4, DVec3};
use restauro_spectral::csv::{Quantity, load as load_csv};
use restauro_spectral::tabulated::Coverage;
use restauro_spectral::{Illuminant, Spectrum, library};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

pub use crate::limits::Limits;

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

/// The camera in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedCamera {
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub vertical_fov_deg: f64,
    pub width: u32,
    pub height: u32,
}

/// An object's mesh in world coordinates and what each of its parts is made of.
#[derive(Clone, Debug)]
pub struct LoadedObject {
    pub name: String,
    pub mesh: Mesh,
    /// For each mesh group, the scene material.
    pub group_materials: Vec<String>,
    /// For each mesh group, whether another object replaces it (level of detail).
    pub hidden_groups: Vec<bool>,
}

/// A light with everything resolved.
#[derive(Clone, Debug)]
pub enum ResolvedLight {
    Point {
        position: [f64; 3],
        intensity_cd: f64,
        spectrum: String,
        photometry: Option<Photometry>,
        aim: Option<[f64; 3]>,
    },
    Spot {
        position: [f64; 3],
        intensity_cd: f64,
        spectrum: String,
        aim: [f64; 3],
        cone_deg: f64,
        falloff_deg: f64,
        photometry: Option<Photometry>,
    },
    Sun {
        /// Unit vector towards the sun (+X east, +Y north, +Z up).
        direction: [f64; 3],
        azimuth_deg: f64,
        elevation_deg: f64,
        illuminance_lux: f64,
        spectrum: String,
    },
    /// The sky dome: `illuminance_lux` on a horizontal surface open to the whole sky.
    Sky {
        illuminance_lux: f64,
        model: SkyModel,
        spectrum: String,
        /// With [`SkyModel::CieGeneral`]: its type and the sun that shapes it.
        general: Option<crate::cie_sky::GeneralSky>,
        /// The luminance of the ground below the horizon (0: none, or black).
        ground_cd_m2: f64,
    },
    /// A Lambertian emitting rectangle.
    Area { panel: crate::area_light::Panel, luminance_cd_m2: f64, spectrum: String },
}

impl ResolvedLight {
    /// A luminaire's luminous flux as rendered, lm: its photometric file's, scaled to the
    /// intensity rendered, or that of its intensity in its shape (isotropic, or the spot's
    /// cone). `None` for the sun and the sky.
    pub fn flux_lm(&self) -> Option<f64> {
        match self {
            ResolvedLight::Point { intensity_cd, photometry, .. } => {
                Some(intensity_cd * lumens_per_cd(photometry.as_ref(), 4.0 * std::f64::consts::PI))
            }
            ResolvedLight::Area { panel, luminance_cd_m2, .. } => {
                Some(std::f64::consts::PI * luminance_cd_m2 * panel.area_m2())
            }
            ResolvedLight::Spot { intensity_cd, photometry, cone_deg, falloff_deg, .. } => Some(
                intensity_cd
                    * lumens_per_cd(
                        photometry.as_ref(),
                        spot_lumens_per_cd(*cone_deg, *falloff_deg),
                    ),
            ),
            _ => None,
        }
    }
}

/// One line describing the light, for people: what `restauro scene check` lists and the demo's
/// report records.
impl std::fmt::Display for ResolvedLight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ResolvedLight::Sun {
                azimuth_deg, elevation_deg, illuminance_lux, spectrum, ..
            } => {
                write!(
                    f,
                    "sun: {illuminance_lux} lux, azimuth {azimuth_deg:.2}°, elevation {elevation_deg:.2}°, spectrum {spectrum}"
                )
            }
            ResolvedLight::Point { position, intensity_cd, photometry, .. } => {
                write!(f, "point luminaire at {position:?}: {intensity_cd} cd")?;
                write_photometry(f, *intensity_cd, photometry.as_ref())
            }
            ResolvedLight::Spot { position, intensity_cd, cone_deg, photometry, .. } => {
                write!(f, "spot at {position:?}: {intensity_cd} cd")?;
                match photometry {
                    Some(_) => write_photometry(f, *intensity_cd, photometry.as_ref()),
                    None => write!(f, ", cone {cone_deg}°"),
                }
            }
            ResolvedLight::Sky { illuminance_lux, model, spectrum, general, ground_cd_m2 } => {
                write!(f, "{model}")?;
                if let Some(g) = general {
                    let el = g.sun[2].clamp(-1.0, 1.0).asin().to_degrees();
                    write!(f, " type {} (sun {el:.1}° high)", g.sky_type)?;
                }
                write!(f, ": {illuminance_lux} lux on the horizontal, spectrum {spectrum}")?;
                if *ground_cd_m2 > 0.0 {
                    write!(f, "; ground below the horizon at {ground_cd_m2:.1} cd/m²")?;
                }
                Ok(())
            }
            ResolvedLight::Area { panel, luminance_cd_m2, spectrum } => {
                let area = panel.area_m2();
                write!(
                    f,
                    "area luminaire at {:?}: {luminance_cd_m2} cd/m² over {area:.3} m², {:.0} lm, \
                     spectrum {spectrum}",
                    panel.corner,
                    std::f64::consts::PI * luminance_cd_m2 * area
                )
            }
        }
    }
}

/// What `scene check` says of a luminaire's photometric file, at the intensity rendered:
/// its flux, peak intensity and beam angle (50 % of the peak).
fn write_photometry(
    f: &mut std::fmt::Formatter<'_>,
    intensity_cd: f64,
    photometry: Option<&Photometry>,
) -> std::fmt::Result {
    let Some(p) = photometry else { return Ok(()) };
    let scale = if p.peak_cd() > 0.0 { intensity_cd / p.peak_cd() } else { 0.0 };
    write!(
        f,
        " (photometric file: {:.0} lm, peak {:.0} cd, beam {:.1}°)",
        scale * p.flux_lm(),
        intensity_cd,
        p.beam_angle_deg()
    )
}

/// A scene that has passed every check.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The file as rendered: recentred on its `origin` when it has one (then `origin` is
    /// `None` here, and every position is relative to [`LoadedScene::origin_m`]).
    pub file: SceneFile,
    /// What was taken out of every position (m; zero for a scene without `origin`): add it to
    /// report a position in the file's coordinates.
    pub origin_m: [f64; 3],
    /// The materials' photo textures, decoded, by their reference in the file.
    pub textures: BTreeMap<String, std::sync::Arc<crate::formats::texture::Texture>>,
    pub camera: ResolvedCamera,
    /// Every named spectrum on the grid.
    pub spectra: BTreeMap<String, Spectrum>,
    pub objects: Vec<LoadedObject>,
    pub lights: Vec<ResolvedLight>,
    /// The calculation grids, in the file's order.
    pub grids: Vec<crate::grid::ResolvedGrid>,
    /// Things done to the data that the user should know (extrapolation, dropped triangles,
    /// materials without a state a variant asks for).
    pub notes: Vec<String>,
}

impl LoadedScene {
    /// The camera as the levels of detail see it ([`crate::lod`]).
    pub fn viewer(&self) -> crate::lod::Viewer {
        crate::lod::Viewer {
            position_m: self.camera.position,
            vertical_fov_deg: self.camera.vertical_fov_deg,
            height_px: self.camera.height,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangles.len()).sum()
    }

    /// The state (`base`, `degraded` or `cleaned`) that `variant` gives part `group` of
    /// `object`: the most specific entry wins.
    pub fn state_of<'a>(&'a self, variant: &str, object: &str, group: &str) -> Option<&'a str> {
        Some(self.file.variants.get(variant)?.state_for(object, group))
    }
}

/// The deepest nesting of arrays and inline tables a scene file may have. A scene needs three
/// (`mix = [{ … }]` inside a table); the TOML parser and serde recurse once per level, so a few
/// hundred kilobytes of `[[[[…` would overflow the stack of the thread that reads it (a worker's
/// thread has 2 MiB) and abort the process, which no error can report.
pub const MAX_TOML_NESTING: usize = 32;

/// Refuse nesting deeper than [`MAX_TOML_NESTING`] before the TOML parser sees it: brackets and
/// braces are counted outside strings and comments, a closer closing only the opener it matches
/// (the fuzz harness found unclosed inline tables with stray `]` between them overflowing the
/// parser, so a stray closer must not hide an opener).
fn check_nesting(text: &str, path: &Path) -> Result<()> {
    let (mut line, mut column) = (1usize, 0usize);
    let mut open: Vec<char> = Vec::new();
    let mut chars = text.chars().peekable();
    // The closing quote of the string being read, and whether it is a multi-line one.
    let mut string: Option<(char, bool)> = None;
    let mut comment = false;
    while let Some(c) = chars.next() {
        column += 1;
        if c == '\n' {
            line += 1;
            column = 0;
            comment = false;
            if string.is_some_and(|(_, multi)| !multi) {
                string = None; // an unterminated string; the parser will say so
            }
            continue;
        }
        if comment {
            continue;
        }
        let triple = |chars: &mut std::iter::Peekable<std::str::Chars>, q: char| {
            let mut ahead = chars.clone();
            if ahead.next() == Some(q) && ahead.next() == Some(q) {
                chars.next();
                chars.next();
                true
            } else {
                false
            }
        };
        match string {
            Some((q, multi)) => {
                if c == '\\' && q == '"' {
                    chars.next(); // an escaped character, whatever it is
                } else if c == q && (!multi || triple(&mut chars, q)) {
                    string = None;
                }
            }
            None => match c {
                '#' => comment = true,
                '"' | '\'' => string = Some((c, triple(&mut chars, c))),
                '[' | '{' => {
                    open.push(c);
                    if open.len() > MAX_TOML_NESTING {
                        return Err(SceneError::syntax(
                            path,
                            line,
                            column,
                            format!(
                                "arrays and inline tables nested more than {MAX_TOML_NESTING} \
                                 deep (or left open); a scene needs three at most, so this file \
                                 is damaged or not a scene"
                            ),
                        ));
                    }
                }
                ']' | '}' if open.last() == Some(&if c == ']' { '[' } else { '{' }) => {
                    open.pop();
                }
                _ => {}
            },
        }
    }
    Ok(())
}

/// Parse the text of a scene file. TOML errors carry their line and column.
pub fn parse_scene(text: &str, path: &Path) -> Result<SceneFile> {
    check_nesting(text, path)?;
    let parsed = crate::guard::catch(|| toml::from_str::<SceneFile>(text))
        .map_err(|_| SceneError::invalid(path, "TOML", crate::guard::gave_up("TOML")))?;
    let file: SceneFile = parsed.map_err(|e| {
        let (line, column) = e
            .span()
            .map(|s| {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
                (line, column)
            })
            .unwrap_or((0, 0));
        SceneError::syntax(path, line, column, plain_message(e.message()))
    })?;
    if file.format != scene_file::FORMAT {
        return Err(SceneError::invalid(
            path,
            "format",
            format!(
                "format = {}, but this restauro reads format {}",
                file.format,
                scene_file::FORMAT
            ),
        ));
    }
    Ok(file)
}

/// The TOML reader's message in the user's words where serde's would name a Rust type: a
/// spectrum that is none of the four forms (an unknown or misspelt key in its inline table).
fn plain_message(message: &str) -> String {
    if message.contains("untagged enum SpectrumSource") {
        return "a spectrum is a shipped name (\"travertine_tufa_solid__eco_ward73\"), \
                { file = \"…csv\", extrapolate = true|false }, { illuminant = \"D65\" } or \
                { mix = [{ spectrum = \"…\", weight = … }, …] }, with no other keys: check the \
                keys of this table"
            .to_owned();
    }
    message.to_owned()
}

/// Load and check the scene file at `path` with the files of its folder; files named by URL
/// are refused (restauro-assets's `load_scene` fetches them, and reads archives too).
pub fn load_folder(path: &Path, limits: &Limits) -> Result<LoadedScene> {
    let file = read_scene_file(path, limits)?;
    crate::pins::check_pins(path, &file.pins)?;
    let assets = FolderAssets::new(path, limits.max_file_bytes)?;
    load(file, &assets, limits)
}

/// Read and parse the scene file at `path`: a regular file (not a FIFO or a device, which would
/// block or never end), within the file size limit, UTF-8.
pub fn read_scene_file(path: &Path, limits: &Limits) -> Result<SceneFile> {
    let bytes =
        crate::assets::read_regular_file(path, limits.max_file_bytes, crate::assets::MAX_FILE_FIX)?;
    let text = crate::assets::utf8_text(bytes, path)?;
    parse_scene(&text, path)
}

/// "unknown X `name` (did you mean …?); the scene defines …".
pub(crate) fn unknown<'a>(kind: &str, name: &str, known: impl Iterator<Item = &'a str>) -> String {
    let known: Vec<&str> = known.collect();
    let mut close: Vec<(f64, &str)> = known
        .iter()
        .map(|k| (strsim::jaro_winkler(k, name), *k))
        .filter(|(s, _)| *s > 0.75)
        .collect();
    close.sort_by(|a, b| b.0.total_cmp(&a.0));
    let hint = match close.first() {
        Some((_, k)) => format!(" (did you mean `{k}`?)"),
        None => String::new(),
    };
    let list = if known.is_empty() {
        "none".to_owned()
    } else {
        known.iter().take(12).map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ")
    };
    format!("unknown {kind} `{name}`{hint}; the scene defines {list}")
}

fn finite3(v: [f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

struct Ctx<'a> {
    path: PathBuf,
    file: &'a SceneFile,
    assets: &'a dyn Assets,
    notes: Vec<String>,
    spectra: BTreeMap<String, Spectrum>,
    /// The largest value of each resolved spectrum (reflectances must not exceed 1).
    spectrum_max: BTreeMap<String, f32>,
}

impl Ctx<'_> {
    fn invalid(&self, place: impl Into<String>, problem: impl Into<String>) -> SceneError {
        SceneError::invalid(&self.path, place, problem)
    }

    /// Resolve a named spectrum (and what it mixes), detecting cycles.
    fn spectrum(
        &mut self,
        name: &str,
        place: &str,
        visiting: &mut Vec<String>,
    ) -> Result<Spectrum> {
        if let Some(s) = self.spectra.get(name) {
            return Ok(*s);
        }
        let source = self
            .file
            .spectra
            .get(name)
            .ok_or_else(|| {
                self.invalid(
                    place,
                    unknown("spectrum", name, self.file.spectra.keys().map(String::as_str)),
                )
            })?
            .clone();
        if visiting.iter().any(|v| v == name) {
            return Err(self.invalid(
                format!("spectra.{name}"),
                format!("the mixture refers to itself ({} → {name})", visiting.join(" → ")),
            ));
        }
        visiting.push(name.to_owned());
        let spectrum_place = format!("spectra.{name}");
        let s = match &source {
            SpectrumSource::Library(stem) => {
                let loaded = library::load_reflectance(stem)
                    .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?;
                self.notes.extend(
                    loaded.notes.iter().map(|n| format!("spectrum `{name}` ({stem}): {n}")),
                );
                loaded.spectrum
            }
            SpectrumSource::File { file, extrapolate } => {
                let bytes = self.assets.read(file, &spectrum_place)?;
                let shown = self.assets.display_path(file);
                let text = utf8_text(bytes, &shown)?;
                let coverage = if *extrapolate { Coverage::HoldEnds } else { Coverage::Require };
                let loaded = load_csv(
                    &text,
                    &shown.display().to_string(),
                    Quantity::RelativePower,
                    coverage,
                )
                .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?;
                self.notes.extend(
                    loaded.notes.iter().map(|n| format!("spectrum `{name}` ({file}): {n}")),
                );
                loaded.spectrum
            }
            SpectrumSource::Illuminant { illuminant } => illuminant
                .parse::<Illuminant>()
                .and_then(|i| i.spd())
                .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?,
            SpectrumSource::Constant { constant } => {
                if !(constant.is_finite() && (0.0..=1e6).contains(constant)) {
                    return Err(self.invalid(
                        &spectrum_place,
                        format!("constant = {constant}: give a value from 0 (a black surface) to 1 for a reflectance, or up to 1e6 for a light"),
                    ));
                }
                Spectrum::splat(*constant as f32)
            }
            SpectrumSource::Mix { mix } => {
                if mix.is_empty() {
                    return Err(self.invalid(
                        &spectrum_place,
                        "an empty mixture; list the spectra and their weights",
                    ));
                }
                let total: f64 = mix.iter().map(|p| p.weight).sum();
                if mix.iter().any(|p| !(p.weight.is_finite() && p.weight >= 0.0))
                    || (total - 1.0).abs() > 1e-6
                {
                    return Err(self.invalid(
                        &spectrum_place,
                        format!("mixture weights must be ≥ 0 and sum to 1 (they sum to {total})"),
                    ));
                }
                let mut out = Spectrum::ZERO;
                for part in mix {
                    let s = self.spectrum(&part.spectrum, &spectrum_place, visiting)?;
                    out += s * part.weight as f32;
                }
                out
            }
        };
        visiting.pop();
        self.spectra.insert(name.to_owned(), s);
        self.spectrum_max.insert(name.to_owned(), s.max_value());
        Ok(s)
    }

    /// A spectrum used as a reflectance: at most 1.
    fn reflectance(&mut self, name: &str, place: &str) -> Result<()> {
        self.spectrum(name, place, &mut Vec::new())?;
        let max = self.spectrum_max[name];
        if max > 1.0 {
            return Err(self.invalid(
                place,
                format!(
                    "spectrum `{name}` reaches {max} but is used as a reflectance, which cannot \
                     exceed 1; give reflectance as a fraction 0..1"
                ),
            ));
        }
        Ok(())
    }

    /// A spectrum used as a light: it must emit at 555 nm (Eq. 2 normalises there).
    fn emission(&mut self, name: &str, place: &str) -> Result<()> {
        let s = self.spectrum(name, place, &mut Vec::new())?;
        restauro_spectral::photometry::LuminousSpectrum::new(&s, name)
            .map_err(|e| self.invalid(place, e.to_string()))?;
        Ok(())
    }
}

/// Check a material's optical numbers.
fn check_surface(
    ctx: &mut Ctx,
    place: &str,
    model: MaterialModel,
    reflectance: Option<&str>,
    roughness: Option<f64>,
    specular: Option<f64>,
    ior: Option<f64>,
) -> Result<()> {
    if let Some(r) = reflectance {
        ctx.reflectance(r, &format!("{place}.reflectance"))?;
    }
    match model {
        MaterialModel::Glass => {
            if reflectance.is_some() || roughness.is_some() || specular.is_some() {
                return Err(ctx.invalid(
                    place,
                    "glass has no reflectance, roughness or specular: its reflection follows from \
                     its ior; give ior, thickness_mm and transmittance",
                ));
            }
            if let Some(n) = ior
                && !(n.is_finite() && n > 1.0 && n <= 3.0)
            {
                return Err(ctx.invalid(
                    format!("{place}.ior"),
                    format!(
                        "{n} is out of range; glass has an index of refraction above 1, at most 3"
                    ),
                ));
            }
        }
        MaterialModel::Lambert => {
            if roughness.is_some() || specular.is_some() || ior.is_some() {
                return Err(ctx.invalid(place, "a lambert material has no roughness, specular or ior; use model = \"cook-torrance\""));
            }
        }
        MaterialModel::CookTorrance => {
            if let Some(m) = roughness
                && !(m.is_finite() && m > 0.0 && m <= 1.0)
            {
                return Err(ctx.invalid(
                    format!("{place}.roughness"),
                    format!("{m} is out of range; the Beckmann roughness m is in (0, 1]"),
                ));
            }
            if specular.is_some() && ior.is_some() {
                return Err(ctx.invalid(place, "give either specular (F0) or ior, not both"));
            }
            if let Some(f0) = specular
                && !(f0.is_finite() && (0.0..=1.0).contains(&f0))
            {
                return Err(ctx.invalid(
                    format!("{place}.specular"),
                    format!("{f0} is out of range; F0 is a reflectance 0..1"),
                ));
            }
            if let Some(n) = ior
                && !(n.is_finite() && (1.0..=5.0).contains(&n))
            {
                return Err(ctx.invalid(
                    format!("{place}.ior"),
                    format!("{n} is out of range; an index of refraction is 1 to 5"),
                ));
            }
        }
    }
    Ok(())
}

/// The name of the spectrum a sky is given without one: CIE D65, the daylight of the CIE
/// general sky's definition. A `[spectra]` entry of this name is the user's own, and wins.
pub const DEFAULT_SKY_SPECTRUM: &str = "cie:D65";

/// A sky's spectrum: its own, or [`DEFAULT_SKY_SPECTRUM`], resolved into the scene's spectra.
fn sky_spectrum(ctx: &mut Ctx, given: &str) -> Result<String> {
    if !given.is_empty() {
        return Ok(given.to_owned());
    }
    if !ctx.file.spectra.contains_key(DEFAULT_SKY_SPECTRUM) {
        let d65 = Illuminant::D65.spd().map_err(|e| ctx.invalid("spectrum", e.to_string()))?;
        ctx.spectra.insert(DEFAULT_SKY_SPECTRUM.to_owned(), d65);
    }
    Ok(DEFAULT_SKY_SPECTRUM.to_owned())
}

/// A material's glazing keys: only glass has them, and glass needs no reflectance. The pane is
/// at most 100 mm thick and transmits at most what its faces let through, (1 − r)/(1 + r), in
/// every band.
fn check_glazing(ctx: &mut Ctx, place: &str, m: &crate::scene_file::Material) -> Result<()> {
    if m.model != MaterialModel::Glass {
        if m.thickness_mm.is_some() || m.transmittance.is_some() {
            return Err(
                ctx.invalid(place, "thickness_mm and transmittance are for model = \"glass\"")
            );
        }
        if m.reflectance.is_empty() {
            return Err(ctx.invalid(
                format!("{place}.reflectance"),
                "a material needs its reflectance, a spectrum name",
            ));
        }
        return Ok(());
    }
    if !m.reflectance.is_empty() {
        return Err(ctx.invalid(
            format!("{place}.reflectance"),
            "glass has no reflectance: its reflection follows from its ior",
        ));
    }
    if let Some(d) = m.thickness_mm
        && !(d.is_finite() && d > 0.0 && d <= 100.0)
    {
        return Err(ctx.invalid(
            format!("{place}.thickness_mm"),
            format!("{d} mm is out of range; a pane is more than 0 and at most 100 mm thick"),
        ));
    }
    let n = m.ior.unwrap_or(crate::glazing::DEFAULT_IOR);
    let most = crate::glazing::max_transmittance(n).min(1.0);
    let field = format!("{place}.transmittance");
    let (t, band) = match &m.transmittance {
        None => return Ok(()),
        Some(Transmittance::Neutral(t)) => (*t, String::new()),
        Some(Transmittance::Spectral(name)) => {
            let s = ctx.spectrum(name, &field, &mut Vec::new())?;
            // The first band out of range, to name it (its value as the spectrum holds it).
            let inside = |v: f32| (0.0..=most).contains(&f64::from(v));
            let Some(i) = s.0.iter().position(|&v| !inside(v)) else { return Ok(()) };
            let nm = restauro_spectral::grid::wavelength_nm(i);
            let t = format!("{}", s.0[i]).parse().unwrap_or(f64::NAN);
            (t, format!("spectrum `{name}` at {nm} nm: "))
        }
    };
    if !(t.is_finite() && (0.0..=most).contains(&t)) {
        return Err(ctx.invalid(
            field,
            format!("{band}{t} is out of range; glass of index {n} transmits 0 to {most:.4} at normal incidence (its faces reflect the rest)"),
        ));
    }
    Ok(())
}

/// Import a mesh by its reference's extension; also returns VRML viewpoints and the file's
/// own notes (what a VRML world holds but does not draw). Messages about the mesh's content
/// name the mesh file by its path.
fn import_mesh(
    ctx: &Ctx,
    reference: &str,
    place: &str,
    limits: &Limits,
) -> Result<(Mesh, Vec<vrml::Viewpoint>, UpAxis, Vec<String>)> {
    let bytes = ctx.assets.read(reference, place)?;
    let name = ctx.assets.display_path(reference);
    Ok(match extension(reference).as_str() {
        "obj" => {
            let text = utf8_text(bytes, &name)?;
            let mut mesh = obj::parse_limited(&text, &name, limits)?;
            let notes = crate::formats::obj::library::apply(
                &mut mesh,
                &text,
                reference,
                ctx.assets,
                place,
                limits.max_pixels,
            )?;
            (mesh, Vec::new(), UpAxis::Z, notes)
        }
        "ply" => (ply::parse_limited(&bytes, &name, limits)?, Vec::new(), UpAxis::Z, Vec::new()),
        "gltf" | "glb" => {
            // A buffer that cannot be read is the model's problem: the message names the model.
            let beside = |uri: &str| {
                let invalid = |e: String| SceneError::invalid(&name, format!("buffer `{uri}`"), e);
                let file = crate::assets::sibling(reference, uri).map_err(invalid)?;
                ctx.assets.read(&file, place).map_err(|e| invalid(e.to_string()))
            };
            let (mesh, cameras) = gltf_mesh::parse_with_cameras(&bytes, &name, limits, &beside)?;
            (mesh, cameras, UpAxis::Y, Vec::new())
        }
        "wrl" => {
            let text = utf8_text(bytes, &name)?;
            let inlines = crate::assets::vrml_inlines(ctx.assets, place);
            let scene = vrml::parse_with_inlines(&text, &name, reference, limits, &inlines)?;
            (scene.mesh, scene.viewpoints, UpAxis::Y, scene.notes)
        }
        other => {
            return Err(ctx.invalid(
                place,
                format!("`{reference}`: `.{other}` is not a mesh format restauro reads; use .obj, .gltf, .glb, .ply or .wrl"),
            ));
        }
    })
}

/// The object's placement: the file's up axis turned to +Z, then scale, rotation (X, Y, Z)
/// and translation.
fn object_matrix(object: &scene_file::Object, file_up: UpAxis) -> DMat4 {
    let up = match object.up_axis.unwrap_or(file_up) {
        // Y-up to Z-up: +Y becomes +Z, +Z becomes −Y (a +90° turn about X).
        UpAxis::Y => DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2),
        UpAxis::Z => DMat4::IDENTITY,
    };
    let t = &object.transform;
    let scale = match &t.scale {
        Some(scene_file::Scale::Uniform(s)) => DVec3::splat(*s),
        Some(scene_file::Scale::PerAxis(s)) => DVec3::from_array(*s),
        None => DVec3::ONE,
    };
    let r = t.rotate_deg.unwrap_or([0.0; 3]).map(f64::to_radians);
    let rotation =
        DMat4::from_rotation_z(r[2]) * DMat4::from_rotation_y(r[1]) * DMat4::from_rotation_x(r[0]);
    DMat4::from_translation(DVec3::from_array(t.translate.unwrap_or([0.0; 3])))
        * rotation
        * DMat4::from_scale(scale)
        * up
}

/// A note when a mesh read as Z-up looks as if it were written Y-up (see [`upright`]).
fn note_if_on_its_back(ctx: &mut Ctx, mesh: &Mesh, place: &str, reference: &str) {
    if let Some(e) = upright::y_up_evidence(mesh) {
        ctx.notes.push(format!(
            "{place}: `{reference}` probably lies on its back: read Z-up, as OBJ and PLY are by \
             default, its surfaces face +Y overall ({:.0}° from +Y, where a survey's open \
             underside leaves them facing up). If it was exported Y-up, add `up_axis = \"y\"` \
             to the object; `up_axis = \"z\"` says it is right as it is and ends this note",
            e.angle_to_y_deg
        ));
    }
}

/// Check the imported mesh: finite vertices, valid indices, something to render; degenerate
/// triangles (zero area, common in scans) are dropped and counted.
fn check_mesh(ctx: &mut Ctx, mesh: &mut Mesh, place: &str, reference: &str) -> Result<()> {
    if let Some(i) = mesh.positions.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(ctx.invalid(
            place,
            format!("`{reference}`: vertex {i} is {:?}, not a finite position", mesh.positions[i]),
        ));
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(ctx.invalid(
            place,
            format!("`{reference}`: triangle {t} refers to a vertex beyond the {n} there are"),
        ));
    }
    let before = mesh.triangles.len();
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| DVec3::from_array(mesh.positions[i as usize].map(f64::from)));
            (b - a).cross(c - a).length_squared() > 0.0
        })
        .collect();
    let mut k = keep.iter();
    mesh.triangles.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    mesh.triangle_group.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    mesh.levels.of_triangle.retain(|_| *k.next().unwrap_or(&true));
    let dropped = before - mesh.triangles.len();
    if mesh.triangles.is_empty() {
        return Err(ctx.invalid(
            place,
            format!("`{reference}` has no triangles with an area; nothing to render"),
        ));
    }
    if dropped > 0 {
        ctx.notes.push(format!(
            "{place}: {dropped} degenerate (zero-area) triangles of `{reference}` dropped"
        ));
    }
    Ok(())
}

/// A pose (the camera's, a view's) the tracer can look from: every point in range, the target
/// away from the eye, up not along the line of sight, a field of view between 0° and 180°.
fn check_pose(ctx: &Ctx, place: &str, pose: &ResolvedCamera) -> Result<()> {
    check_point(ctx, &format!("{place}.position"), pose.position)?;
    check_point(ctx, &format!("{place}.target"), pose.target)?;
    check_point(ctx, &format!("{place}.up"), pose.up)?;
    let (p, t, u) = (
        DVec3::from_array(pose.position),
        DVec3::from_array(pose.target),
        DVec3::from_array(pose.up),
    );
    if (t - p).length() < 1e-9 {
        return Err(ctx.invalid(place, "the target is where the camera is; move one of them"));
    }
    if (t - p).normalize().cross(u.normalize_or_zero()).length() < 1e-6 {
        return Err(ctx.invalid(
            format!("{place}.up"),
            "up is parallel to the viewing direction; use another up, e.g. [0, 0, 1]",
        ));
    }
    let fov = pose.vertical_fov_deg;
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        return Err(ctx.invalid(
            format!("{place}.vertical_fov_deg"),
            format!("{fov} is out of range; use an angle between 0 and 180 degrees"),
        ));
    }
    Ok(())
}

/// `key` names an object (`name`) or a part of one (`object/part`).
fn check_part(ctx: &Ctx, place: &str, objects: &[LoadedObject], key: &str) -> Result<()> {
    let (object, group) = match key.split_once('/') {
        Some((o, g)) => (o, Some(g)),
        None => (key, None),
    };
    let o = objects.iter().find(|o| o.name == object).ok_or_else(|| {
        ctx.invalid(place, unknown("object", object, objects.iter().map(|o| o.name.as_str())))
    })?;
    if let Some(g) = group
        && !o.mesh.groups.iter().any(|x| x.name == g)
    {
        return Err(ctx.invalid(
            place,
            unknown("mesh part", g, o.mesh.groups.iter().map(|x| x.name.as_str())),
        ));
    }
    Ok(())
}

/// The longest link an annotation may hold, in bytes.
const MAX_LINK_BYTES: usize = 2048;

/// Every annotation: a title of its own, its pin in range, its part in the scene, its links
/// web addresses (so that no link runs a script or opens a local file), its pose one the
/// camera can take.
fn check_annotations(ctx: &Ctx, file: &SceneFile, objects: &[LoadedObject]) -> Result<()> {
    let mut seen = BTreeSet::new();
    for (i, a) in file.annotations.iter().enumerate() {
        let place = format!("annotations[{i}]");
        if a.title.trim().is_empty() {
            return Err(ctx.invalid(format!("{place}.title"), "a note needs a title"));
        }
        if !seen.insert(a.title.as_str()) {
            return Err(ctx.invalid(
                format!("{place}.title"),
                format!("a second note titled `{}`; give each note its own title", a.title),
            ));
        }
        check_point(ctx, &format!("{place}.position"), a.position)?;
        if let Some(part) = &a.part {
            check_part(ctx, &format!("{place}.part"), objects, part)?;
        }
        for (k, link) in a.links.iter().enumerate() {
            let web = link.starts_with("https://") || link.starts_with("http://");
            if !web || link.len() > MAX_LINK_BYTES || link.chars().any(char::is_whitespace) {
                return Err(ctx.invalid(
                    format!("{place}.links[{k}]"),
                    format!(
                        "`{}` is not a web address; give an https:// (or http://) address of at most {MAX_LINK_BYTES} bytes, without spaces",
                        link.chars().take(80).collect::<String>().escape_debug()
                    ),
                ));
            }
        }
        if let Some(p) = &a.pose {
            let pose = pose_camera(p.position, p.target, p.up, p.vertical_fov_deg);
            check_pose(ctx, &format!("{place}.pose"), &pose)?;
        }
        check_note_images(ctx, &place, &a.images)?;
    }
    Ok(())
}

/// A note's images: at most [`note_image::MAX_PER_NOTE`], each a PNG or JPEG file that is what
/// its name says.
fn check_note_images(ctx: &Ctx, place: &str, images: &[String]) -> Result<()> {
    use crate::note_image;
    if images.len() > note_image::MAX_PER_NOTE {
        return Err(ctx.invalid(
            format!("{place}.images"),
            format!(
                "{} images; a note holds at most {}: link the rest as documents",
                images.len(),
                note_image::MAX_PER_NOTE
            ),
        ));
    }
    for (k, reference) in images.iter().enumerate() {
        let place = format!("{place}.images[{k}]");
        let kind = extension(reference);
        if !note_image::EXTENSIONS.contains(&kind.as_str()) {
            return Err(ctx.invalid(
                place,
                format!("`{reference}`: a note's image is a .png, .jpg or .jpeg file"),
            ));
        }
        let bytes = ctx.assets.read(reference, &place)?;
        let shown = ctx.assets.display_path(reference);
        if bytes.len() > note_image::MAX_BYTES {
            return Err(SceneError::invalid(
                &shown,
                place,
                format!(
                    "{} bytes; a note's image may have at most {}: send a smaller copy",
                    bytes.len(),
                    note_image::MAX_BYTES
                ),
            ));
        }
        if note_image::media_type(&kind, &bytes).is_none() {
            return Err(SceneError::invalid(&shown, place, note_image::not_an_image(&kind)));
        }
    }
    Ok(())
}

/// A pose as a camera, for [`check_pose`] (its image size is not a pose's).
fn pose_camera(position: [f64; 3], target: [f64; 3], up: [f64; 3], fov: f64) -> ResolvedCamera {
    ResolvedCamera { position, target, up, vertical_fov_deg: fov, width: 1, height: 1 }
}

/// Every saved view: a name of its own, and a pose [`check_pose`] accepts.
fn check_views(ctx: &Ctx, views: &[scene_file::View]) -> Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for (i, v) in views.iter().enumerate() {
        let place = format!("views[{i}]");
        if v.name.trim().is_empty() {
            return Err(ctx.invalid(format!("{place}.name"), "a view needs a name"));
        }
        if !seen.insert(v.name.as_str()) {
            return Err(ctx.invalid(
                format!("{place}.name"),
                format!("a second view named `{}`; give each view its own name", v.name),
            ));
        }
        check_pose(ctx, &place, &pose_camera(v.position, v.target, v.up, v.vertical_fov_deg))?;
    }
    Ok(())
}

/// Whether a world coordinate is one the tracer can hold: finite, and within
/// [`MAX_COORDINATE_M`] (so finite as a 32-bit float too).
fn placeable(x: f64) -> bool {
    x.is_finite() && x.abs() <= MAX_COORDINATE_M
}

/// "must be finite and within ±1e9 m" for a point field.
fn check_point(ctx: &Ctx, place: &str, p: [f64; 3]) -> Result<()> {
    if p.iter().all(|&x| placeable(x)) {
        return Ok(());
    }
    Err(ctx.invalid(
        place,
        format!(
            "{p:?} is out of range; every coordinate must be finite and within ±{MAX_COORDINATE_M:e} m \
             (check the units: restauro works in metres)"
        ),
    ))
}

/// Every vertex of a placed mesh within [`MAX_COORDINATE_M`]: a huge scale or translation
/// must be refused here, by `scene check`, not by the tracer's BVH builder.
fn check_placed(ctx: &Ctx, mesh: &Mesh, place: &str, reference: &str) -> Result<()> {
    match mesh.positions.iter().position(|p| !p.iter().all(|&x| placeable(f64::from(x)))) {
        None => Ok(()),
        Some(i) => Err(ctx.invalid(
            format!("{place}.transform"),
            format!(
                "vertex {i} of `{reference}` lands at {:?} m once placed, beyond ±{MAX_COORDINATE_M:e} m; \
                 check the transform's scale and translate (and the file's units)",
                mesh.positions[i]
            ),
        )),
    }
}

/// Place the mesh: its file coordinates (anchor and all, in 64 bits) through `m`, which
/// includes the scene's `origin`; the placed mesh has no anchor.
fn transform_mesh(mesh: &mut Mesh, m: DMat4) {
    let anchor = DVec3::from_array(mesh.anchor_m);
    for p in &mut mesh.positions {
        let in_file = anchor + DVec3::from_array(p.map(f64::from));
        *p = m.transform_point3(in_file).as_vec3().to_array();
    }
    mesh.anchor_m = [0.0; 3];
    mesh.levels.transform(m);
    let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
    if let Some(normals) = &mut mesh.normals {
        for n in normals.iter_mut() {
            *n = (normal_matrix * DVec3::from_array(n.map(f64::from)))
                .normalize_or_zero()
                .as_vec3()
                .to_array();
        }
    }
    // A mirroring placement turns the winding around; keep front faces counter-clockwise.
    if m.determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
}

fn photometry(ctx: &Ctx, reference: &Option<String>, place: &str) -> Result<Option<Photometry>> {
    let Some(reference) = reference else { return Ok(None) };
    let bytes = ctx.assets.read(reference, place)?;
    let text = photometric::decode_text(bytes);
    let name = ctx.assets.display_path(reference);
    Ok(Some(match extension(reference).as_str() {
        "ies" => photometric::parse_ies(&text, &name)?,
        "ldt" => photometric::parse_ldt(&text, &name)?,
        other => {
            return Err(ctx.invalid(place, format!("`{reference}`: `.{other}` is not a photometric format; use .ies (LM-63) or .ldt (EULUMDAT)")));
        }
    }))
}

/// Validate and resolve a parsed scene, reading its files through `assets`.
pub fn load(file: SceneFile, assets: &dyn Assets, limits: &Limits) -> Result<LoadedScene> {
    if let Some(o) = file.origin
        && !o.iter().all(|&x| placeable(x))
    {
        return Err(SceneError::invalid(
            assets.scene_path(),
            "origin",
            format!(
                "{o:?} is out of range; every coordinate must be finite and within ±{MAX_COORDINATE_M:e} m"
            ),
        ));
    }
    let (file, origin_m) = crate::origin::recentre(file);
    let mut ctx = Ctx {
        path: assets.scene_path().to_owned(),
        file: &file,
        assets,
        notes: Vec::new(),
        spectra: BTreeMap::new(),
        spectrum_max: BTreeMap::new(),
    };
    let limit = |what: &str, value: u64, limit: u64, fix: &str| SceneError::Limit {
        path: assets.scene_path().to_owned(),
        what: what.to_owned(),
        value,
        limit,
        fix: fix.to_owned(),
    };

    // Render settings.
    let r = &file.render;
    if r.samples_per_pixel == 0 || r.samples_per_pixel > limits.max_samples_per_pixel {
        return Err(limit(
            "render.samples_per_pixel",
            u64::from(r.samples_per_pixel),
            u64::from(limits.max_samples_per_pixel),
            "use 1 or more, or raise the limit with --max-spp",
        ));
    }
    // 0 is no cap: the roulette ends paths, at a cost bounded in expectation.
    if r.max_depth > limits.max_depth {
        return Err(limit(
            "render.max_depth",
            u64::from(r.max_depth),
            u64::from(limits.max_depth),
            "use fewer bounces (0: no cap, the roulette ends paths), or raise the limit with --max-depth",
        ));
    }

    // Spectra: every one must resolve, used or not, so mistakes surface now.
    for name in file.spectra.keys() {
        ctx.spectrum(name, &format!("spectra.{name}"), &mut Vec::new())?;
    }

    // Materials and their states.
    for (name, m) in &file.materials {
        let place = format!("materials.{name}");
        check_glazing(&mut ctx, &place, m)?;
        check_surface(
            &mut ctx,
            &place,
            m.model,
            (m.model != MaterialModel::Glass).then_some(m.reflectance.as_str()),
            m.roughness,
            m.specular,
            m.ior,
        )?;
        for (state, o) in [("degraded", &m.degraded), ("cleaned", &m.cleaned)] {
            if let Some(o) = o {
                let p = format!("{place}.{state}");
                check_surface(
                    &mut ctx,
                    &p,
                    m.model,
                    o.reflectance.as_deref(),
                    o.roughness,
                    o.specular,
                    o.ior,
                )?;
                if let Some(soiling) = &o.soiling {
                    check_soiling(&mut ctx, &format!("{p}.soiling"), soiling)?;
                }
            }
        }
    }

    let mut textures = load_textures(&ctx, limits)?;
    check_maps(&mut ctx, limits, &mut textures)?;

    // Objects.
    let mut objects: Vec<LoadedObject> = Vec::new();
    let mut viewpoints: BTreeMap<String, (Vec<vrml::Viewpoint>, DMat4)> = BTreeMap::new();
    let mut names = BTreeSet::new();
    let mut triangles: u64 = 0;
    for (i, o) in file.objects.iter().enumerate() {
        let place = format!("objects[{i}] ({})", o.name);
        if !names.insert(o.name.clone()) {
            return Err(ctx.invalid(
                &place,
                format!("the name `{}` is used by two objects; names must be unique", o.name),
            ));
        }
        let t = &o.transform;
        let bad_vec =
            t.translate.is_some_and(|v| !finite3(v)) || t.rotate_deg.is_some_and(|v| !finite3(v));
        let bad_scale = match &t.scale {
            Some(scene_file::Scale::Uniform(s)) => !(s.is_finite() && *s != 0.0),
            Some(scene_file::Scale::PerAxis(s)) => !s.iter().all(|v| v.is_finite() && *v != 0.0),
            None => false,
        };
        if bad_vec || bad_scale {
            return Err(ctx.invalid(
                format!("{place}.transform"),
                "every number must be finite, and a scale not 0",
            ));
        }
        let (mut mesh, vps, file_up, file_notes) =
            import_mesh(&ctx, &o.mesh, &format!("{place}.mesh"), limits)?;
        // The notes name the mesh file and its line; the object says which use of it.
        ctx.notes.extend(file_notes.into_iter().map(|n| format!("object `{}`: {n}", o.name)));
        check_mesh(&mut ctx, &mut mesh, &place, &o.mesh)?;
        for g in 0..mesh.groups.len() {
            if mesh.groups[g].photo.is_some() && !mesh.group_has_texcoords(g as u32) {
                mesh.groups[g].photo = None;
                ctx.notes.push(format!(
                    "object `{}`: part `{}` has a photo in `{}` but no texture coordinates for it; it is shown without",
                    o.name, mesh.groups[g].name, o.mesh
                ));
            }
        }
        if o.up_axis.is_none() && file_up == UpAxis::Z {
            note_if_on_its_back(&mut ctx, &mesh, &place, &o.mesh);
        }
        triangles += mesh.triangles.len() as u64;
        if triangles > limits.max_triangles {
            return Err(limit(
                "the number of triangles",
                triangles,
                limits.max_triangles,
                "simplify the meshes, or raise the limit with --max-triangles",
            ));
        }
        let matrix = object_matrix(o, file_up);
        transform_mesh(&mut mesh, matrix);
        check_placed(&ctx, &mesh, &place, &o.mesh)?;
        viewpoints.insert(o.name.clone(), (vps, matrix));
        // Bind each part to a scene material.
        for key in o.materials.keys() {
            if !mesh.groups.iter().any(|g| &g.name == key) {
                return Err(ctx.invalid(
                    format!("{place}.materials"),
                    unknown("mesh part", key, mesh.groups.iter().map(|g| g.name.as_str()))
                        .replace("the scene defines", &format!("`{}` has", o.mesh)),
                ));
            }
        }
        let mut group_materials = Vec::new();
        for g in &mesh.groups {
            let material = o.materials.get(&g.name).or(o.material.as_ref()).ok_or_else(|| {
                ctx.invalid(&place, format!("part `{}` of `{}` has no material: bind it in `materials` or give `material`", g.name, o.mesh))
            })?;
            if !file.materials.contains_key(material) {
                return Err(ctx.invalid(
                    &place,
                    unknown("material", material, file.materials.keys().map(String::as_str)),
                ));
            }
            let m = &file.materials[material];
            if let (Some(photo), None, Some(patch)) = (&g.photo, &m.texture, m.white_patch) {
                photo.check_patch(patch).map_err(|problem| {
                    ctx.invalid(
                        format!("materials.{material}.white_patch"),
                        format!("in the photo of part `{}` of `{}`: {problem}", g.name, o.mesh),
                    )
                })?;
            }
            let textured =
                ["base", "degraded", "cleaned"].iter().any(|st| m.texture_of(st).is_some());
            let group = group_materials.len() as u32;
            if textured && !mesh.group_has_texcoords(group) {
                return Err(ctx.invalid(
                    &place,
                    format!(
                        "part `{}` of `{}` has no texture coordinates (OBJ `vt`, glTF TEXCOORD_0), \
                         but its material `{material}` has a texture; export the model with its \
                         texture coordinates, or take the texture off the material",
                        g.name, o.mesh
                    ),
                ));
            }
            group_materials.push(material.clone());
        }
        let hidden_groups = vec![false; mesh.groups.len()];
        objects.push(LoadedObject { name: o.name.clone(), mesh, group_materials, hidden_groups });
    }
    // Level of detail: hide the parts that detailed objects replace.
    for (i, o) in file.objects.iter().enumerate() {
        let Some(rep) = &o.replaces else { continue };
        let place = format!("objects[{i}] ({}).replaces", o.name);
        if rep.object == o.name {
            return Err(ctx.invalid(&place, "an object cannot replace itself"));
        }
        let target = objects.iter_mut().find(|t| t.name == rep.object).ok_or_else(|| {
            SceneError::invalid(
                &ctx.path,
                &place,
                unknown("object", &rep.object, file.objects.iter().map(|o| o.name.as_str())),
            )
        })?;
        for g in &rep.groups {
            let k = target.mesh.groups.iter().position(|x| &x.name == g).ok_or_else(|| {
                SceneError::invalid(
                    &ctx.path,
                    &place,
                    unknown("mesh part", g, target.mesh.groups.iter().map(|x| x.name.as_str())),
                )
            })?;
            target.hidden_groups[k] = true;
        }
    }

    // Camera.
    let c = &file.camera;
    if c.width == 0 || c.height == 0 {
        return Err(ctx.invalid("camera", "width and height must be at least 1 pixel"));
    }
    let pixels = u64::from(c.width) * u64::from(c.height);
    if pixels > limits.max_pixels {
        return Err(limit(
            "the image size (pixels)",
            pixels,
            limits.max_pixels,
            "render smaller, or raise the limit with --max-pixels",
        ));
    }
    let camera = match &c.viewpoint {
        Some(vp) => {
            let (list, matrix) = viewpoints.get(&vp.object).ok_or_else(|| {
                ctx.invalid(
                    "camera.viewpoint",
                    unknown("object", &vp.object, file.objects.iter().map(|o| o.name.as_str())),
                )
            })?;
            let v = match &vp.name {
                Some(name) => list.iter().find(|v| &v.description == name).ok_or_else(|| {
                    ctx.invalid(
                        "camera.viewpoint.name",
                        unknown("viewpoint", name, list.iter().map(|v| v.description.as_str())),
                    )
                })?,
                None => list.get(vp.index).ok_or_else(|| {
                    ctx.invalid(
                        "camera.viewpoint",
                        format!(
                            "object `{}` has {} viewpoints; index {} does not exist",
                            vp.object,
                            list.len(),
                            vp.index
                        ),
                    )
                })?,
            };
            // VRML and glTF view along −Z with +Y up, turned by the viewpoint's orientation.
            let (axis, angle) = v.orientation;
            let rot = DMat3::from_axis_angle(
                DVec3::from_array(axis.map(f64::from)).normalize_or(DVec3::Y),
                f64::from(angle),
            );
            let pos = DVec3::from_array(v.position);
            let look = rot * DVec3::NEG_Z;
            let up = rot * DVec3::Y;
            let to_world = |p: DVec3| matrix.transform_point3(p);
            let position = to_world(pos);
            ResolvedCamera {
                position: position.to_array(),
                target: to_world(pos + look).to_array(),
                up: matrix.transform_vector3(up).normalize_or(DVec3::Z).to_array(),
                vertical_fov_deg: f64::from(v.field_of_view).to_degrees(),
                width: c.width,
                height: c.height,
            }
        }
        None => {
            let (Some(position), Some(target)) = (c.position, c.target) else {
                return Err(ctx.invalid("camera", "give position and target, or a viewpoint"));
            };
            ResolvedCamera {
                position,
                target,
                up: c.up,
                vertical_fov_deg: c.vertical_fov_deg,
                width: c.width,
                height: c.height,
            }
        }
    };
    check_pose(&ctx, "camera", &camera)?;
    check_views(&ctx, &file.views)?;

    // Lights.
    if file.lights.is_empty() {
        return Err(ctx.invalid("lights", "the scene has no light; add a sun or a luminaire"));
    }
    let mut lights = Vec::new();
    for (i, l) in file.lights.iter().enumerate() {
        let place = format!("lights[{i}]");
        let resolved = match l {
            Light::Point { position, intensity_cd, flux_lm, spectrum, ies, aim } => {
                ctx.emission(spectrum, &format!("{place}.spectrum"))?;
                let photometry = photometry(&ctx, ies, &format!("{place}.ies"))?;
                let given = given_intensity(&ctx, &place, *intensity_cd, *flux_lm, || {
                    lumens_per_cd(photometry.as_ref(), 4.0 * std::f64::consts::PI)
                })?;
                let intensity_cd =
                    luminaire_intensity(&mut ctx, &place, given, photometry.as_ref())?;
                check_luminaire(&ctx, &place, *position, intensity_cd, *aim)?;
                ResolvedLight::Point {
                    position: *position,
                    intensity_cd,
                    spectrum: spectrum.clone(),
                    photometry,
                    aim: *aim,
                }
            }
            Light::Area { corner, u, v, normal, luminance_cd_m2, flux_lm, spectrum } => {
                ctx.emission(spectrum, &format!("{place}.spectrum"))?;
                let panel = crate::area_light::Panel::new(*corner, *u, *v, *normal)
                    .map_err(|(field, problem)| ctx.invalid(format!("{place}.{field}"), problem))?;
                let luminance_cd_m2 =
                    crate::area_light::luminance(&panel, *luminance_cd_m2, *flux_lm).map_err(
                        |(field, problem)| ctx.invalid(format!("{place}{field}"), problem),
                    )?;
                ResolvedLight::Area { panel, luminance_cd_m2, spectrum: spectrum.clone() }
            }
            Light::Spot {
                position,
                intensity_cd,
                flux_lm,
                spectrum,
                aim,
                cone_deg,
                falloff_deg,
                ies,
            } => {
                if !(cone_deg.is_finite()
                    && *cone_deg > 0.0
                    && falloff_deg.is_finite()
                    && *falloff_deg >= 0.0
                    && cone_deg + falloff_deg <= 180.0)
                {
                    return Err(ctx.invalid(
                        &place,
                        "cone_deg must be > 0 and falloff_deg ≥ 0, their sum at most 180",
                    ));
                }
                ctx.emission(spectrum, &format!("{place}.spectrum"))?;
                let photometry = photometry(&ctx, ies, &format!("{place}.ies"))?;
                let given = given_intensity(&ctx, &place, *intensity_cd, *flux_lm, || {
                    lumens_per_cd(photometry.as_ref(), spot_lumens_per_cd(*cone_deg, *falloff_deg))
                })?;
                let intensity_cd =
                    luminaire_intensity(&mut ctx, &place, given, photometry.as_ref())?;
                check_luminaire(&ctx, &place, *position, intensity_cd, Some(*aim))?;
                ResolvedLight::Spot {
                    position: *position,
                    intensity_cd,
                    spectrum: spectrum.clone(),
                    aim: *aim,
                    cone_deg: *cone_deg,
                    falloff_deg: *falloff_deg,
                    photometry,
                }
            }
            Light::Sun { illuminance_lux, preset, azimuth_deg, elevation_deg, site, spectrum } => {
                ctx.emission(spectrum, &format!("{place}.spectrum"))?;
                let lux = match (illuminance_lux, preset) {
                    (Some(_), Some(_)) => {
                        return Err(
                            ctx.invalid(&place, "give illuminance_lux or a preset, not both")
                        );
                    }
                    (Some(e), None) => *e,
                    (None, Some(SunPreset::Sun)) => 100_000.0,
                    (None, Some(SunPreset::Cloudy)) => 10_000.0,
                    (None, Some(SunPreset::FullMoon)) => 0.2,
                    (None, None) => return Err(ctx.invalid(
                        &place,
                        "give illuminance_lux, or preset = \"sun\", \"cloudy\" or \"full-moon\"",
                    )),
                };
                check_illuminance(&ctx, &place, lux)?;
                let position = match (azimuth_deg, elevation_deg, site) {
                    (Some(_), _, Some(_)) | (_, Some(_), Some(_)) => {
                        return Err(ctx.invalid(
                            &place,
                            "give azimuth/elevation or a site and date-time, not both",
                        ));
                    }
                    (None, None, Some(s)) => {
                        let site = Site::new(s.latitude_deg, s.longitude_deg, s.height_m);
                        sun_position(site, &s.datetime, None)
                            .map_err(|e| ctx.invalid(format!("{place}.site"), e))?
                    }
                    (az, el, None) => {
                        // The paper's sun preset stands 50° above the horizon; due south
                        // unless an azimuth is given.
                        let el = el.or((*preset == Some(SunPreset::Sun)).then_some(50.0));
                        let az = az.or(el.map(|_| 180.0));
                        match (az, el) {
                            (Some(az), Some(el)) if az.is_finite() && el.is_finite() && (-90.0..=90.0).contains(&el) => SunPosition { azimuth_deg: az, elevation_deg: el },
                            (Some(az), Some(_)) if !az.is_finite() => return Err(ctx.invalid(format!("{place}.azimuth_deg"), format!("{az} is not a direction; give degrees from north towards east (0 north, 90 east, 180 south)"))),
                            (Some(_), Some(el)) => return Err(ctx.invalid(format!("{place}.elevation_deg"), format!("{el} is out of range; use −90 to 90 degrees"))),
                            _ => return Err(ctx.invalid(&place, "give azimuth_deg and elevation_deg, or a site with latitude, longitude and date-time")),
                        }
                    }
                };
                if position.elevation_deg <= 0.0 {
                    // A moment after sunset is a real question (the facade at dusk): that sun
                    // lights nothing, and the other lights still do. A direction given below
                    // the horizon is a slip, and refused.
                    let Some(s) = site else {
                        return Err(ctx.invalid(
                            &place,
                            format!(
                                "the sun is below the horizon (elevation {:.2}°, azimuth {:.2}°); choose a daytime date-time or a positive elevation",
                                position.elevation_deg, position.azimuth_deg
                            ),
                        ));
                    };
                    ctx.notes.push(format!(
                        "{place}: at {} the sun is below the horizon (elevation {:.2}°, azimuth {:.2}°): it lights nothing, the other lights still do",
                        s.datetime, position.elevation_deg, position.azimuth_deg
                    ));
                    continue;
                }
                ResolvedLight::Sun {
                    direction: direction_to_sun(position),
                    azimuth_deg: position.azimuth_deg,
                    elevation_deg: position.elevation_deg,
                    illuminance_lux: lux,
                    spectrum: spectrum.clone(),
                }
            }
            Light::Sky { illuminance_lux, preset, model, spectrum, .. } => {
                let spectrum = &sky_spectrum(&mut ctx, spectrum)?;
                ctx.emission(spectrum, &format!("{place}.spectrum"))?;
                let (lux, preset_model) = match (illuminance_lux, preset) {
                    (Some(_), Some(_)) => {
                        return Err(
                            ctx.invalid(&place, "give illuminance_lux or a preset, not both")
                        );
                    }
                    (Some(e), None) => (*e, SkyModel::CieOvercast),
                    (None, Some(SkyPreset::Overcast)) => (10_000.0, SkyModel::CieOvercast),
                    (None, Some(SkyPreset::Clear)) => (15_000.0, SkyModel::Uniform),
                    (None, None) => {
                        return Err(ctx.invalid(
                            &place,
                            "give illuminance_lux, or preset = \"overcast\" or \"clear\"",
                        ));
                    }
                };
                check_illuminance(&ctx, &place, lux)?;
                // The general sky's sun and the ground are settled once every light is
                // resolved (`crate::sky_shape`): the scene's sun may come after the sky.
                ResolvedLight::Sky {
                    illuminance_lux: lux,
                    model: model.unwrap_or(preset_model),
                    spectrum: spectrum.clone(),
                    general: None,
                    ground_cd_m2: 0.0,
                }
            }
        };
        lights.push(resolved);
    }
    if lights.is_empty() {
        return Err(ctx.invalid(
            "lights",
            "the sun is below the horizon at that time and the scene has no other light; \
             choose a daytime date-time, or add a sky or a luminaire",
        ));
    }
    if file.lights.iter().filter(|l| matches!(l, Light::Sky { .. })).count() > 1 {
        return Err(ctx.invalid(
            "lights",
            "more than one sky; a scene has one sky dome (give its total illuminance_lux)",
        ));
    }
    crate::sky_shape::settle(&ctx.path, &file.lights, &mut lights)?;

    check_annotations(&ctx, &file, &objects)?;
    let grids = crate::grid::resolve_grids(&ctx.path, &file.grids)?;

    // Variants.
    let states = ["base", "degraded", "cleaned"];
    for (name, v) in &file.variants {
        let place = format!("variants.{name}");
        let check_state = |s: &str| -> Result<()> {
            if states.contains(&s) {
                Ok(())
            } else {
                Err(SceneError::invalid(
                    &ctx.path,
                    &place,
                    format!("unknown state `{s}`; use base, degraded or cleaned"),
                ))
            }
        };
        check_state(&v.state)?;
        for (key, state) in &v.states {
            check_state(state)?;
            check_part(&ctx, &place, &objects, key)?;
        }
        // Materials asked for a state they do not have keep their base state; say so.
        let mut lacking = BTreeSet::new();
        for o in &objects {
            for (g, material) in o.mesh.groups.iter().zip(&o.group_materials) {
                let state = v.state_for(&o.name, &g.name);
                if !file.materials[material].has_state(state) {
                    lacking.insert(format!("{material} ({state})"));
                }
            }
        }
        if !lacking.is_empty() {
            ctx.notes.push(format!(
                "{place}: these materials have no such state and keep their base one: {}",
                lacking.into_iter().collect::<Vec<_>>().join(", ")
            ));
        }
    }

    let Ctx { notes, spectra, .. } = ctx;
    Ok(LoadedScene { camera, spectra, objects, lights, grids, notes, file, origin_m, textures })
}

/// The degradation maps: their images decoded (PNG only: a JPEG's compression would blur
/// the class colours), their rectangles, classes and spectra checked; and each material state
/// that names a map, checked against it.
fn check_maps(
    ctx: &mut Ctx,
    limits: &Limits,
    textures: &mut BTreeMap<String, std::sync::Arc<crate::formats::texture::Texture>>,
) -> Result<()> {
    let file = ctx.file;
    let mut names = BTreeSet::new();
    for (i, m) in file.maps.iter().enumerate() {
        let place = format!("maps[{i}] ({})", m.name);
        if !names.insert(m.name.as_str()) {
            return Err(ctx.invalid(place, "two maps have this name; names must be unique"));
        }
        let ext = extension(&m.image);
        if ext != "png" {
            return Err(ctx.invalid(
                format!("{place}.image"),
                format!("`{}`: a map must be a PNG image, whose class colours stay exact (a JPEG's compression blurs them)", m.image),
            ));
        }
        let bytes = ctx.assets.read(&m.image, &format!("{place}.image"))?;
        let shown = ctx.assets.display_path(&m.image);
        let texture = crate::formats::texture::decode(&bytes, &ext, &shown, limits.max_pixels)?;
        textures.insert(m.image.clone(), std::sync::Arc::new(texture));
        let (u, v) = (DVec3::from_array(m.u), DVec3::from_array(m.v));
        if !(finite3(m.corner) && finite3(m.u) && finite3(m.v)) || u.cross(v).length() < 1e-9 {
            return Err(ctx.invalid(
                &place,
                "`corner`, `u` and `v` must be finite, and `u` and `v` edges of a rectangle (not zero, not parallel)",
            ));
        }
        if m.classes.is_empty() || m.classes.len() > MAX_MAP_CLASSES {
            return Err(ctx.invalid(
                format!("{place}.classes"),
                format!("a map needs 1 to {MAX_MAP_CLASSES} classes; it has {}", m.classes.len()),
            ));
        }
        for (k, c) in m.classes.iter().enumerate() {
            let here = format!("{place}.classes[{k}] ({})", c.name);
            if m.classes[..k].iter().any(|o| o.name == c.name || o.colour == c.colour) {
                return Err(
                    ctx.invalid(here, "another class has this name or colour; each needs its own")
                );
            }
            ctx.reflectance(&c.spectrum, &format!("{here}.spectrum"))?;
        }
    }
    for (name, material) in &file.materials {
        for (state, o) in [("degraded", &material.degraded), ("cleaned", &material.cleaned)] {
            let Some(o) = o else { continue };
            let place = format!("materials.{name}.{state}");
            let map = match (&o.map, &o.classes) {
                (None, None) => continue,
                (None, Some(_)) => {
                    return Err(ctx.invalid(place, "`classes` needs the `map` they are classes of"));
                }
                (Some(map), _) => file.maps.iter().find(|m| &m.name == map).ok_or_else(|| {
                    ctx.invalid(
                        format!("{place}.map"),
                        unknown("map", map, file.maps.iter().map(|m| m.name.as_str())),
                    )
                })?,
            };
            for class in o.classes.iter().flatten() {
                if !map.classes.iter().any(|c| &c.name == class) {
                    return Err(ctx.invalid(
                        format!("{place}.classes"),
                        unknown("class", class, map.classes.iter().map(|c| c.name.as_str()))
                            .replace("the scene defines", &format!("map `{}` has", map.name)),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// A state's soiling: a reflectance for its deposit, its numbers in range.
fn check_soiling(ctx: &mut Ctx, place: &str, s: &crate::scene_file::Soiling) -> Result<()> {
    ctx.reflectance(&s.spectrum, &format!("{place}.spectrum"))?;
    let checks = [
        ("max_fraction", Some(s.max_fraction), 0.0, 1.0),
        ("rain_azimuth_deg", s.rain_azimuth_deg, -360.0, 360.0),
        ("rain_angle_deg", s.rain_angle_deg, 0.0, 80.0),
        ("sky_weight", s.sky_weight, 0.0, 10.0),
        ("rain_weight", s.rain_weight, 0.0, 10.0),
    ];
    for (key, value, low, high) in checks {
        if let Some(v) = value
            && !(v.is_finite() && (low..=high).contains(&v))
        {
            return Err(ctx.invalid(
                format!("{place}.{key}"),
                format!("{v} is out of range; use {low} to {high}"),
            ));
        }
    }
    Ok(())
}

/// Every material's photo textures (the base one and the states'), decoded once each.
fn load_textures(
    ctx: &Ctx,
    limits: &Limits,
) -> Result<BTreeMap<String, std::sync::Arc<crate::formats::texture::Texture>>> {
    let mut out: BTreeMap<String, std::sync::Arc<crate::formats::texture::Texture>> =
        BTreeMap::new();
    for (name, m) in &ctx.file.materials {
        let states = [("", m.texture.as_ref(), m.white_patch)].into_iter().chain(
            [("degraded", &m.degraded), ("cleaned", &m.cleaned)].map(|(st, o)| {
                let o = o.as_ref();
                (st, o.and_then(|o| o.texture.as_ref()), o.and_then(|o| o.white_patch))
            }),
        );
        for (state, reference, patch) in states {
            let at = match state {
                "" => format!("materials.{name}"),
                s => format!("materials.{name}.{s}"),
            };
            let Some(reference) = reference else {
                if patch.is_some() && !state.is_empty() {
                    return Err(ctx.invalid(
                        format!("{at}.white_patch"),
                        "the patch lies in the state's own photo, and it has none; give the \
                         state a `texture`, or put `white_patch` on the material",
                    ));
                }
                continue;
            };
            let place = format!("{at}.texture");
            if m.model == MaterialModel::Glass {
                return Err(
                    ctx.invalid(place, "glass takes no texture; give it to the stone behind")
                );
            }
            if let Some(texture) = out.get(reference) {
                check_white_patch(ctx, &at, texture, patch)?;
                continue;
            }
            let ext = extension(reference);
            if !crate::formats::texture::EXTENSIONS.contains(&ext.as_str()) {
                return Err(ctx.invalid(
                    place,
                    format!("`{reference}`: `.{ext}` is not an image restauro reads; use a PNG or JPEG file"),
                ));
            }
            let bytes = ctx.assets.read(reference, &place)?;
            let shown = ctx.assets.display_path(reference);
            let texture = crate::formats::texture::decode(&bytes, &ext, &shown, limits.max_pixels)?;
            check_white_patch(ctx, &at, &texture, patch)?;
            out.insert(reference.clone(), std::sync::Arc::new(texture));
        }
    }
    Ok(out)
}

/// A grey patch (`{at}.white_patch`) that white-balances `texture`, checked against it.
fn check_white_patch(
    ctx: &Ctx,
    at: &str,
    texture: &crate::formats::texture::Texture,
    patch: Option<scene_file::PixelRect>,
) -> Result<()> {
    let Some(patch) = patch else { return Ok(()) };
    texture.check_patch(patch).map_err(|problem| ctx.invalid(format!("{at}.white_patch"), problem))
}

/// An illuminance (sun or sky): finite, ≥ 0 and at most [`MAX_ILLUMINANCE_LUX`].
fn check_illuminance(ctx: &Ctx, place: &str, lux: f64) -> Result<()> {
    if !(lux.is_finite() && lux >= 0.0) {
        return Err(ctx.invalid(
            format!("{place}.illuminance_lux"),
            format!("{lux} is not a finite illuminance ≥ 0 lux"),
        ));
    }
    if lux > MAX_ILLUMINANCE_LUX {
        return Err(ctx.invalid(
            format!("{place}.illuminance_lux"),
            format!(
                "{lux:e} lux is more than the {MAX_ILLUMINANCE_LUX:e} lux restauro accepts (full \
                 sunlight is about 1e5 lux); give the illuminance in lux"
            ),
        ));
    }
    Ok(())
}

/// A luminaire's peak intensity (cd): the photometric file's own unless `intensity_cd`
/// overrides it (noted when it departs from the file by more than 1 %); without a file,
/// `intensity_cd` itself, which is then required.
/// The intensity a luminaire is given: `intensity_cd`, or `flux_lm` over the lumens one
/// candela of its distribution emits (`per_cd`), or neither (its photometric file's own).
fn given_intensity(
    ctx: &Ctx,
    place: &str,
    intensity_cd: Option<f64>,
    flux_lm: Option<f64>,
    per_cd: impl FnOnce() -> f64,
) -> Result<Option<f64>> {
    match (intensity_cd, flux_lm) {
        (Some(_), Some(_)) => Err(ctx
            .invalid(place, "give intensity_cd or flux_lm, not both (one follows from the other)")),
        (None, Some(lm)) if !(lm.is_finite() && (0.0..=1e10).contains(&lm)) => Err(ctx.invalid(
            format!("{place}.flux_lm"),
            format!("{lm} is not a luminous flux; give lumens from 0 to 1e10"),
        )),
        (None, Some(lm)) => {
            let per = per_cd();
            if per > 0.0 { Ok(Some(lm / per)) } else { Ok(Some(0.0)) }
        }
        (cd, None) => Ok(cd),
    }
}

/// The lumens a luminaire emits per candela of its peak: its photometric file's flux over its
/// peak, or `shape`'s (the lumens of one candela in the distribution without a file).
fn lumens_per_cd(photometry: Option<&Photometry>, shape: f64) -> f64 {
    match photometry {
        Some(p) if p.peak_cd() > 0.0 => p.flux_lm() / p.peak_cd(),
        Some(_) => 0.0,
        None => shape,
    }
}

/// The lumens of a spot of one candela inside its cone: Φ = 2π ∫ f(cos θ) d(cos θ), with f = 1
/// inside `cone_deg` and the smoothstep of the render between it and `cone_deg + falloff_deg`,
/// whose mean over the band is ½: 2π [(1 − cos θ_in) + ½ (cos θ_in − cos θ_out)].
fn spot_lumens_per_cd(cone_deg: f64, falloff_deg: f64) -> f64 {
    let inner = cone_deg.to_radians().cos();
    let outer = (cone_deg + falloff_deg.max(1e-3)).to_radians().cos();
    2.0 * std::f64::consts::PI * ((1.0 - inner) + 0.5 * (inner - outer))
}

fn luminaire_intensity(
    ctx: &mut Ctx,
    place: &str,
    intensity_cd: Option<f64>,
    photometry: Option<&Photometry>,
) -> Result<f64> {
    match (intensity_cd, photometry) {
        (None, Some(p)) => Ok(p.peak_cd()),
        (Some(cd), Some(p)) => {
            let peak = p.peak_cd();
            if cd.is_finite() && peak > 0.0 && (cd / peak - 1.0).abs() > 0.01 {
                ctx.notes.push(format!(
                    "{place}: intensity_cd = {cd} cd overrides the photometric file's peak of \
                     {peak:.1} cd (× {:.3}); leave intensity_cd out to render the luminaire as \
                     measured",
                    cd / peak
                ));
            }
            Ok(cd)
        }
        (Some(cd), None) => Ok(cd),
        (None, None) => Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            "a luminaire without a photometric file (ies) needs its intensity_cd (candela) or its flux_lm (lumens)",
        )),
    }
}

fn check_luminaire(
    ctx: &Ctx,
    place: &str,
    position: [f64; 3],
    intensity_cd: f64,
    aim: Option<[f64; 3]>,
) -> Result<()> {
    check_point(ctx, &format!("{place}.position"), position)?;
    if !(intensity_cd.is_finite() && intensity_cd >= 0.0) {
        return Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            format!("{intensity_cd} is not a luminous intensity; give candela ≥ 0"),
        ));
    }
    if intensity_cd > MAX_INTENSITY_CD {
        return Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            format!(
                "{intensity_cd:e} cd is more than the {MAX_INTENSITY_CD:e} cd restauro accepts (the \
                 brightest searchlights reach about 1e9 cd); give the luminaire's intensity in \
                 candela"
            ),
        ));
    }
    if let Some(a) = aim {
        check_point(ctx, &format!("{place}.aim"), a)?;
        if (DVec3::from_array(a) - DVec3::from_array(position)).length() < 1e-9 {
            return Err(ctx
                .invalid(format!("{place}.aim"), "the aim point is the luminaire's own position"));
        }
    }
    Ok(())
}
