//! From a scene file to a validated scene: every number checked to be finite and in range, every
//! name resolved (with the nearest names suggested when one is not), every file read through
//! [`Assets`] (so inside the scene's folder), meshes imported and placed in the world, lights
//! resolved (the sun's position computed), and the limits that protect the machine enforced.
//! Nothing renders until all of it has passed.
//!
//! One file here checks one table of the scene file; [`load`] calls them in a fixed order
//! (origin, render settings, spectra, materials, textures, maps, objects, camera, views, lights,
//! annotations, grids, variants), so that the first error a bad file reports stays the same.

mod annotations;
mod camera;
mod lights;
mod maps;
mod materials;
mod objects;
mod render;
mod scene_text;
mod sky_shape;
mod spectra;
mod textures;
mod variants;

use crate::assets::Assets;
use crate::error::{Result, SceneError};
use crate::scene_file::SceneFile;
use restauro_spectral::Spectrum;
use std::collections::BTreeMap;
use std::path::PathBuf;

pub use self::camera::ResolvedCamera;
pub use self::lights::ResolvedLight;
pub use self::objects::LoadedObject;
pub use self::scene_text::{
    MAX_TOML_NESTING, load_folder, open_folder, parse_scene, read_scene_file,
};
pub use self::spectra::DEFAULT_SKY_SPECTRUM;
pub use crate::limits::{
    Limits, MAX_COORDINATE_M, MAX_ILLUMINANCE_LUX, MAX_INTENSITY_CD, MAX_MAP_CLASSES,
};

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
    pub textures: BTreeMap<String, std::sync::Arc<crate::texture::Texture>>,
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
            position_m: self.camera.pose.position,
            vertical_fov_deg: self.camera.pose.vertical_fov_deg,
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

/// Validate and resolve a parsed scene, reading its files through `assets`.
pub fn load(file: SceneFile, assets: &dyn Assets, limits: &Limits) -> Result<LoadedScene> {
    check_origin(&file, assets)?;
    let (file, origin_m) = crate::origin::recentre(file);
    let mut ctx = Ctx {
        path: assets.scene_path().to_owned(),
        file: &file,
        assets,
        notes: Vec::new(),
        spectra: BTreeMap::new(),
        spectrum_max: BTreeMap::new(),
    };
    render::check_render(&ctx, limits)?;
    spectra::check_spectra(&mut ctx)?;
    materials::check_materials(&mut ctx)?;
    let mut textures = textures::load_textures(&ctx, limits)?;
    maps::check_maps(&mut ctx, limits, &mut textures)?;
    let (objects, viewpoints) = objects::load_objects(&mut ctx, limits)?;
    let camera = camera::resolve_camera(&ctx, limits, &viewpoints)?;
    camera::check_views(&ctx, &file.views)?;
    let lights = lights::resolve_lights(&mut ctx)?;
    annotations::check_annotations(&ctx, &file, &objects)?;
    let grids = crate::grid::resolve_grids(&ctx.path, &file.grids)?;
    variants::check_variants(&mut ctx, &objects)?;

    let Ctx { notes, spectra, .. } = ctx;
    Ok(LoadedScene { camera, spectra, objects, lights, grids, notes, file, origin_m, textures })
}

/// The scene's `origin`, checked before the scene is recentred on it: every coordinate
/// finite and within [`MAX_COORDINATE_M`].
fn check_origin(file: &SceneFile, assets: &dyn Assets) -> Result<()> {
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
    Ok(())
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

/// What every check shares: the scene file's path (for messages), the file, where its files
/// are read from, the notes gathered so far and the spectra resolved so far.
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

    /// A limit that protects the machine, not kept: `what` is `value` where the limit is
    /// `limit`; `fix` says what to do.
    fn limit(&self, what: &str, value: u64, limit: u64, fix: &str) -> SceneError {
        SceneError::Limit {
            path: self.path.clone(),
            what: what.to_owned(),
            value,
            limit,
            fix: fix.to_owned(),
        }
    }
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
