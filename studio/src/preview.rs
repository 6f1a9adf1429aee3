//! What the page draws in real time: a scene's geometry as GLB ([`gltf_export`]), each
//! material coloured as restauro computes it from its reflectance spectrum under each of the
//! scene's lights and D65 ([`appearance`]), and the scene's camera, in the GLB's coordinates. Kept for the few scenes opened last, by
//! bundle identity.

use super::appearance::{self, appearance};
use crate::error::Result;
use crate::gltf_export::{self, Preview};
use restauro_farm::farm::{Farm, Revised};
use restauro_scene::load::{LoadedScene, ResolvedCamera};
use restauro_scene::scene_file::{Pose, View};
use serde::Serialize;
use std::sync::Arc;

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
    /// Its L*a*b* and colour under each light of [`SceneView::preview_lights`], by key.
    pub under: std::collections::BTreeMap<String, appearance::Look>,
}

/// The wavelengths of `StateView::reflectance`, in nm.
pub const FIRST_NM: f64 = 380.0;
pub const STEP_NM: f64 = 5.0;

/// A state's view; a state soiled by exposure shows its deposit at half its most, as a typical
/// share (the render places it where the weather leaves it).
fn state_view(
    state: &'static str,
    spectrum: &str,
    soiling: Option<&restauro_scene::scene_file::Soiling>,
    scene: &LoadedScene,
    lights: &[appearance::Light],
) -> Option<StateView> {
    let own = scene.spectra.get(spectrum)?;
    let rho = &match soiling {
        Some(s) => {
            let deposit = scene.spectra.get(&s.spectrum)?;
            let share = (s.max_fraction / 2.0) as f32;
            restauro_spectral::Spectrum(std::array::from_fn(|i| {
                own.0[i] + share * (deposit.0[i] - own.0[i])
            }))
        }
        None => *own,
    };
    let under = appearance::Light::looks(rho, lights);
    // D65 is among the lights: its look is the state's own colour.
    let (lab, colour_linear_srgb) = under
        .get(appearance::D65_KEY)
        .map_or_else(|| appearance(rho), |l| (l.lab, l.colour_linear_srgb));
    Some(StateView {
        state,
        spectrum: spectrum.to_owned(),
        reflectance: rho.0.to_vec(),
        lab,
        colour_linear_srgb,
        under,
    })
}

/// The scene's sun: where it is (as the render places it) and the site and time it was put
/// at, when it was.
#[derive(Serialize)]
pub struct SunView {
    /// Unit vector towards the sun, in the GLB's coordinates.
    pub direction: [f64; 3],
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    /// On a surface normal to the sun.
    pub illuminance_lux: f64,
    pub site: Option<restauro_scene::scene_file::SiteTime>,
}

/// The scene's sun as the render has it; a sun placed after sunset lights nothing and is not
/// among the render's lights, so its position is worked out from its site here, the same way.
fn sun_view(scene: &LoadedScene) -> Option<SunView> {
    use restauro_scene::load::ResolvedLight;
    use restauro_scene::scene_file::Light;
    use restauro_scene::sun::{Site, direction_to_sun, sun_position};
    let site = scene.file.lights.iter().find_map(|l| match l {
        Light::Sun { site, .. } => Some(site.clone()),
        _ => None,
    })?;
    let resolved = scene.lights.iter().find_map(|l| match l {
        ResolvedLight::Sun { direction, azimuth_deg, elevation_deg, illuminance_lux, .. } => {
            Some((*direction, *azimuth_deg, *elevation_deg, *illuminance_lux))
        }
        _ => None,
    });
    let (direction, azimuth_deg, elevation_deg, illuminance_lux) = match (resolved, &site) {
        (Some(r), _) => r,
        (None, Some(s)) => {
            let at = Site::new(s.latitude_deg, s.longitude_deg, s.height_m);
            let p = sun_position(at, &s.datetime, None).ok()?;
            (direction_to_sun(p), p.azimuth_deg, p.elevation_deg, 0.0)
        }
        (None, None) => return None,
    };
    Some(SunView {
        direction: to_glb(direction, [0.0; 3]),
        azimuth_deg,
        elevation_deg,
        illuminance_lux,
        site,
    })
}

/// A light of the scene: as the file holds it (the page's form shows and sends this), and for a
/// luminaire where it is and what it aims at in the GLB's coordinates, the intensity rendered,
/// and, shaped by a file, its flux, beam angle and photometric solid.
#[derive(Serialize)]
pub struct LightView {
    /// Its place among the file's `[[lights]]`, from 0.
    pub index: usize,
    pub light: restauro_scene::scene_file::Light,
    pub position: Option<[f64; 3]>,
    pub aim: Option<[f64; 3]>,
    /// A luminaire's peak intensity as rendered, cd.
    pub intensity_cd: Option<f64>,
    pub flux_lm: Option<f64>,
    pub beam_angle_deg: Option<f64>,
    /// An area light's corners in the GLB's frame: corner, + u, + u + v, + v.
    pub corners: Option<[[f64; 3]; 4]>,
    /// The photometric solid: for γ = 0, 5, … 180° (rows) and C = 0, 10, … 350° (columns), the
    /// direction (GLB, unit) times I(C, γ) / I_peak.
    pub solid: Option<Vec<[f32; 3]>>,
    /// A sky's diffuse horizontal illuminance (lux) and model, as rendered.
    pub illuminance_lux: Option<f64>,
    pub model: Option<String>,
}

/// The rows and columns of [`LightView::solid`].
pub const SOLID_GAMMA_STEP_DEG: usize = 5;
pub const SOLID_C_STEP_DEG: usize = 10;

fn solid(
    p: &restauro_scene::formats::photometric::Photometry,
    frame: [[f64; 3]; 3],
) -> Vec<[f32; 3]> {
    let peak = p.peak_cd().max(1e-12);
    let mut out = Vec::new();
    for g in (0..=180).step_by(SOLID_GAMMA_STEP_DEG) {
        for c in (0..360).step_by(SOLID_C_STEP_DEG) {
            let (gamma, c_rad) = ((g as f64).to_radians(), (c as f64).to_radians());
            // In the frame: γ from the nadir (−z), C from +x towards +y.
            let local = [gamma.sin() * c_rad.cos(), gamma.sin() * c_rad.sin(), -gamma.cos()];
            let r = p.intensity_at(c as f64, g as f64) / peak;
            let world: [f64; 3] =
                std::array::from_fn(|k| (0..3).map(|i| frame[i][k] * local[i]).sum::<f64>() * r);
            out.push(to_glb(world, [0.0; 3]).map(|v| v as f32));
        }
    }
    out
}

fn light_views(scene: &LoadedScene, offset: [f64; 3]) -> Vec<LightView> {
    use restauro_scene::formats::photometric::luminaire_frame;
    use restauro_scene::load::ResolvedLight;
    use restauro_scene::scene_file::Light;
    // Luminaires resolve one to one and in order (a sun after sunset is left out, a luminaire
    // never is).
    let mut luminaires = scene
        .lights
        .iter()
        .filter(|l| matches!(l, ResolvedLight::Point { .. } | ResolvedLight::Spot { .. }));
    let mut panels = scene.lights.iter().filter(|l| matches!(l, ResolvedLight::Area { .. }));
    let sky = scene.lights.iter().find_map(|l| match l {
        ResolvedLight::Sky { illuminance_lux, model, .. } => {
            Some((*illuminance_lux, model.to_string()))
        }
        _ => None,
    });
    let mut out = Vec::new();
    for (index, light) in scene.file.lights.iter().enumerate() {
        let mut view = LightView {
            index,
            // As the file gives it: the page edits the file (a georeferenced scene's `origin`
            // back in).
            light: restauro_scene::origin::light_in_file(light, scene.origin_m),
            position: None,
            aim: None,
            intensity_cd: None,
            flux_lm: None,
            beam_angle_deg: None,
            solid: None,
            corners: None,
            illuminance_lux: None,
            model: None,
        };
        match light {
            Light::Point { .. } | Light::Spot { .. } => {
                let resolved = luminaires.next();
                view.flux_lm = resolved.and_then(ResolvedLight::flux_lm);
                let (position, intensity_cd, photometry, aim) = match resolved {
                    Some(ResolvedLight::Point {
                        position, intensity_cd, photometry, aim, ..
                    }) => (*position, *intensity_cd, photometry, *aim),
                    Some(ResolvedLight::Spot {
                        position, intensity_cd, photometry, aim, ..
                    }) => (*position, *intensity_cd, photometry, Some(*aim)),
                    _ => continue,
                };
                view.position = Some(to_glb(position, offset));
                view.aim = aim.map(|a| to_glb(a, offset));
                view.intensity_cd = Some(intensity_cd);
                if let Some(p) = photometry {
                    view.beam_angle_deg = Some(p.beam_angle_deg());
                    view.solid = Some(solid(p, luminaire_frame(position, aim)));
                }
            }
            Light::Sky { .. } => {
                if let Some((lux, model)) = &sky {
                    view.illuminance_lux = Some(*lux);
                    view.model = Some(model.clone());
                }
            }
            Light::Area { .. } => {
                let Some(resolved @ ResolvedLight::Area { panel, .. }) = panels.next() else {
                    continue;
                };
                let centre: [f64; 3] =
                    std::array::from_fn(|k| panel.corner[k] + 0.5 * (panel.u[k] + panel.v[k]));
                view.position = Some(to_glb(centre, offset));
                let at = |a: f64, b: f64| {
                    to_glb(
                        std::array::from_fn(|k| panel.corner[k] + a * panel.u[k] + b * panel.v[k]),
                        offset,
                    )
                };
                view.corners = Some([at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)]);
                view.flux_lm = resolved.flux_lm();
            }
            Light::Sun { .. } => {}
        }
        out.push(view);
    }
    out
}

/// The spectra a light may take: the scene's illuminants and those its lights use.
fn light_spectra(scene: &LoadedScene) -> Vec<String> {
    use restauro_scene::scene_file::{Light, SpectrumSource};
    let used = scene.file.lights.iter().map(|l| match l {
        Light::Point { spectrum, .. }
        | Light::Spot { spectrum, .. }
        | Light::Sun { spectrum, .. }
        | Light::Sky { spectrum, .. }
        | Light::Area { spectrum, .. } => spectrum.clone(),
    });
    let illuminants = scene
        .file
        .spectra
        .iter()
        .filter(|(_, source)| matches!(source, SpectrumSource::Illuminant { .. }))
        .map(|(name, _)| name.clone());
    // A sky without a spectrum of its own (D65) names none.
    let all: std::collections::BTreeSet<String> =
        used.chain(illuminants).filter(|name| !name.is_empty()).collect();
    all.into_iter().collect()
}

#[derive(Serialize)]
pub struct SceneView {
    pub id: String,
    /// The revision shown (0: as first submitted).
    pub revision: u32,
    /// The point of the scene file's coordinates (its `origin` included) that the GLB's zero
    /// stands for: [`to_world`] with it turns the page's positions into the file's.
    pub offset_m: [f64; 3],
    pub triangles: usize,
    /// The triangles of the coarser copy the page draws while the view moves (0: none).
    pub coarse_triangles: usize,
    /// The scene's camera, in the GLB's coordinates.
    pub camera: ResolvedCamera,
    pub materials: Vec<MaterialView>,
    /// The scene's hypotheses (variants).
    pub variants: Vec<VariantView>,
    /// The scene's saved views (`[[views]]`), in the GLB's coordinates.
    pub views: Vec<View>,
    /// Its notes (`[[annotations]]`), positions and poses in the GLB's coordinates.
    pub annotations: Vec<restauro_scene::scene_file::Annotation>,
    pub sun: Option<SunView>,
    /// Every light of the file, in its order.
    pub lights: Vec<LightView>,
    /// The calculation grids (`[[grids]]`), in the file's order.
    pub grids: Vec<super::grid_views::GridView>,
    pub light_spectra: Vec<String>,
    /// The lights the page may colour the materials under, the scene's own first.
    pub preview_lights: Vec<appearance::LightChoice>,
    pub notes: Vec<String>,
}

/// A hypothesis as the file holds it, and the state it gives every part of the model, so
/// that the page colours each part with that state's colour.
#[derive(Serialize)]
pub struct VariantView {
    pub name: String,
    pub state: String,
    pub states: std::collections::BTreeMap<String, String>,
    /// `object/part` → `base`, `degraded` or `cleaned`, as the render resolves it.
    pub parts: std::collections::BTreeMap<String, String>,
}

fn variant_views(scene: &LoadedScene) -> Vec<VariantView> {
    let parts = |variant: &restauro_scene::scene_file::Variant| {
        let mut out = std::collections::BTreeMap::new();
        for o in &scene.objects {
            for g in &o.mesh.groups {
                let state = variant.state_for(&o.name, &g.name);
                out.insert(format!("{}/{}", o.name, g.name), state.to_owned());
            }
        }
        out
    };
    let variants = &scene.file.variants;
    variants
        .iter()
        .map(|(name, v)| VariantView {
            name: name.clone(),
            state: v.state.clone(),
            states: v.states.clone(),
            parts: parts(v),
        })
        .collect()
}

pub struct ScenePreview {
    pub view: SceneView,
    pub glb: Vec<u8>,
}

/// The linear-sRGB colour of relative tristimulus values (Y = 100 for white), clipped to the
/// gamut.
/// World (Z up) to the GLB's frame (Y up), relative to `offset`.
fn to_glb(p: [f64; 3], offset: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = std::array::from_fn(|k| p[k] - offset[k]);
    [x, z, -y]
}

/// A pose in the GLB's frame (Y up, `offset` removed); `up` is a direction, not moved.
fn pose_to_glb(pose: &Pose, offset: [f64; 3]) -> Pose {
    Pose {
        position: to_glb(pose.position, offset),
        target: to_glb(pose.target, offset),
        up: to_glb(pose.up, [0.0; 3]),
        vertical_fov_deg: pose.vertical_fov_deg,
    }
}

/// The GLB's frame back to the world: the inverse of [`to_glb`].
pub fn to_world(p: [f64; 3], offset: [f64; 3]) -> [f64; 3] {
    [p[0] + offset[0], -p[2] + offset[1], p[1] + offset[2]]
}

/// A pose the page sends, in the world: the inverse of [`pose_to_glb`].
pub fn pose_to_world(pose: &Pose, offset: [f64; 3]) -> Pose {
    Pose {
        position: to_world(pose.position, offset),
        target: to_world(pose.target, offset),
        up: to_world(pose.up, [0.0; 3]),
        vertical_fov_deg: pose.vertical_fov_deg,
    }
}

/// The spectrum a state of `m` reflects with, when the state changes it.
fn state_spectrum<'a>(
    m: &'a restauro_scene::scene_file::Material,
    state: &str,
) -> Option<&'a String> {
    let o = m.state(state)?;
    // A state soiled by exposure changes the surface even with the base's spectrum.
    o.reflectance.as_ref().or(o.soiling.as_ref().map(|_| &m.reflectance))
}

fn build(id: &str, revision: u32, scene: &LoadedScene) -> ScenePreview {
    let lights = appearance::scene_lights(scene);
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
            .filter_map(|(state, spectrum)| {
                let soiling = m.state(state).and_then(|o| o.soiling.as_ref());
                state_view(state, spectrum?, soiling, scene, &lights)
            })
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
    let Preview { glb, offset_m, triangles, coarse_triangles } =
        gltf_export::scene_glb(scene, |name| {
            materials.iter().find(|m| m.name == name).map_or([0.5; 3], |m| m.colour_linear_srgb)
        });
    let camera = ResolvedCamera { pose: pose_to_glb(&scene.camera.pose, offset_m), ..scene.camera };
    let views = scene
        .file
        .views
        .iter()
        .map(|v| View::at(v.name.clone(), pose_to_glb(&v.pose(), offset_m)))
        .collect();
    let annotations = scene
        .file
        .annotations
        .iter()
        .map(|a| {
            let mut a = a.clone();
            a.position = to_glb(a.position, offset_m);
            a.pose = a.pose.map(|p| pose_to_glb(&p, offset_m));
            a
        })
        .collect();
    let view = SceneView {
        id: id.to_owned(),
        annotations,
        revision,
        views,
        sun: sun_view(scene),
        lights: light_views(scene, offset_m),
        grids: super::grid_views::grid_views(
            scene,
            |p| to_glb(p, offset_m),
            |d| to_glb(d, [0.0; 3]),
        ),
        light_spectra: light_spectra(scene),
        preview_lights: lights.iter().map(appearance::Light::choice).collect(),
        // The page's positions go back into the file: the scene's `origin` is part of it.
        offset_m: restauro_scene::origin::to_file(offset_m, scene.origin_m),
        triangles,
        coarse_triangles,
        camera,
        materials,
        variants: variant_views(scene),
        notes: scene.notes.clone(),
    };
    ScenePreview { view, glb }
}

/// The last few previews.
pub struct Previews {
    kept: restauro_farm::recent::Recent<String, Arc<ScenePreview>>,
}

impl Default for Previews {
    fn default() -> Self {
        Previews { kept: restauro_farm::recent::Recent::new(KEPT) }
    }
}

impl Previews {
    /// The preview of revision `revision` of scene `id` (the latest when `None`).
    pub async fn get(
        &self,
        farm: &Arc<Farm>,
        id: &str,
        revision: Option<u32>,
    ) -> Result<Arc<ScenePreview>> {
        let number = match revision {
            Some(n) => n,
            None => farm.scene_revision(id, None)?.0,
        };
        let key = format!("{id}@{number}");
        if let Some(p) = self.kept.get(&key) {
            return Ok(p);
        }
        let (number, scene) = farm.load_scene(id, Some(number)).await?;
        self.build_and_keep(id, number, scene).await
    }

    /// The preview of what an edit made: built from the scene the farm loaded to check the new
    /// revision, so that the edit loads it once; when the edit made none, the latest's.
    pub async fn revised(
        &self,
        farm: &Arc<Farm>,
        id: &str,
        revised: Revised,
    ) -> Result<Arc<ScenePreview>> {
        let number = revised.revision.number;
        match revised.scene {
            Some(scene) => self.build_and_keep(id, number, scene).await,
            None => self.get(farm, id, Some(number)).await,
        }
    }

    async fn build_and_keep(
        &self,
        id: &str,
        number: u32,
        scene: LoadedScene,
    ) -> Result<Arc<ScenePreview>> {
        let key = format!("{id}@{number}");
        let id = id.to_owned();
        let preview =
            tokio::task::spawn_blocking(move || Arc::new(build(&id, number, &scene))).await?;
        self.kept.keep(key, preview.clone());
        Ok(preview)
    }
}
