//! What the page draws in real time: a scene's geometry as GLB ([`gltf_export`]), each
//! material coloured as restauro computes it from its reflectance spectrum (under CIE D65,
//! 2° observer, as linear sRGB: CIE 15:2004 Eqs. 7.1–7.3, IEC 61966-2-1), and the scene's
//! camera, in the GLB's coordinates. Kept for the few scenes opened last, by bundle identity.

use crate::error::Result;
use crate::farm::Farm;
use restauro_scene::gltf_export::{self, Preview};
use restauro_scene::load::LoadedScene;
use restauro_spectral::Lab;
use restauro_spectral::Spectrum;
use restauro_spectral::colorimetry::{Observer, relative_xyz, white_point};
use restauro_spectral::illuminant::Illuminant;
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::sync::{Arc, Mutex};

/// Previews kept at once.
const KEPT: usize = 4;

#[derive(Serialize)]
pub struct MaterialView {
    pub name: String,
    /// `lambert` or `cook-torrance`.
    pub model: String,
    pub roughness: Option<f64>,
    pub reflectance: String,
    /// Linear sRGB, 0–1, under D65.
    pub colour_linear_srgb: [f32; 3],
    /// Its surface in each state it has: `base`, and `degraded` and `cleaned` when defined.
    pub states: Vec<StateView>,
}

/// One state of a material: its reflectance, sampled, and its colour under D65.
#[derive(Serialize)]
pub struct StateView {
    pub state: &'static str,
    pub spectrum: String,
    /// ρ(λ) at 380, 385, … 780 nm.
    pub reflectance: Vec<f32>,
    /// CIE 1976 L*a*b* under D65 (2° observer), D65 white.
    pub lab: [f64; 3],
    pub colour_linear_srgb: [f32; 3],
}

/// The wavelengths of `StateView::reflectance`, in nm.
pub const FIRST_NM: f64 = 380.0;
pub const STEP_NM: f64 = 5.0;

fn state_view(state: &'static str, spectrum: &str, scene: &LoadedScene) -> Option<StateView> {
    let rho = scene.spectra.get(spectrum)?;
    let d65 = Illuminant::D65.spd().unwrap_or(Spectrum::ONE);
    let xyz = relative_xyz(rho, &d65, Observer::Cie1931TwoDegree);
    let lab = Lab::from_xyz(xyz, white_point(&d65, Observer::Cie1931TwoDegree));
    Some(StateView {
        state,
        spectrum: spectrum.to_owned(),
        reflectance: rho.0.to_vec(),
        lab: [lab.l, lab.a, lab.b],
        colour_linear_srgb: colour(xyz),
    })
}

#[derive(Serialize)]
pub struct CameraView {
    /// In the GLB's coordinates (Y up, offset removed).
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub vertical_fov_deg: f64,
    pub width: u32,
    pub height: u32,
}

#[derive(Serialize)]
pub struct SceneView {
    pub id: String,
    pub offset_m: [f64; 3],
    pub triangles: usize,
    pub camera: CameraView,
    pub materials: Vec<MaterialView>,
    /// The scene's hypotheses (variants), by name.
    pub variants: Vec<String>,
    pub notes: Vec<String>,
}

pub struct ScenePreview {
    pub view: SceneView,
    pub glb: Vec<u8>,
}

/// The linear-sRGB colour of relative tristimulus values (Y = 100 for white), clipped to the
/// gamut.
fn colour(xyz: restauro_spectral::Xyz) -> [f32; 3] {
    RgbSpace::Srgb.linear_from_xyz(xyz.scale(0.01)).map(|v| v.clamp(0.0, 1.0) as f32)
}

/// World (Z up) to the GLB's frame (Y up), relative to `offset`.
fn to_glb(p: [f64; 3], offset: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = std::array::from_fn(|k| p[k] - offset[k]);
    [x, z, -y]
}

/// The GLB's frame back to the world: the inverse of [`to_glb`].
pub fn to_world(p: [f64; 3], offset: [f64; 3]) -> [f64; 3] {
    [p[0] + offset[0], -p[2] + offset[1], p[1] + offset[2]]
}

/// The spectrum a state of `m` reflects with, when the state changes it.
fn state_spectrum<'a>(
    m: &'a restauro_scene::scene_file::Material,
    state: &str,
) -> Option<&'a String> {
    m.state(state)?.reflectance.as_ref()
}

fn build(id: &str, scene: &LoadedScene) -> ScenePreview {
    let materials: Vec<MaterialView> = scene
        .file
        .materials
        .iter()
        .map(|(name, m)| {
            let states: Vec<StateView> = [
                ("base", Some(&m.reflectance)),
                ("degraded", state_spectrum(m, "degraded")),
                ("cleaned", state_spectrum(m, "cleaned")),
            ]
            .into_iter()
            .filter_map(|(state, spectrum)| state_view(state, spectrum?, scene))
            .collect();
            MaterialView {
                name: name.clone(),
                model: serde_json::to_value(m.model)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_owned))
                    .unwrap_or_default(),
                roughness: m.roughness,
                reflectance: m.reflectance.clone(),
                // The base state comes first whenever its spectrum is loaded.
                colour_linear_srgb: states
                    .first()
                    .filter(|s| s.state == "base")
                    .map_or([0.5; 3], |s| s.colour_linear_srgb),
                states,
            }
        })
        .collect();
    let Preview { glb, offset_m, triangles } = gltf_export::scene_glb(scene, |name| {
        materials.iter().find(|m| m.name == name).map_or([0.5; 3], |m| m.colour_linear_srgb)
    });
    let c = &scene.camera;
    let camera = CameraView {
        position: to_glb(c.position, offset_m),
        target: to_glb(c.target, offset_m),
        up: to_glb(c.up, [0.0; 3]),
        vertical_fov_deg: c.vertical_fov_deg,
        width: c.width,
        height: c.height,
    };
    let view = SceneView {
        id: id.to_owned(),
        offset_m,
        triangles,
        camera,
        materials,
        variants: scene.file.variants.keys().cloned().collect(),
        notes: scene.notes.clone(),
    };
    ScenePreview { view, glb }
}

/// The last few previews.
#[derive(Default)]
pub struct Previews {
    kept: Mutex<Vec<(String, Arc<ScenePreview>)>>,
}

impl Previews {
    pub async fn get(&self, farm: &Arc<Farm>, id: &str) -> Result<Arc<ScenePreview>> {
        if let Some(p) = self.lock().iter().find(|(k, _)| k == id) {
            return Ok(p.1.clone());
        }
        let scene = farm.load_scene(id).await?;
        let (key, id) = (id.to_owned(), id.to_owned());
        let preview = tokio::task::spawn_blocking(move || Arc::new(build(&id, &scene)))
            .await
            .map_err(|e| crate::error::CoordinatorError::Internal(e.to_string()))?;
        let mut kept = self.lock();
        kept.retain(|(k, _)| *k != key);
        if kept.len() == KEPT {
            kept.remove(0);
        }
        kept.push((key, preview.clone()));
        Ok(preview)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(String, Arc<ScenePreview>)>> {
        self.kept.lock().unwrap_or_else(|p| p.into_inner())
    }
}
