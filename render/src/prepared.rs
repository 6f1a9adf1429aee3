//! A scene prepared for tracing, once per job per process: every visible triangle in one
//! four-wide BVH ([`crate::bvh`]), each triangle's material resolved for the chosen restoration
//! hypothesis, every spectrum on the grid, every light turned into spectral terms.

use crate::bsdf::Bsdf;
use crate::bvh::{self, Bvh4};
use crate::camera::Camera;
use crate::degradation::ClassMap;
use crate::glass::Transmission;
use crate::light::{Distribution, Light, Panel};
use crate::material_detail::{MaterialDetails, Surface, own_detail};
use crate::sampler::Strata;
use crate::sky::Sky;
use crate::soiling::Soiling;
use crate::texture::{Detail, DetailPoint, LuminancePyramid, Pyramid, TexturedTriangle};
use crate::vertex_colour::{ColourPoint, VertexPalette};
use glam::Vec3A;
use obvhs::ray::Ray;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use restauro_scene::load::{LoadedObject, LoadedScene, ResolvedLight};
use restauro_scene::mesh::Mesh;
use restauro_scene::plan::Plan;
use restauro_scene::scene_file::{Integrator, MaterialModel, Transmittance};
use restauro_spectral::Spectrum;
use restauro_spectral::grid::BANDS;
use restauro_spectral::photometry::LuminousSpectrum;
use std::collections::BTreeMap;
use std::sync::Arc;

#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    #[error("unknown variant `{name}`; the scene defines {known}")]
    UnknownVariant { name: String, known: String },
    #[error("{0}")]
    Scene(String),
}

/// What the tracer needs of a render: the integrator and its numbers. A job's [`Plan`] gives it
/// ([`PreparedScene::for_plan`]); benchmarks and tests set it directly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub integrator: Integrator,
    pub samples_per_pixel: u32,
    pub max_depth: u32,
    pub seed: u64,
    /// Compute the scene's calculation grids rather than its camera's image (`Plan::grids`).
    pub grids: bool,
    /// Adaptive sampling's target (`crate::adaptive`): 0 takes every sample.
    pub noise_target: f32,
}

impl Settings {
    /// Whether pixels stop early by their own noise ([`crate::adaptive`]); never for grids.
    pub fn adaptive(&self) -> bool {
        self.noise_target > 0.0 && !self.grids
    }
}

/// A scene's own `[render]` table, for its camera's image: what tests and benchmarks render a
/// scene file with.
impl From<&restauro_scene::scene_file::Render> for Settings {
    fn from(render: &restauro_scene::scene_file::Render) -> Self {
        Self {
            integrator: render.integrator,
            samples_per_pixel: render.samples_per_pixel,
            max_depth: render.max_depth,
            seed: render.seed,
            grids: false,
            noise_target: render.noise_target,
        }
    }
}

impl From<&Plan> for Settings {
    fn from(plan: &Plan) -> Self {
        Self {
            integrator: plan.integrator,
            samples_per_pixel: plan.samples_per_pixel,
            max_depth: plan.max_depth,
            seed: plan.seed,
            grids: plan.grids,
            noise_target: plan.noise_target,
        }
    }
}

/// The most panes of glass a shadow ray passes through before it is taken as blocked.
const MAX_PANES: usize = 8;

pub struct PreparedScene {
    pub camera: Camera,
    pub settings: Settings,
    pub strata: Strata,
    bvh: Bvh4,
    /// Triangles in BVH order.
    triangles: Vec<RtTriangle>,
    normals: Vec<Vec3A>,
    /// Per triangle in BVH order, its index in `vertex_normals`, or [`FLAT`]; empty when no
    /// triangle has shading normals (most scenes: the facade's blocks are flat).
    smooth_of: Vec<u32>,
    /// The vertex normals of the triangles shaded smooth.
    vertex_normals: Vec<[Vec3A; 3]>,
    material_of: Vec<u32>,
    pub materials: Vec<Bsdf>,
    /// Per material, its photo texture as detail over its reflectance, if it has one.
    details: Vec<Option<Detail>>,
    /// Per triangle in BVH order, its index in `textured`, or [`FLAT`]; empty when no
    /// triangle carries a texture.
    texture_of: Vec<u32>,
    textured: Vec<TexturedTriangle>,
    /// The photos' pyramids, held once however many materials share one.
    pyramids: Vec<Pyramid>,
    /// Per triangle in BVH order, its index in `coloured`, or [`FLAT`]; empty when no
    /// triangle takes detail from vertex colours.
    coloured_of: Vec<u32>,
    /// Per coloured triangle, its corners' colours in `palette`.
    coloured: Vec<[u32; 3]>,
    palette: Option<Arc<VertexPalette>>,
    /// Per material, the degradation map its state shows, if any; empty when none has one.
    maps: Vec<Option<ClassMap>>,
    /// Per material, its state's exposure-driven soiling, if any; empty when none has one.
    soilings: Vec<Option<Soiling>>,
    pub lights: Vec<Light>,
    /// The sky, sampled over the hemisphere (at most one: the loader refuses two).
    pub sky: Option<Sky>,
    /// The sensors of every calculation grid, in the grids' order.
    pub sensors: Vec<Sensor>,
    /// The area luminaires (also in `lights`), for the rays that meet them.
    panels: Vec<Panel>,
    /// Whether any triangle is glass: shadow rays then pass through panes.
    has_glass: bool,
}

/// A sensor of a calculation grid: where the grids' irradiance is computed
/// ([`crate::sensor::irradiance_sum`]).
#[derive(Clone, Copy, Debug)]
pub struct Sensor {
    pub point: Vec3A,
    /// Unit; the side whose illuminance is computed.
    pub normal: Vec3A,
}

/// A triangle without shading normals in [`PreparedScene::smooth_of`].
const FLAT: u32 = u32::MAX;

/// What a hit's triangle gives its material detail from: its index in
/// [`PreparedScene::textured`] or in [`PreparedScene::coloured`].
#[derive(Clone, Copy)]
enum On {
    Photo(u32),
    Colours(u32),
}

/// A surface hit.
pub struct Hit {
    pub t: f32,
    /// Where rays leave the surface from: the hit itself, or on a triangle with shading normals
    /// the point moved out to the smooth surface those normals describe ([`terminator_point`]).
    pub point: Vec3A,
    /// The geometric normal, turned to face the incoming ray.
    pub normal: Vec3A,
    /// The shading normal, on the same side: the vertex normals interpolated at the hit, or
    /// the geometric normal on a flat triangle.
    pub shading: Vec3A,
    pub material: u32,
    /// Where the hit falls on its material's photo or vertex colours, on a triangle with
    /// either.
    pub detail: Option<DetailPoint>,
}

impl PreparedScene {
    /// The scene prepared for a plan: its variant, integrator, samples, depth and seed. The
    /// worker and `restauro render --in-process` both prepare a job this way.
    pub fn for_plan(scene: &LoadedScene, plan: &Plan) -> Result<Self, TraceError> {
        Self::new(scene, plan.variant.as_deref(), Settings::from(plan))
    }

    pub fn new(
        scene: &LoadedScene,
        variant: Option<&str>,
        settings: Settings,
    ) -> Result<Self, TraceError> {
        check_variant(scene, variant)?;
        let Gathered {
            materials,
            material_states,
            details,
            tris,
            material_of,
            smooth,
            textured,
            coloured,
            ..
        } = Gathered::from_scene(scene, variant);
        if tris.is_empty() {
            return Err(TraceError::Scene("nothing to render: every part is hidden".into()));
        }
        let (bvh, triangles, normals) = build_bvh(&tris);
        // Triangles in BVH order, so a hit's slot indexes them directly.
        let order = &bvh.primitive_indices;
        let material_of: Vec<u32> = order.iter().map(|&i| material_of[i as usize]).collect();
        let (smooth_of, vertex_normals) = in_bvh_order(&smooth, order);
        let (texture_of, textured) = in_bvh_order(&textured, order);
        let (coloured_of, coloured) = in_bvh_order(&coloured, order);
        let (details, pyramids, palette) = details.details();
        let (lights, sky) = lights_and_sky(scene)?;
        let has_glass = materials.iter().any(|m| matches!(m, Bsdf::Glass(_)));
        Ok(Self {
            has_glass,
            sensors: grid_sensors(scene),
            panels: area_panels(&lights),
            camera: Camera::new(&scene.camera),
            strata: Strata::new(settings.samples_per_pixel),
            settings,
            bvh,
            triangles,
            normals,
            smooth_of,
            vertex_normals,
            material_of,
            materials,
            details,
            maps: class_maps(scene, &material_states)?,
            soilings: soilings(scene, &material_states),
            texture_of,
            textured,
            pyramids,
            coloured_of,
            coloured,
            palette,
            lights,
            sky,
        })
    }

    /// The number of triangles traced (after hidden parts are removed).
    pub fn triangle_count(&self) -> usize {
        self.bvh.triangle_count()
    }

    /// The memory the prepared scene holds, in bytes (the BVH, the triangles and their
    /// attributes, materials and lights; a luminaire's measured distribution is counted by its
    /// share of the table), for a worker's bound on the scenes it keeps.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        size_of::<Self>()
            + self.bvh.memory_bytes()
            + self.triangles.len() * size_of::<RtTriangle>()
            + self.normals.len() * size_of::<Vec3A>()
            + self.smooth_of.len() * size_of::<u32>()
            + self.vertex_normals.len() * size_of::<[Vec3A; 3]>()
            + self.material_of.len() * size_of::<u32>()
            + self.materials.len() * size_of::<Bsdf>()
            + self.texture_of.len() * size_of::<u32>()
            + self.textured.len() * size_of::<TexturedTriangle>()
            + self.pyramids.iter().map(|p| p.memory_bytes()).sum::<usize>()
            + self.coloured_of.len() * size_of::<u32>()
            + self.coloured.len() * size_of::<[u32; 3]>()
            + self.palette.as_ref().map_or(0, |p| p.memory_bytes())
            + self.maps.iter().flatten().map(ClassMap::memory_bytes).sum::<usize>()
            + self.lights.iter().map(Light::memory_bytes).sum::<usize>()
            + self.sensors.len() * size_of::<Sensor>()
    }

    /// The closest hit along the ray within (tmin, tmax).
    #[inline]
    pub fn intersect(&self, origin: Vec3A, direction: Vec3A, tmax: f32) -> Option<Hit> {
        let (slot, t) = self.bvh.closest(origin, direction, tmax)?;
        let n = self.normals[slot];
        let normal = if n.dot(direction) > 0.0 { -n } else { n };
        let point = origin + direction * t;
        let material = self.material_of[slot];
        let detail = match (self.texture_of.get(slot), self.coloured_of.get(slot)) {
            (Some(&k), _) if k != FLAT => Some(self.detail_point(slot, point, On::Photo(k))),
            (_, Some(&k)) if k != FLAT => Some(self.detail_point(slot, point, On::Colours(k))),
            _ => None,
        };
        match self.smooth_of.get(slot) {
            Some(&k) if k != FLAT => {
                let corners = &self.vertex_normals[k as usize];
                let mut hit = self.smooth_hit(slot, corners, point, t, normal, material);
                hit.detail = detail;
                Some(hit)
            }
            _ => Some(Hit { t, point, normal, shading: normal, material, detail }),
        }
    }

    /// Where a hit on triangle `slot` falls on its photo or among its vertex colours. Out of
    /// line: scenes without either never come here.
    #[inline(never)]
    fn detail_point(&self, slot: usize, point: Vec3A, on: On) -> DetailPoint {
        let tri = &self.triangles[slot];
        let weights = barycentric([tri.v0, tri.v0 - tri.e1, tri.v0 + tri.e2], point);
        match on {
            On::Photo(k) => DetailPoint::Photo(self.textured[k as usize].at(weights)),
            On::Colours(k) => {
                // Inside the triangle: rounding may put a hit on an edge a hair outside.
                let w = weights.map(|w| w.max(0.0));
                let weights = w.map(|x| x / (w[0] + w[1] + w[2]).max(f32::MIN_POSITIVE));
                DetailPoint::Vertices(ColourPoint { corners: self.coloured[k as usize], weights })
            }
        }
    }

    /// The exposure-driven soiling of material `material`'s state, if it has one.
    #[inline]
    pub fn soiling(&self, material: u32) -> Option<&Soiling> {
        self.soilings.get(material as usize)?.as_ref()
    }

    /// The diffuse reflectance at a hit: its material's own, or on a textured surface that
    /// spectrum under the photo's detail there, filtered over `footprint_m` (the width of the
    /// ray's cone on the surface). `buffer` holds the latter.
    #[inline]
    pub fn reflectance<'a>(
        &'a self,
        hit: &Hit,
        footprint_m: f32,
        buffer: &'a mut Spectrum,
    ) -> &'a Spectrum {
        let m = hit.material as usize;
        let own = self.materials[m].rho();
        let map = self.maps.get(m).and_then(Option::as_ref);
        let detail = match (&self.details[m], hit.detail) {
            (Some(detail), Some(at)) => Some((detail, at)),
            _ => None,
        };
        if map.is_none() && detail.is_none() {
            return own;
        }
        *buffer = *own;
        if let Some(map) = map {
            map.mix(hit.point, footprint_m, buffer);
        }
        if let Some((detail, at)) = detail {
            detail.apply(at, footprint_m, buffer);
        }
        buffer
    }

    /// A hit on a triangle with shading normals: the normals interpolated at the hit, turned to
    /// the side the ray came from, and the point moved out to the smooth surface. Out of line:
    /// flat scenes never come here.
    #[inline(never)]
    fn smooth_hit(
        &self,
        slot: usize,
        corners: &[Vec3A; 3],
        point: Vec3A,
        t: f32,
        normal: Vec3A,
        material: u32,
    ) -> Hit {
        let tri = &self.triangles[slot];
        let vertices = [tri.v0, tri.v0 - tri.e1, tri.v0 + tri.e2];
        let weights = barycentric(vertices, point);
        let interpolated =
            corners[0] * weights[0] + corners[1] * weights[1] + corners[2] * weights[2];
        // The file's normals may face either way whatever the winding (scans often mix them):
        // they are taken on the side the ray came from, as the geometric normal is.
        let side = if interpolated.dot(normal) < 0.0 { -1.0 } else { 1.0 };
        let shading = (interpolated * side).normalize_or(normal);
        let facing = corners.map(|n| n * side);
        let point = terminator_point(vertices, facing, weights, point);
        Hit { t, point, normal, shading, material, detail: None }
    }

    /// The nearest area luminaire the ray meets before `tmax`, and whether on its emitting
    /// side. Luminaires are not in the BVH: they cast no shadow on the light of others.
    #[inline]
    pub fn panel_hit(&self, origin: Vec3A, direction: Vec3A, tmax: f32) -> Option<(&Panel, bool)> {
        let mut nearest = None;
        let mut reach = tmax;
        for p in &self.panels {
            if let Some((t, front)) = p.intersect(origin, direction, reach) {
                reach = t;
                nearest = Some((p, front));
            }
        }
        nearest
    }

    /// Whether the scene has a light source the camera can see: the sky or an area luminaire.
    pub fn has_visible_sources(&self) -> bool {
        self.sky.is_some() || !self.panels.is_empty()
    }

    /// The share of light that passes along the segment from `origin` along `direction` up to
    /// `distance`: none when something opaque blocks it, else the product of the
    /// transmittances of the panes of glass it crosses (all of it through nothing), by band
    /// behind tinted glass. Without glass in the scene, one any-hit query.
    #[inline]
    pub fn visibility(&self, origin: Vec3A, direction: Vec3A, distance: f32) -> Transmission {
        if !self.has_glass {
            let blocked = self.occluded(origin, direction, distance);
            return Transmission::Neutral(if blocked { 0.0 } else { 1.0 });
        }
        self.visibility_through_glass(origin, direction, distance)
    }

    /// [`PreparedScene::visibility`] in a scene with glass: closest hits pane after pane. Kept
    /// out of line so that the shadow rays of scenes without glass stay small.
    #[inline(never)]
    fn visibility_through_glass(
        &self,
        origin: Vec3A,
        direction: Vec3A,
        distance: f32,
    ) -> Transmission {
        const BLOCKED: Transmission = Transmission::Neutral(0.0);
        let (mut from, mut through) = (origin, Transmission::Neutral(1.0));
        // A segment crosses a few panes at most; past this many it is taken as blocked.
        for _ in 0..MAX_PANES {
            let left = distance - (from - origin).dot(direction);
            if left <= 0.0 {
                return through;
            }
            let Some(hit) = self.intersect(from, direction, left) else { return through };
            let Bsdf::Glass(glass) = &self.materials[hit.material as usize] else {
                return BLOCKED;
            };
            through = through.then(glass.optics(direction.dot(hit.normal)).transmittance());
            if through.is_blocked() {
                return BLOCKED;
            }
            // On, beyond the pane (the hit's normal faces back along the ray).
            from = crate::frame::lift_along(hit.point, -hit.normal);
        }
        BLOCKED
    }

    /// Whether anything blocks the segment from `origin` along `direction` up to `distance`.
    #[inline]
    pub fn occluded(&self, origin: Vec3A, direction: Vec3A, distance: f32) -> bool {
        self.bvh.any_hit(origin, direction, distance)
    }

    /// A closest hit by testing every triangle, for checking the BVH.
    pub fn intersect_brute_force(&self, origin: Vec3A, direction: Vec3A) -> Option<f32> {
        let ray = Ray::new(origin, direction, 0.0, f32::INFINITY);
        self.triangles
            .iter()
            .map(|t| t.intersect(&ray))
            .filter(|t| t.is_finite())
            .min_by(f32::total_cmp)
    }
}

/// Refuses a variant the scene does not define, naming those it does.
fn check_variant(scene: &LoadedScene, variant: Option<&str>) -> Result<(), TraceError> {
    if let Some(v) = variant
        && !scene.file.variants.contains_key(v)
    {
        let known: Vec<&str> = scene.file.variants.keys().map(String::as_str).collect();
        return Err(TraceError::UnknownVariant {
            name: v.to_owned(),
            known: if known.is_empty() { "none".into() } else { known.join(", ") },
        });
    }
    Ok(())
}

/// The triangles to trace, in the meshes' order (before the BVH orders them), and the materials
/// they resolve to: one BSDF per (material, state), and per part's own photo where one shows
/// (the file's photo of a part, under a material without a texture of its own).
#[derive(Default)]
struct Gathered {
    /// Each BSDF's index, by material, state and the part's own detail.
    index: BTreeMap<(String, String, Option<String>), u32>,
    materials: Vec<Bsdf>,
    /// Per material: its name and state, for its degradation map and soiling.
    material_states: Vec<(String, String)>,
    details: MaterialDetails,
    tris: Vec<Triangle>,
    /// Per triangle, its material.
    material_of: Vec<u32>,
    /// The triangles with shading normals, by index in `tris`, and their vertex normals.
    smooth: Vec<(u32, [Vec3A; 3])>,
    /// The triangles on which a photo gives their material detail.
    textured: Vec<(u32, TexturedTriangle)>,
    /// The triangles whose vertex colours give their material detail: their corners' colours.
    coloured: Vec<(u32, [u32; 3])>,
}

impl Gathered {
    /// Every triangle shown of every object, its part's material in `variant`'s state.
    fn from_scene(scene: &LoadedScene, variant: Option<&str>) -> Self {
        let mut gathered = Self::default();
        let viewer = scene.viewer();
        for o in &scene.objects {
            let m = &o.mesh;
            let group_bsdf = gathered.group_materials(scene, variant, o);
            let colours = gathered.details.vertex_colours(m, &group_bsdf);
            // Levels of detail: the camera's choice ([`restauro_scene::lod`]).
            let shown = m.levels.shown(&viewer);
            for (k, (t, &g)) in m.triangles.iter().zip(&m.triangle_group).enumerate() {
                if o.hidden_groups[g as usize] || shown.as_ref().is_some_and(|s| !s[k]) {
                    continue;
                }
                gathered.add_triangle(m, t, group_bsdf[g as usize], colours.as_deref());
            }
        }
        gathered
    }

    /// Per group of object `o`'s mesh, its BSDF's index, each BSDF added the first time a
    /// group needs it.
    fn group_materials(
        &mut self,
        scene: &LoadedScene,
        variant: Option<&str>,
        o: &LoadedObject,
    ) -> Vec<u32> {
        let m = &o.mesh;
        let coloured_groups = m.coloured_groups();
        m.groups
            .iter()
            .zip(&o.group_materials)
            .zip(&coloured_groups)
            .map(|((g, name), &coloured)| {
                let state = variant
                    .and_then(|v| scene.state_of(v, &o.name, &g.name))
                    .unwrap_or("base")
                    .to_owned();
                let own = own_detail(scene, (name, &state), &o.name, g, coloured);
                let key = (name.clone(), state.clone(), own.as_ref().map(|(k, _)| k.clone()));
                *self.index.entry(key).or_insert_with(|| {
                    self.materials.push(bsdf(scene, name, &state));
                    self.material_states.push((name.clone(), state.clone()));
                    self.details.add_material(scene, name, &state, own);
                    (self.materials.len() - 1) as u32
                })
            })
            .collect()
    }

    /// Triangle `t` of mesh `m`, of BSDF `bsdf_index`, with its shading normals and its share
    /// of its material's detail (`colours`, the mesh's vertex colours in the palette).
    fn add_triangle(&mut self, m: &Mesh, t: &[u32; 3], bsdf_index: u32, colours: Option<&[u32]>) {
        let [a, b, c] = t.map(|i| Vec3A::from(m.positions[i as usize]));
        self.tris.push(Triangle { v0: a, v1: b, v2: c });
        self.material_of.push(bsdf_index);
        // Panes are traced flat: through glass, rays go on from the hit itself.
        let pane = matches!(self.materials[bsdf_index as usize], Bsdf::Glass(_));
        let normals = m.normals.as_ref().filter(|_| !pane);
        if let Some(corners) = normals.and_then(|n| smooth_normals(n, t, [a, b, c])) {
            self.smooth.push((self.tris.len() as u32 - 1, corners));
        }
        let at = self.tris.len() as u32 - 1;
        match self.details.triangle(bsdf_index, m, t, [a, b, c], colours) {
            Some(Surface::Textured(t)) => self.textured.push((at, t)),
            Some(Surface::Coloured(corners)) => self.coloured.push((at, corners)),
            None => {}
        }
    }
}

/// The BVH over `tris`, and the triangles and their normals in its order.
fn build_bvh(tris: &[Triangle]) -> (Bvh4, Vec<RtTriangle>, Vec<Vec3A>) {
    let bvh = Bvh4::build(tris, bvh::build_params());
    let order = &bvh.primitive_indices;
    let triangles: Vec<RtTriangle> =
        order.iter().map(|&i| RtTriangle::from(&tris[i as usize])).collect();
    let normals: Vec<Vec3A> = order
        .iter()
        .map(|&i| {
            let t = &tris[i as usize];
            (t.v1 - t.v0).cross(t.v2 - t.v0).normalize_or_zero()
        })
        .collect();
    (bvh, triangles, normals)
}

/// The scene's lights as spectral terms, and its sky apart (at most one: the loader refuses
/// two).
fn lights_and_sky(scene: &LoadedScene) -> Result<(Vec<Light>, Option<Sky>), TraceError> {
    let mut lights = Vec::new();
    let mut sky = None;
    for l in &scene.lights {
        match l {
            ResolvedLight::Sky { illuminance_lux, model, spectrum, general, ground_cd_m2 } => {
                let per_nit = luminous(scene, spectrum)?;
                sky = Some(Sky::new(*illuminance_lux, *model, per_nit, *general, *ground_cd_m2));
            }
            _ => lights.push(light(scene, l)?),
        }
    }
    Ok((lights, sky))
}

/// The sensors of every calculation grid, in the grids' order.
fn grid_sensors(scene: &LoadedScene) -> Vec<Sensor> {
    scene
        .grids
        .iter()
        .flat_map(|g| {
            let normal = Vec3A::from(g.normal.map(|x| x as f32));
            g.points.iter().map(move |p| Sensor { point: Vec3A::from(p.map(|x| x as f32)), normal })
        })
        .collect()
}

/// The area luminaires among `lights`.
fn area_panels(lights: &[Light]) -> Vec<Panel> {
    lights
        .iter()
        .filter_map(|l| match l {
            Light::Area(p) => Some(p.clone()),
            _ => None,
        })
        .collect()
}

/// Per material (by name and state), its state's soiling; empty when none has one.
fn soilings(scene: &LoadedScene, material_states: &[(String, String)]) -> Vec<Option<Soiling>> {
    let out: Vec<Option<Soiling>> = material_states
        .iter()
        .map(|(name, state)| {
            let s = scene.file.materials[name].state(state)?.soiling.as_ref()?;
            Some(Soiling::new(s, scene.spectra[&s.spectrum]))
        })
        .collect();
    if out.iter().all(Option::is_none) { Vec::new() } else { out }
}

/// Per material (by name and state), the degradation map its state names, with the classes it
/// shows; empty when no state names one. Each class's coverage is built once.
fn class_maps(
    scene: &LoadedScene,
    material_states: &[(String, String)],
) -> Result<Vec<Option<ClassMap>>, TraceError> {
    let mut coverages: BTreeMap<(String, String), Arc<LuminancePyramid>> = BTreeMap::new();
    let mut out = Vec::with_capacity(material_states.len());
    for (name, state) in material_states {
        let Some(o) = scene.file.materials[name].state(state) else {
            out.push(None);
            continue;
        };
        let Some(map) = o.map.as_ref().and_then(|m| scene.file.maps.iter().find(|x| &x.name == m))
        else {
            out.push(None);
            continue;
        };
        let image = scene.textures.get(&map.image).ok_or_else(|| {
            TraceError::Scene(format!("map `{}`: its image was not loaded", map.name))
        })?;
        let shown = |c: &&restauro_scene::scene_file::DegradationClass| {
            o.classes.as_ref().is_none_or(|list| list.contains(&c.name))
        };
        let classes = map
            .classes
            .iter()
            .filter(shown)
            .map(|c| {
                let key = (map.name.clone(), c.name.clone());
                let pyramid = coverages
                    .entry(key)
                    .or_insert_with(|| Arc::new(crate::degradation::coverage(image, c.colour)))
                    .clone();
                (pyramid, scene.spectra[&c.spectrum])
            })
            .collect();
        out.push(Some(ClassMap::new(map, (image.width, image.height), classes)));
    }
    if out.iter().all(Option::is_none) {
        out.clear();
    }
    Ok(out)
}

/// The BSDF of material `name` in `state`: the state's fields over the base ones.
fn bsdf(scene: &LoadedScene, name: &str, state: &str) -> Bsdf {
    let m = &scene.file.materials[name];
    let surface = m.surface(state);
    if m.model == MaterialModel::Glass {
        let ior = surface.ior.unwrap_or(crate::glass::DEFAULT_IOR);
        let thickness = m.thickness_mm.unwrap_or(crate::glass::DEFAULT_THICKNESS_MM);
        let transmittance = m.transmittance.as_ref().map(|t| match t {
            Transmittance::Neutral(t) => Spectrum([*t as f32; BANDS]),
            Transmittance::Spectral(name) => scene.spectra[name],
        });
        return Bsdf::Glass(crate::glass::Glass::new(ior, thickness, transmittance.as_ref()));
    }
    let rho = scene.spectra[surface.reflectance.unwrap_or_default()];
    match m.model {
        MaterialModel::Glass => unreachable!("returned above"),
        MaterialModel::Lambert => Bsdf::Lambert { rho },
        MaterialModel::CookTorrance => {
            let roughness = surface.roughness.unwrap_or(0.3) as f32;
            let (specular, ior) = (surface.specular, surface.ior);
            // F0 = ((n − 1)/(n + 1))², 0.04 (n = 1.5) when neither is given.
            let f0 = specular.unwrap_or_else(|| {
                let n = ior.unwrap_or(1.5);
                ((n - 1.0) / (n + 1.0)).powi(2)
            }) as f32;
            Bsdf::CookTorrance { rho, f0, roughness: roughness.max(1e-3) }
        }
    }
}

fn luminous(scene: &LoadedScene, spectrum: &str) -> Result<Spectrum, TraceError> {
    LuminousSpectrum::new(&scene.spectra[spectrum], spectrum)
        .map(|l| l.per_lumen)
        .map_err(|e| TraceError::Scene(e.to_string()))
}

/// The photometric frame of a luminaire (`restauro_scene::formats::photometric::luminaire_frame`).
fn frame(position: [f64; 3], aim: Option<[f64; 3]>) -> [Vec3A; 3] {
    restauro_scene::formats::photometric::luminaire_frame(position, aim)
        .map(|row| Vec3A::from(row.map(|v| v as f32)))
}

/// A measured distribution, its peak scaled to the luminaire's `intensity_cd`.
fn photometric(
    p: &restauro_scene::formats::photometric::Photometry,
    position: [f64; 3],
    aim: Option<[f64; 3]>,
) -> Distribution {
    Distribution::Photometric {
        to_local: frame(position, aim),
        scale: 1.0 / p.peak_cd().max(1e-12),
        photometry: p.clone(),
    }
}

fn light(scene: &LoadedScene, l: &ResolvedLight) -> Result<Light, TraceError> {
    Ok(match l {
        ResolvedLight::Point { position, intensity_cd, spectrum, photometry, aim } => {
            Light::Point {
                position: Vec3A::from(position.map(|v| v as f32)),
                intensity_cd: *intensity_cd as f32,
                per_cd: luminous(scene, spectrum)?,
                distribution: match photometry {
                    Some(p) => photometric(p, *position, *aim),
                    None => Distribution::Isotropic,
                },
            }
        }
        ResolvedLight::Spot {
            position,
            intensity_cd,
            spectrum,
            aim,
            cone_deg,
            falloff_deg,
            photometry,
        } => {
            let axis = (Vec3A::from(aim.map(|v| v as f32))
                - Vec3A::from(position.map(|v| v as f32)))
            .normalize();
            Light::Point {
                position: Vec3A::from(position.map(|v| v as f32)),
                intensity_cd: *intensity_cd as f32,
                per_cd: luminous(scene, spectrum)?,
                distribution: match photometry {
                    Some(p) => photometric(p, *position, Some(*aim)),
                    None => Distribution::Cone {
                        axis,
                        cos_inner: (cone_deg.to_radians().cos()) as f32,
                        cos_outer: ((cone_deg + falloff_deg.max(1e-3)).to_radians().cos()) as f32,
                    },
                },
            }
        }
        ResolvedLight::Sun { direction, illuminance_lux, spectrum, .. } => Light::Distant {
            direction: Vec3A::from(direction.map(|v| v as f32)).normalize(),
            irradiance: luminous(scene, spectrum)? * (*illuminance_lux as f32),
            illuminance_lux: *illuminance_lux as f32,
        },
        ResolvedLight::Area { panel, luminance_cd_m2, spectrum } => {
            let v3 = |p: [f64; 3]| Vec3A::from(p.map(|x| x as f32));
            Light::Area(Panel {
                corner: v3(panel.corner),
                u: v3(panel.u),
                v: v3(panel.v),
                normal: v3(panel.normal),
                area_m2: panel.area_m2() as f32,
                luminance_cd_m2: *luminance_cd_m2 as f32,
                per_nit: luminous(scene, spectrum)?,
            })
        }
        ResolvedLight::Sky { .. } => {
            return Err(TraceError::Scene("the sky is not a delta light".into()));
        }
    })
}

/// A triangle's vertex normals when the mesh gives all three and they bend away from its face
/// (a triangle whose normals all equal its face normal is flat, and traced as such).
fn smooth_normals(normals: &[[f32; 3]], t: &[u32; 3], v: [Vec3A; 3]) -> Option<[Vec3A; 3]> {
    let corners = t.map(|i| normals.get(i as usize).map_or(Vec3A::ZERO, |n| Vec3A::from(*n)));
    if corners.contains(&Vec3A::ZERO) {
        return None;
    }
    let face = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    let flat = corners.iter().all(|n| n.dot(face).abs() > 1.0 - 1e-6);
    (!flat).then_some(corners)
}

/// Per-triangle attributes of some triangles (the smooth ones' vertex normals, the textured
/// ones' coordinates; by triangle, in the meshes' order) as per-triangle indices in BVH order
/// into a list of them ([`FLAT`] for a triangle without); both empty when no triangle has one.
fn in_bvh_order<T: Copy>(smooth: &[(u32, T)], order: &[u32]) -> (Vec<u32>, Vec<T>) {
    if smooth.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let mut of_triangle = vec![FLAT; order.len()];
    for (k, (t, _)) in smooth.iter().enumerate() {
        of_triangle[*t as usize] = k as u32;
    }
    let index = order.iter().map(|&i| of_triangle[i as usize]).collect();
    (index, smooth.iter().map(|(_, c)| *c).collect())
}

/// The barycentric weights of `p` (on the triangle's plane) for its vertices a, b, c.
#[inline]
fn barycentric([a, b, c]: [Vec3A; 3], p: Vec3A) -> [f32; 3] {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det <= 0.0 {
        return [1.0 / 3.0; 3];
    }
    let u = (d22 * d1 - d12 * d2) / det;
    let v = (d11 * d2 - d12 * d1) / det;
    [1.0 - u - v, u, v]
}

/// The point from which rays leave a triangle with shading normals: the hit moved out to the
/// curved surface the vertex normals describe, so that a coarse mesh of a round surface does
/// not shadow itself in facets near the terminator (Hanika, "Hacking the shadow terminator",
/// Ray Tracing Gems II, ch. 4, 2021): the hit is projected onto each vertex's tangent plane
/// where it lies below it, and the projections are blended by the barycentric weights. Where
/// the surface is concave the hit stays where it is.
#[inline]
pub(crate) fn terminator_point(
    vertices: [Vec3A; 3],
    normals: [Vec3A; 3],
    weights: [f32; 3],
    p: Vec3A,
) -> Vec3A {
    let mut offset = Vec3A::ZERO;
    for k in 0..3 {
        let to_p = p - vertices[k];
        let below = to_p.dot(normals[k]).min(0.0);
        offset += (to_p - normals[k] * below) * weights[k];
    }
    p + offset
}
