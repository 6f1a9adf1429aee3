//! The light transport of one camera sample.
//!
//! * `whitted` — the paper's method: at each hit, the direct light of every source with shadow
//!   rays, plus the specular reflection followed in the mirror direction (weighted by Fresnel)
//!   for materials that have a specular part, up to the maximum depth.
//! * `path` — unidirectional path tracing: the same direct light at every vertex (next-event
//!   estimation; all sources are points or directions, so they are sampled exactly), then a
//!   direction drawn from the BSDF, with Russian roulette after three bounces. It adds the
//!   diffuse inter-reflection that the paper notes ray tracing underestimates.
//!
//! The sky, an extended source, is sampled at every vertex by a cosine-weighted direction about
//! the normal (pdf cos θ/π) with a shadow ray to infinity: the estimate of its reflected radiance
//! is f(wo, wi) · L_sky(wi) · π (a CIE general sky adds a sample by its luminance, see
//! [`crate::sky`]); area luminaires are sampled at every vertex too ([`crate::light::Panel`]).
//! A camera ray that escapes sees the sky's radiance, and so does one that passed through glass
//! or reflected in it; a bounce off any other surface that escapes adds nothing, because the sky
//! was already counted at the vertex it left, through any glass on the way (Whitted's mirror
//! rays therefore do not reflect the sky). Shadow rays pass through glass by its transmittance.
//!
//! **The adapting white.** A camera ray also measures, at the first surface it meets, what a
//! perfect white diffuser there would send back: E(λ)/π, with E the spectral irradiance from
//! every source (the same shadow rays and sky samples as the surface's own direct light, whatever
//! the surface's BSDF) and, under `path`, from the other surfaces — the path's continuation from
//! that first vertex is the incoming radiance L_i along the sampled direction, and a white
//! diffuser turns it into L_i · cos θ / (π · pdf). The seen image adapts to this white, the light
//! that falls where the person looks, instead of guessing it from the stones
//! (`restauro_spectral::seen`). Light arriving through glass on the way in is weighted as the
//! surface's own is, so a tinted pane tints both alike.
//!
//! Surfaces shade by their hit's shading normal (the mesh's vertex normals interpolated, or the
//! triangle's own); the geometric normal decides which side rays leave from ([`below_surface`]).
//!
//! All 81 bands travel together on every ray; nothing here allocates.

use crate::bsdf::{Bsdf, cosine_sample};
use crate::frame::Frame;
pub use crate::frame::lift_along;
use crate::glass::{Optics, Transmission};
use crate::prepared::{Hit, PreparedScene};
use crate::sampler::PixelSampler;
use glam::Vec3A;
use restauro_scene::scene_file::Integrator;
use restauro_spectral::Spectrum;
use std::f32::consts::PI;
use std::ops::ControlFlow;

pub use restauro_scene::plan::LIT_BITS;
/// A light lights a point when it gives at least this share of the direct illuminance there
/// from the scene's point and distant lights (the sky not counted): a faint lamp far off does
/// not make a framework of its own.
const LIT_SHARE: f32 = 0.1;

/// What a camera sample saw besides its radiance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Seen {
    /// The ray saw a light source: it escaped to the sky (if there is one), or met an area
    /// luminaire's emitting side.
    pub sky: bool,
    /// Bit k: light k (in the scene's order, the sky not counted) lights the camera ray's first
    /// hit, unoccluded, with at least a tenth of the direct illuminance there. Points lit by the
    /// same lights share their illumination: the Retinex's frameworks (Gilchrist et al., "An
    /// anchoring theory of lightness perception", Psychological Review 106, 1999).
    pub lit_by: u32,
    /// The camera ray met a surface (not the sky, a luminaire or nothing): the white it
    /// measured is that surface's.
    pub surface: bool,
}

/// The direct illuminance (lux) each light gives the first hit, by bit of [`Seen::lit_by`].
type LitLux = [f32; LIT_BITS];

fn lit_mask(lux: &LitLux) -> u32 {
    let total: f32 = lux.iter().sum();
    lux.iter()
        .enumerate()
        .filter(|&(_, &e)| e > 0.0 && e >= LIT_SHARE * total)
        .fold(0, |mask, (k, _)| mask | 1 << k)
}

/// The reflectance of a light source: what [`Weight::add`] takes for a light added unreflected.
static NO_LIGHT: Spectrum = Spectrum::ZERO;

/// Rays leave a surface from a point lifted off it, against self-intersection in f32.
#[inline]
pub fn lift(hit: &Hit) -> Vec3A {
    lift_along(hit.point, hit.normal)
}

/// Whether a bounce `direction`, above the surface by the shading normal, goes into the surface
/// by its geometric normal: the path then ends (a shading normal bends the light's angle, never
/// which side it leaves from). Always false on a flat triangle. Light is not tested so: its
/// shadow ray, from the point moved out to the smooth surface ([`Hit::point`]), finds whether
/// the facet or its neighbours hide it, which keeps the terminator of a coarse round mesh
/// smooth (Hanika 2021) rather than stepped facet by facet.
#[inline]
fn below_surface(hit: &Hit, direction: Vec3A) -> bool {
    hit.shading != hit.normal && direction.dot(hit.normal) <= 0.0
}

/// What the light arriving at a vertex is multiplied by on its way to the camera: one at the
/// camera's hit, a neutral factor behind Whitted's Fresnel-weighted mirror bounces, a spectrum
/// behind diffuse or glossy bounces of the path tracer.
#[derive(Clone, Copy)]
enum Weight<'a> {
    Neutral(f32),
    Spectral(&'a Spectrum),
}

/// A surface hit seen from the ray that found it: the hit, its local frame, and the direction
/// back along the ray in that frame.
struct Vertex<'a> {
    hit: &'a Hit,
    frame: Frame,
    wo: Vec3A,
    /// The diffuse reflectance there (a textured surface's varies from point to point).
    rho: &'a Spectrum,
}

impl Weight<'_> {
    /// `out += weight · light · (ρ·a + b)`.
    #[inline]
    fn add(self, out: &mut Spectrum, light: &Spectrum, rho: &Spectrum, a: f32, b: f32) {
        match self {
            Weight::Neutral(t) => out.add_reflected(light, rho, a * t, b * t),
            Weight::Spectral(w) => out.add_reflected_weighted(w, light, rho, a, b),
        }
    }

    /// `out += weight · through · light · (ρ·a + b)`: light that arrived through glass.
    #[inline]
    fn add_through(
        self,
        through: &Transmission,
        out: &mut Spectrum,
        light: &Spectrum,
        rho: &Spectrum,
        (a, b): (f32, f32),
    ) {
        match through {
            Transmission::Neutral(t) => self.add(out, light, rho, a * t, b * t),
            Transmission::Tinted(t) => self.add_tinted(t, out, light, rho, (a, b)),
        }
    }

    /// [`Weight::add_through`] behind tinted glass; out of line, as rare.
    #[cold]
    #[inline(never)]
    fn add_tinted(
        self,
        tint: &Spectrum,
        out: &mut Spectrum,
        light: &Spectrum,
        rho: &Spectrum,
        (a, b): (f32, f32),
    ) {
        let weight = match self {
            Weight::Neutral(w) => *tint * w,
            Weight::Spectral(w) => *tint * *w,
        };
        Weight::Spectral(&weight).add(out, light, rho, a, b)
    }
}

/// Adds the direct light at a vertex to `out`: Σ f(wo, wi) · E⊥(λ) · cos θi over the visible
/// sources, times `weight`. With f = ρ(λ)·a + b and E⊥ = s·S(λ), each source adds
/// S(λ)·(ρ(λ)·a·s·cos + b·s·cos) in one pass over the bands, with no temporary spectrum. The
/// sky, when there is one, adds one sample of its reflected radiance. At the camera's hit,
/// `lit` collects each light's illuminance, and at its first surface `white` the white
/// diffuser's radiance, E/π (every light that reaches the point, whatever its BSDF makes of it).
#[inline]
#[allow(clippy::too_many_arguments)] // a vertex's context and its three accumulators
fn add_direct(
    scene: &PreparedScene,
    v: &Vertex<'_>,
    weight: Weight<'_>,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
    mut lit: Option<&mut LitLux>,
    mut white: Option<&mut Spectrum>,
) {
    let hit = v.hit;
    let origin = lift(hit);
    let bsdf = &scene.materials[hit.material as usize];
    add_sky(scene, v, origin, weight, sampler, rays, out, white.as_deref_mut());
    for (i, light) in scene.lights.iter().enumerate() {
        let Some(inc) = light.sampled_incident(hit.point, || sampler.next2()) else { continue };
        let cos = inc.direction.dot(hit.shading);
        if cos <= 0.0 {
            continue;
        }
        let (a, b) = bsdf.parts(v.wo, v.frame.to_local(inc.direction));
        let reflects = a > 0.0 || b > 0.0;
        if !reflects && white.is_none() {
            continue;
        }
        *rays += 1;
        let through = scene.visibility(origin, inc.direction, inc.shadow_reach());
        if through.is_blocked() {
            continue;
        }
        let k = inc.scale * cos;
        if reflects {
            weight.add_through(&through, out, inc.spectrum, v.rho, (a * k, b * k));
        }
        if let Some(w) = white.as_deref_mut() {
            weight.add_through(&through, w, inc.spectrum, &NO_LIGHT, (0.0, k / PI));
        }
        if let Some(lux) = lit.as_deref_mut() {
            lux[i.min(LIT_BITS - 1)] += inc.illuminance_lux * cos * through.mean();
        }
    }
}

/// The sky's light reflected at a vertex (nothing when the scene has no sky): a direction drawn
/// with pdf cos θ/π about the normal, and for a sky sampled by its luminance a second direction
/// drawn from it, each with a shadow ray to infinity ([`crate::sky`] gives each its weight).
/// With `white`, the same samples give the white diffuser's radiance, L · weight / π.
#[inline]
#[allow(clippy::too_many_arguments)] // the vertex's context, as add_direct has it
fn add_sky(
    scene: &PreparedScene,
    v: &Vertex<'_>,
    origin: Vec3A,
    weight: Weight<'_>,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
    mut white: Option<&mut Spectrum>,
) {
    let Some(sky) = &scene.sky else { return };
    let (u1, u2) = sampler.next2();
    let cosine = v.frame.to_world(cosine_sample(u1, u2));
    let bsdf = &scene.materials[v.hit.material as usize];
    for sample in sky.samples(v.hit.shading, cosine, || sampler.next2()).into_iter().flatten() {
        if sample.luminance_cd_m2 <= 0.0 {
            continue;
        }
        let (a, b) = bsdf.parts(v.wo, v.frame.to_local(sample.direction));
        let reflects = a > 0.0 || b > 0.0;
        if !reflects && white.is_none() {
            continue;
        }
        *rays += 1;
        let through = scene.visibility(origin, sample.direction, f32::INFINITY);
        if through.is_blocked() {
            continue;
        }
        let k = sample.luminance_cd_m2 * sample.weight;
        if reflects {
            weight.add_through(&through, out, &sky.per_nit, v.rho, (a * k, b * k));
        }
        if let Some(w) = white.as_deref_mut() {
            weight.add_through(&through, w, &sky.per_nit, &NO_LIGHT, (0.0, k / PI));
        }
    }
}

/// Where a path of `max_depth = 0` (no cap) stops if the roulette has not ended it. The roulette
/// keeps a path with probability at most 0.95 a bounce from the third surface on, so a path
/// reaches this depth with probability below 0.95^4094 ≈ 1e-91: no bias that a float can hold,
/// and no endless path between two mirrors under Whitted.
pub const UNCAPPED_DEPTH_GUARD: u32 = 4096;

/// The spectral radiance (W·sr⁻¹·m⁻²·nm⁻¹) arriving at the camera along the ray; `rays`
/// counts the rays traced (closest-hit and shadow), for the benchmarks.
pub fn radiance(
    scene: &PreparedScene,
    origin: Vec3A,
    direction: Vec3A,
    sampler: &mut PixelSampler,
    rays: &mut u64,
) -> Spectrum {
    let (mut out, mut white) = (Spectrum::ZERO, Spectrum::ZERO);
    add_radiance(scene, origin, direction, sampler, rays, &mut out, &mut white);
    out
}

/// [`radiance`], added to `out`: a pixel sums its samples in place; and the radiance a perfect
/// white diffuser at the ray's first surface would send back, added to `white` (see the module
/// comment). Returns what the camera ray saw besides: the sky, or the lights of its first hit.
pub fn add_radiance(
    scene: &PreparedScene,
    origin: Vec3A,
    direction: Vec3A,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
    white: &mut Spectrum,
) -> Seen {
    let path = Path { from_depth: 0, escape: Escape::SeesSky, camera: Some(white), roulette: 1.0 };
    walk(scene, (origin, direction), path, sampler, rays, out)
}

/// What a ray that meets no surface adds.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Escape {
    /// The sky's radiance: a camera ray.
    SeesSky,
    /// Nothing: a calculation grid's ray for its indirect light (the sky's direct light is
    /// sampled at the sensor itself).
    Nothing,
}

/// The radiance arriving at `origin` along the ray, as [`add_radiance`] computes it, with
/// `escape` saying whether a ray that meets nothing sees the sky.
pub fn trace(
    scene: &PreparedScene,
    ray: (Vec3A, Vec3A),
    escape: Escape,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
) -> Seen {
    let path = Path { from_depth: 0, escape, camera: None, roulette: 1.0 };
    walk(scene, ray, path, sampler, rays, out)
}

/// Where a walk starts and what it records.
struct Path<'a> {
    /// The surfaces met before it (the depth cap and the roulette count them).
    from_depth: u32,
    escape: Escape,
    /// A camera ray's white diffuser, measured at its first surface; `None` for other rays.
    camera: Option<&'a mut Spectrum>,
    /// The largest band of the throughput before the walk, for the roulette's odds.
    roulette: f32,
}

/// The light arriving along the ray, added to `out`: the loop of both integrators.
fn walk(
    scene: &PreparedScene,
    (origin, direction): (Vec3A, Vec3A),
    mut path: Path<'_>,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
) -> Seen {
    let mut lux: LitLux = [0.0; LIT_BITS];
    // Whitted's bounces are neutral (Fresnel of a dielectric); the path tracer's become spectral
    // at its first bounce.
    let mut neutral = 1.0f32;
    let mut spectral: Option<Spectrum> = None;
    let (mut origin, mut direction) = (origin, direction);
    let max_depth = depth_cap(scene.settings.max_depth);
    // Whether light met on escaping (the sky, an area luminaire) counts: along the camera's own
    // ray, and after a reflection in glass; not after a surface, whose direct light sampled the
    // sky and the luminaires already (through any glass on the way). `view`: every surface so
    // far was glass, so what the ray meets is what the camera sees.
    let mut counts = path.escape == Escape::SeesSky;
    let mut view = path.from_depth == 0;
    let mut surface = false;
    // The width of the ray's cone (a pixel's, widening with the distance travelled), for the
    // filtering of photo textures; and where a textured or soiled surface's reflectance is put.
    let spread = scene.camera.pixel_spread();
    let mut travelled_m = 0.0f32;
    let (mut textured_rho, mut soiled_rho) = (Spectrum::ZERO, Spectrum::ZERO);
    for depth in path.from_depth..max_depth {
        *rays += 1;
        let hit = scene.intersect(origin, direction, f32::INFINITY);
        let through = weight_of(&spectral, neutral);
        let hit = match surface_or_source(scene, (origin, direction), hit, through, counts, out) {
            ControlFlow::Continue(hit) => hit,
            ControlFlow::Break(seen) => {
                return Seen { sky: view && seen, lit_by: lit_mask(&lux), surface };
            }
        };
        travelled_m += hit.t;
        let bsdf = &scene.materials[hit.material as usize];
        // Panes are flat: glass keeps the geometric normal; other surfaces shade by theirs.
        let is_glass = matches!(bsdf, Bsdf::Glass(_));
        let frame = Frame::new(if is_glass { hit.normal } else { hit.shading });
        let wo = frame.to_local(-direction);
        if let Bsdf::Glass(glass) = bsdf {
            if depth + 1 == max_depth {
                break;
            }
            let weights = (&mut neutral, &mut spectral);
            let across = across_pane(glass, (&hit, frame, wo), direction, sampler, weights);
            let Some(((from, along), reflected)) = across else { break };
            (origin, direction, counts) = (from, along, counts || reflected);
            continue;
        }
        // The cone's width over a slanted surface: w/√|cos θ| (the mean of its two axes).
        let footprint_m = spread * travelled_m / wo.z.abs().max(0.01).sqrt();
        let buffers = (&mut textured_rho, &mut soiled_rho);
        let rho = surface_reflectance(scene, &hit, footprint_m, sampler, rays, buffers);
        // The camera's first surface measures its white diffuser, seen through the same glass
        // (`before`, the weight the path arrived with).
        let mut white = if view { path.camera.take() } else { None };
        surface |= white.is_some();
        let before = white.as_ref().map(|_| (spectral, neutral));
        let lit = view.then_some(&mut lux);
        let vertex = Vertex { hit: &hit, frame, wo, rho };
        add_direct(scene, &vertex, through, sampler, rays, out, lit, white.as_deref_mut());
        (counts, view) = (false, false);
        if depth + 1 == max_depth {
            break;
        }
        match scene.settings.integrator {
            Integrator::Whitted => {
                match mirror_bounce(bsdf, &vertex, &mut neutral, &mut spectral) {
                    Some(mirrored) => direction = mirrored,
                    None => break,
                }
            }
            Integrator::Path => {
                let sampled = sample_bounce(bsdf, &vertex, sampler, neutral, &mut spectral);
                let Some((wi, pdf, throughput)) = sampled else { break };
                direction = frame.to_world(wi);
                if below_surface(&hit, direction) {
                    break;
                }
                if let (Some(white), Some((spectral_before, neutral_before))) = (white, before) {
                    let rest = ((lift(&hit), direction), depth + 1);
                    let camera = (weight_of(&spectral_before, neutral_before), white);
                    let bounce = (&*throughput, wi.z / (PI * pdf));
                    walk_rest(scene, rest, bounce, camera, sampler, rays, out);
                    return Seen { sky: false, lit_by: lit_mask(&lux), surface };
                }
                if depth >= 2 && !survives_roulette(throughput, path.roulette, sampler) {
                    break;
                }
            }
        }
        origin = lift(&hit);
    }
    Seen { sky: false, lit_by: lit_mask(&lux), surface }
}

/// What the light arriving along a path is multiplied by: its spectral throughput once it has
/// one, else its neutral factor.
#[inline]
fn weight_of(spectral: &Option<Spectrum>, neutral: f32) -> Weight<'_> {
    match spectral {
        Some(t) => Weight::Spectral(t),
        None => Weight::Neutral(neutral),
    }
}

/// What a ray meets: the surface `hit` it goes on to, or a light source that ends the path,
/// an area luminaire before the surface (whichever side it meets) or the sky when it meets no
/// surface. At a source it adds the source's radiance, times `through`, when light met on
/// escaping `counts`, and breaks with whether the ray saw a source (a luminaire from its
/// emitting side, or the sky).
#[inline]
fn surface_or_source(
    scene: &PreparedScene,
    (origin, direction): (Vec3A, Vec3A),
    hit: Option<Hit>,
    through: Weight<'_>,
    counts: bool,
    out: &mut Spectrum,
) -> ControlFlow<bool, Hit> {
    let reach = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
    if let Some((panel, front)) = scene.panel_hit(origin, direction, reach) {
        if counts && front {
            through.add(out, &panel.per_nit, &NO_LIGHT, 0.0, panel.luminance_cd_m2);
        }
        return ControlFlow::Break(front);
    }
    let Some(hit) = hit else {
        if let Some(sky) = scene.sky.as_ref().filter(|_| counts) {
            through.add(out, &sky.per_nit, &NO_LIGHT, 0.0, sky.luminance_cd_m2(direction));
        }
        return ControlFlow::Break(true);
    };
    ControlFlow::Continue(hit)
}

/// Where a path goes at a pane ([`through_pane`] chooses, and weights the path): the ray it
/// goes on along, straight on from beyond the pane or mirrored off it (`wo`, the direction back
/// along the incoming ray in the pane's frame), and whether it reflected; `None` when the pane
/// neither reflects nor transmits.
#[inline]
fn across_pane(
    glass: &crate::glass::Glass,
    (hit, frame, wo): (&Hit, Frame, Vec3A),
    direction: Vec3A,
    sampler: &mut PixelSampler,
    (neutral, spectral): (&mut f32, &mut Option<Spectrum>),
) -> Option<((Vec3A, Vec3A), bool)> {
    Some(if through_pane(glass, wo.z, sampler, neutral, spectral)? {
        ((lift_along(hit.point, -hit.normal), direction), false)
    } else {
        ((lift(hit), frame.to_world(Vec3A::new(-wo.x, -wo.y, wo.z))), true)
    })
}

/// The diffuse reflectance at a hit, as the light sees it: its material's, under its photo's
/// or vertex colours' detail filtered over `footprint_m` ([`PreparedScene::reflectance`]), and
/// under its soiling's deposit, one estimate of the share it covers there
/// ([`crate::soiling`]). `buffers` hold the textured and the soiled reflectance.
#[inline]
fn surface_reflectance<'a>(
    scene: &'a PreparedScene,
    hit: &Hit,
    footprint_m: f32,
    sampler: &mut PixelSampler,
    rays: &mut u64,
    (textured_rho, soiled_rho): (&'a mut Spectrum, &'a mut Spectrum),
) -> &'a Spectrum {
    let rho = scene.reflectance(hit, footprint_m, textured_rho);
    let Some(soiling) = scene.soiling(hit.material) else { return rho };
    let occluded = |from, towards| scene.occluded(from, towards, f32::INFINITY);
    let share = soiling.share(occluded, lift(hit), hit.shading, sampler, rays);
    soiling.mix(rho, share, soiled_rho);
    soiled_rho
}

/// Whitted's bounce: the mirror direction, the path's weight multiplied by the surface's
/// Fresnel reflectance; `None` when the surface has no specular part or the mirror direction
/// goes into it ([`below_surface`]).
#[inline]
fn mirror_bounce(
    bsdf: &Bsdf,
    v: &Vertex<'_>,
    neutral: &mut f32,
    spectral: &mut Option<Spectrum>,
) -> Option<Vec3A> {
    let f = bsdf.mirror_reflectance(v.wo.z)?;
    match spectral {
        Some(s) => *s *= f,
        None => *neutral *= f,
    }
    let direction = v.frame.to_world(Vec3A::new(-v.wo.x, -v.wo.y, v.wo.z));
    (!below_surface(v.hit, direction)).then_some(direction)
}

/// The path tracer's bounce: a direction drawn from the BSDF (in the vertex's frame) and its
/// pdf, and the path's throughput, multiplied by f · cos θ / pdf (spectral from the first
/// bounce on); `None` when the BSDF gives no direction.
#[inline]
fn sample_bounce<'s>(
    bsdf: &Bsdf,
    v: &Vertex<'_>,
    sampler: &mut PixelSampler,
    neutral: f32,
    spectral: &'s mut Option<Spectrum>,
) -> Option<(Vec3A, f32, &'s mut Spectrum)> {
    let (u, u1, u2) = (sampler.next_1d(), sampler.next_1d(), sampler.next_1d());
    let (wi, pdf) = bsdf.sample(v.wo, u, u1, u2)?;
    let f = bsdf.eval_with(v.rho, v.wo, wi) * (wi.z / pdf);
    match spectral {
        Some(t) => *t *= f,
        None => *spectral = Some(f * neutral),
    }
    Some((wi, pdf, spectral.as_mut()?))
}

/// Russian roulette from the third surface on: the path goes on with probability
/// min(0.95, the largest band of its throughput, times the one it started with), and its
/// throughput is divided by that probability when it does.
#[inline]
fn survives_roulette(throughput: &mut Spectrum, roulette: f32, sampler: &mut PixelSampler) -> bool {
    let survive = (throughput.max_value() * roulette).min(0.95);
    if sampler.next_1d() >= survive {
        return false;
    }
    *throughput /= survive;
    true
}

/// The surfaces a path meets at most: `render.max_depth`, or for 0 (no cap)
/// [`UNCAPPED_DEPTH_GUARD`].
#[inline]
fn depth_cap(max_depth: u32) -> u32 {
    match max_depth {
        0 => UNCAPPED_DEPTH_GUARD,
        cap => cap,
    }
}

/// The rest of a camera path past its first surface (`from_depth` surfaces met), under the path
/// tracer: the radiance L_i arriving along the sampled direction, walked on its own, its
/// roulette's odds scaled by the throughput so far. The surface reflects
/// `throughput` · L_i of it into `out`, and the white diffuser there L_i · cos θ / (π · pdf)
/// (`bounce`'s second part) into `white`, both behind any glass on the way in (`arrived`, the
/// weight the path arrived with).
#[allow(clippy::too_many_arguments)] // the walk's context, and the two sums the rest adds to
fn walk_rest(
    scene: &PreparedScene,
    (ray, from_depth): ((Vec3A, Vec3A), u32),
    (throughput, white_scale): (&Spectrum, f32),
    (arrived, white): (Weight<'_>, &mut Spectrum),
    sampler: &mut PixelSampler,
    rays: &mut u64,
    out: &mut Spectrum,
) {
    let rest = Path {
        from_depth,
        escape: Escape::Nothing,
        camera: None,
        roulette: throughput.max_value(),
    };
    let mut incoming = Spectrum::ZERO;
    walk(scene, ray, rest, sampler, rays, &mut incoming);
    *out += *throughput * incoming;
    arrived.add(white, &incoming, &NO_LIGHT, 0.0, white_scale);
}

/// A path meets a pane: it goes through or reflects off, chosen by their shares (mean over the
/// bands for tinted glass), and the throughput takes the chosen share over its probability.
/// Returns whether it goes through, or `None` when the pane neither reflects nor transmits.
/// Out of line: it keeps the tracer's loop small for the scenes (most) without glass.
#[inline(never)]
fn through_pane(
    glass: &crate::glass::Glass,
    cos_i: f32,
    sampler: &mut PixelSampler,
    neutral: &mut f32,
    spectral: &mut Option<Spectrum>,
) -> Option<bool> {
    match glass.optics(cos_i) {
        Optics::Neutral { r, t } => {
            if r + t <= 0.0 {
                return None;
            }
            match spectral {
                Some(s) => *s *= r + t,
                None => *neutral *= r + t,
            }
            Some(sampler.next_1d() * (r + t) < t)
        }
        Optics::Tinted { r, t } => {
            let (r_mean, t_mean) = (r.mean(), t.mean());
            if r_mean + t_mean <= 0.0 {
                return None;
            }
            let transmit = sampler.next_1d() * (r_mean + t_mean) < t_mean;
            let (share, p) = if transmit { (t, t_mean) } else { (r, r_mean) };
            let factor = share * ((r_mean + t_mean) / p);
            match spectral {
                Some(s) => *s *= factor,
                None => *spectral = Some(factor * *neutral),
            }
            Some(transmit)
        }
    }
}
