//! What a person standing there sees: the render adapted to the light that falls there.
//!
//! A Retinex must guess the light from the image, and the guess fails where the scene gives it
//! no white: its paths take the brightest surface in each channel for white, so a brick wall
//! with nothing whiter in view is seen white, and a warm lamp on pale stone is discounted as if
//! the stone's colour were the lamp's. restauro does not need the guess. The renderer measures,
//! at every pixel's surface, what a perfect white diffuser there would send back under all the
//! scene's light — sun, sky, luminaires and the light between surfaces (the *adapting white*,
//! `restauro_render::integrator`) — and the seen image adapts to that. The Retinex's paths stay
//! the mechanism for lightness; they no longer decide the colour of the light.
//!
//! For a pixel p with rendered XYZ I(p) (absolute, Y in cd/m²):
//!
//! 1. **Frameworks and the local white.** The frameworks of illumination (the areas lit by the
//!    same lights, from the render's `lit_by` mask; `crate::retinex`'s frameworks), merged where
//!    the light changes gradually across their edge ([`continuity`]), bound the smoothing of the
//!    renderer's white: Ŵ(p) is the light on p's surface, smoothed within its framework
//!    ([`white`]); Y_g is the white level of the most lit framework.
//! 2. **Level.** A surface is seen partly against the light on its own plane and partly
//!    against its framework's, and a framework partly against its own light and partly against
//!    the image's (anchoring's co-determination, Gilchrist et al. 1999; the coplanar ratio
//!    principle, Gilchrist 1977, for the plane's larger weight):
//!
//!    ```text
//!      Y_r(p) = Y_f^w · Y_g^(1−w) · (Ŷ(p) / Y_f)^v,        n(p) = Y(p) / Y_r(p),
//!    ```
//!
//!    with Y_f the level of p's framework, w the framework weight (0.5 by default) and v the
//!    plane weight ([`DEFAULT_PLANE_WEIGHT`]). n is the surface's lightness: its reflectance
//!    for a matte surface facing its framework's most lit way; a shadow lies below that by half
//!    its light's ratio to the sun's, a wall turned from the light by 15 % of its own.
//! 3. **Lightness by the paths.** The Marini–Rizzi paths run on n with a known anchor
//!    (`crate::retinex::Anchor::Known`): each path starts with its start's own lightness
//!    instead of taking it for white, so the lightness ℓ(p) is n(p) where nothing is brighter
//!    than white, smooth gradients below the threshold are discounted, and an area brighter
//!    than its white (a face turned more to the sun than the level, a lamp's hot spot) becomes
//!    the white of what the paths cross after it. One factor for all three cones:
//!    k(p) = ℓ(p)/n(p), smoothed within the frameworks as the white is (it is an adaptation
//!    state, and 20 paths a pixel estimate it with a grain of their own).
//! 4. **Colour.** CAT16 towards Ŵ(p)'s chromaticity with a degree of adaptation D that grows
//!    with the adapting luminance and falls as the light moves from bluish daylight
//!    ([`degree`]), shown as CAM16's corresponding colour under D65:
//!
//!    ```text
//!      seen(p) = M₁₆⁻¹ · diag(g) · M₁₆ · I(p) · k(p) / Y_r(p),
//!      g_i = (D/ρ_Ŵ,i + 1 − D) / (D/ρ_D65,i + 1 − D),   ρ_Ŵ = M₁₆ Ŵ / Ŷ,   L_A = Y_r / 5.
//!    ```
//!
//! 5. **Night.** Below 5 cd/m² of adapting luminance the rods take part (CIE 191:2010's
//!    mesopic coefficient m, from L_A and the scotopic luminance of the white): the seen
//!    colour's CIELAB chroma is scaled by m, its hue and lightness kept ([`mesopic`]).
//!
//! 6. **Time.** The frames of a sequence are seen by one eye that has been adapting between
//!    them: its level lags the image's by the cones' 80 ms and half its white by a 20 s
//!    half-life ([`time_course`]); a still is seen by an eye adapted to it.
//!
//! Light sources in view (the sky, a lamp) are seen against the scene's overall light at the
//! image's level. The output is XYZ relative to a D65 white of Y = 1, as the Retinex's was:
//! a white card in full light is 1, a brick wall its own L*, not white.
//!
//! Why this design: Wilkie & Weidlich (EGSR 2009) estimate the pertinent illumination from what
//! the renderer computes; Akyüz & Reinhard (JEI 2006) and iCAM06 (Kuang, Johnson & Fairchild
//! 2007) adapt partially towards a known white; the degree of adaptation is CAM16's with a
//! blue bias (Pearce et al. 2014; Weiss, Witzel & Gegenfurtner 2017). Measured on Breneman's
//! corresponding colours (`tests/breneman.rs`) and against colour-science's CAM16
//! (`tests/cam16_oracle.rs`).

mod continuity;
pub mod degree;
pub mod mesopic;
mod smoothing;
pub mod time_course;
mod white;

pub use time_course::{EyeHistory, EyeState};
pub use white::RADIUS_OF_DIAGONAL;

use crate::appearance::{ChannelSpace, d65_white};
use crate::colorimetry::Xyz;
use crate::error::{Error, Result};
use crate::lab::Lab;
use crate::retinex::{self, Frameworks, RetinexParams, RetinexStats};
use glam::DVec3;
use rayon::prelude::*;

/// The parameters of the seen image. The Retinex's (paths, reach, threshold, seed, what may be
/// the white, the light sources, the frameworks and their weight) are its lightness stage's.
#[derive(Clone, Debug, PartialEq)]
pub struct SeenParams {
    pub retinex: RetinexParams,
    /// v: the weight (0–1) of the light on a surface's own plane against its framework's.
    pub plane_weight: f32,
    /// Model mesopic vision (colour weakening below 5 cd/m²).
    pub mesopic: bool,
    /// The eye's state after the frame before and the time since, for a frame of a sequence
    /// ([`time_course`]); `None`: the image is seen alone, by an eye adapted to it.
    pub history: Option<EyeHistory>,
}

/// The default plane weight: a surface is seen mostly against the light on its own plane —
/// lightness follows the ratios within a plane more than across planes (Gilchrist, "Perceived
/// lightness depends on perceived spatial arrangement", Science 195, 1977) — but not wholly:
/// observers match a card turned from the light between its reflectance and its luminance
/// (Ripamonti et al., JoV 4(9), 2004). 0.85: a wall turned from the light is seen 15 % of its
/// light's ratio (in log) darker. Under the CIE overcast sky, whose vertical illuminance is
/// about half the horizontal, a wall across a square is then seen 2–3 L* darker than its
/// colour under D65, and a white marble wall white (`render/tests/seen_walls.rs`); at 0.75 the
/// marble was seen L* 82, light grey, and at 0.5 a granite wall 10 L* darker than it is.
pub const DEFAULT_PLANE_WEIGHT: f32 = 0.9;

impl Default for SeenParams {
    fn default() -> Self {
        SeenParams {
            retinex: RetinexParams::default(),
            plane_weight: DEFAULT_PLANE_WEIGHT,
            mesopic: true,
            history: None,
        }
    }
}

/// What a run found, for reports and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct SeenStats {
    pub retinex: RetinexStats,
    /// The image's white level Y_g (cd/m²).
    pub white_level_cd_m2: f64,
    /// The chromaticity (x, y) of the scene's overall light.
    pub white_xy: (f64, f64),
    /// The degree of adaptation D over the surface pixels: least, mean, largest.
    pub degree: [f64; 3],
    /// CIE 191's mesopic coefficient m over the surface pixels: least, mean, largest (1 when
    /// mesopic vision is not modelled).
    pub mesopic: [f64; 3],
    /// The state of an eye adapted to this image's light (its level and white).
    pub light_eye: EyeState,
    /// The eye's state after this image: `light_eye` unless [`SeenParams::history`] brought
    /// an eye that has not caught up; the next frame's history.
    pub eye: EyeState,
}

/// Validate what the Retinex does not: the whites.
fn check_white(white: &[[f32; 4]], len: usize, plane_weight: f32) -> Result<()> {
    if !(plane_weight.is_finite() && (0.0..=1.0).contains(&plane_weight)) {
        return Err(Error::OutOfRange {
            quantity: "plane weight",
            value: f64::from(plane_weight),
            expected: "a weight from 0 to 1",
        });
    }
    if white.len() != len {
        return Err(Error::Image {
            problem: format!("the adapting white has {} pixels, the image {len}", white.len()),
        });
    }
    if let Some(i) = white.iter().position(|w| w.iter().any(|v| !v.is_finite() || *v < 0.0)) {
        return Err(Error::Image {
            problem: format!(
                "the adapting white of pixel {i} is {:?}; it must be finite and ≥ 0 (X, Y, Z, \
                 scotopic luminance, as restauro's renders write it)",
                white[i]
            ),
        });
    }
    Ok(())
}

/// Least, mean and largest of `values`.
fn summary(values: impl Iterator<Item = f64>) -> [f64; 3] {
    let (mut lo, mut hi, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    for v in values {
        (lo, hi, sum, n) = (lo.min(v), hi.max(v), sum + v, n + 1);
    }
    if n == 0 { [0.0; 3] } else { [lo, sum / n as f64, hi] }
}

/// How one pixel is seen: its adapting white, level and lightness factor in, XYZ out.
struct Pixel {
    xyz: [f32; 3],
    white: [f64; 4],
    level_cd_m2: f64,
    /// k = ℓ/n, the paths' change to the known lightness.
    factor: f64,
}

/// A pixel's white (X, Y, Z, scotopic) as an eye lagging by `m` adapts to it: its cones moved
/// by the lag, its scotopic luminance in proportion to its Y.
fn lagging_white(m: &glam::DMat3, white: [f64; 4]) -> [f64; 4] {
    let moved = *m * DVec3::new(white[0], white[1], white[2]);
    let scotopic = if white[1] > 0.0 { white[3] * moved.y / white[1] } else { white[3] };
    [moved.x, moved.y, moved.z, scotopic]
}

/// The seen colour of a pixel (relative XYZ under D65), its D and its m.
fn seen_pixel(p: &Pixel, mesopic: bool) -> ([f32; 3], f64, f64) {
    let white = Xyz::new(p.white[0], p.white[1], p.white[2]);
    let la = degree::ADAPTING_SHARE_OF_WHITE * p.level_cd_m2;
    let d = degree::luminance_term(la) * degree::chromatic_term(white);
    let m = if mesopic {
        let sp = if p.white[1] > 0.0 { p.white[3] / p.white[1] } else { 0.0 };
        mesopic::adaptation_coefficient(la, la * sp)
    } else {
        1.0
    };
    let i = DVec3::new(f64::from(p.xyz[0]), f64::from(p.xyz[1]), f64::from(p.xyz[2]));
    let seen = degree::to_d65(white, d) * i * (p.factor / p.level_cd_m2);
    let seen = if m < 1.0 {
        // The rods' share carries no hue: chroma scaled by m, hue and lightness kept (in CIELAB
        // against the D65 white, where hue is a direction).
        let lab = Lab::from_xyz(Xyz::new(seen.x, seen.y, seen.z), d65_white());
        let x = Lab::new(lab.l, lab.a * m, lab.b * m).to_xyz(d65_white());
        DVec3::new(x.x, x.y, x.z)
    } else {
        seen
    };
    // Finite whatever the input: 60 e-folds above white is white on any display.
    let out =
        seen.to_array().map(|v| if v.is_finite() { v.clamp(-1e26, 1e26) as f32 } else { 0.0 });
    (out, d, m)
}

/// The seen image of `xyz` (absolute, Y in cd/m², row-major `width` × `height`) whose
/// renderer's adapting white is `white` (X, Y, Z, scotopic luminance per pixel): XYZ relative
/// to a D65 white of Y = 1. `progress` is the paths' (see [`retinex::retinex`]).
pub fn seen(
    xyz: &[[f32; 3]],
    white: &[[f32; 4]],
    (width, height): (usize, usize),
    params: &SeenParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Vec<[f32; 3]>, SeenStats)> {
    let rp = &params.retinex;
    retinex::check(xyz, width, height, rp)?;
    check_white(white, xyz.len(), params.plane_weight)?;
    let clock = std::time::Instant::now();
    let n = xyz.len();
    let emitters = rp.emitters.clone().unwrap_or_else(|| vec![false; n]);
    let counted = retinex::counted(&emitters, xyz);
    let frameworks = match &rp.frameworks {
        Some(keys) => {
            let by_lights = retinex::frameworks_of(keys, counted, (width, height));
            let white_y: Vec<f32> = white.iter().map(|w| w[1]).collect();
            continuity::merge_continuous(by_lights, &white_y, width)
        }
        None => Frameworks::one(counted),
    };
    let smoother = smoothing::Smoother::new(&frameworks, (width, height), RADIUS_OF_DIAGONAL);
    let adapting = white::adapting_white(white, &smoother, &frameworks, &emitters);
    // An image that shows no lit surface is seen against its own light sources, if any.
    let level = if adapting.level_cd_m2 > 0.0 {
        adapting.level_cd_m2
    } else {
        xyz.iter().map(|p| f64::from(p[1])).fold(0.0, f64::max).max(f64::MIN_POSITIVE)
    };
    // The eye of a sequence may lag the light: its level and white move by the lag.
    let overall = Xyz::new(adapting.overall[0], adapting.overall[1], adapting.overall[2]);
    let light_eye = time_course::adapted(level, overall);
    let (eye, lag) = time_course::adapt(light_eye, params.history.as_ref())?;
    let white_lag = (lag.cone_ratio != [1.0; 3]).then(|| lag.white_matrix());
    let (w, v) = (f64::from(rp.framework_weight), f64::from(params.plane_weight));
    // Y_r(p), each light floored a millionth below the level: a surface no light reaches is
    // dark, not divided by zero.
    let floor = 1e-6 * level;
    // Per framework, its floored level and the framework's share of the reference, so that a
    // pixel raises one number to a power, not three.
    let frameworks_reference: Vec<(f64, f64)> = adapting
        .framework_level_cd_m2
        .iter()
        .map(|framework| {
            let framework = framework.max(floor);
            (framework, framework.powf(w) * level.powf(1.0 - w))
        })
        .collect();
    let reference: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|p| {
            if emitters[p] {
                return level * lag.level_ratio;
            }
            let (framework, share) = frameworks_reference[usize::from(adapting.framework[p])];
            let own = adapting.local[p][1].max(floor);
            share * (own / framework).powf(v) * lag.level_ratio
        })
        .collect();
    let relative: Vec<[f32; 3]> = (0..n)
        .into_par_iter()
        .map(|p| {
            let v = (f64::from(xyz[p][1]) / reference[p]).min(1e30) as f32;
            [v; 3]
        })
        .collect();
    let framing = clock.elapsed().as_secs_f64();
    let known = RetinexParams { anchor: retinex::Anchor::Known, ..rp.clone() };
    let (lightness, mut stats) =
        retinex::run(&relative, (width, height), &known, &emitters, &frameworks, progress)?;
    stats.seconds.cleaning += framing;
    let started = clock.elapsed().as_secs_f64();
    // k = ℓ/n, smoothed within the frameworks as the white is: the paths' change to the known
    // lightness is an adaptation state (gradients discounted, an area above white anchoring
    // what is around it), and its estimate from 20 paths a pixel carries their sampling noise
    // (a 7 % grain on the demo's flat paving before this smoothing).
    let log_factor = |p: usize| {
        let n_p = f64::from(relative[p][0]);
        (!emitters[p] && n_p > 0.0 && lightness[p][0] > 0.0)
            .then(|| [(f64::from(lightness[p][0]) / n_p).ln(), 0.0, 0.0, 0.0])
    };
    let factors = smoother.smooth(log_factor);
    let seen: Vec<([f32; 3], f64, f64)> = (0..n)
        .into_par_iter()
        .map(|p| {
            let factor = if emitters[p] {
                1.0
            } else {
                let f = usize::from(adapting.framework[p]);
                smoother.at(&factors, f, p).map_or(1.0, |v| v[0].exp())
            };
            let white = match &white_lag {
                Some(m) => lagging_white(m, adapting.local[p]),
                None => adapting.local[p],
            };
            let pixel = Pixel { xyz: xyz[p], white, level_cd_m2: reference[p], factor };
            seen_pixel(&pixel, params.mesopic)
        })
        .collect();
    stats.seconds.lightness += clock.elapsed().as_secs_f64() - started;
    let surfaces = || (0..n).filter(|&p| frameworks.solid[p]);
    let xy = overall.chromaticity().map_or((0.0, 0.0), |c| (c.x, c.y));
    let stats = SeenStats {
        white_level_cd_m2: adapting.level_cd_m2,
        white_xy: xy,
        degree: summary(surfaces().map(|p| seen[p].1)),
        mesopic: summary(surfaces().map(|p| seen[p].2)),
        light_eye,
        eye,
        retinex: stats,
    };
    Ok((seen.into_iter().map(|s| s.0).collect(), stats))
}

/// What the seen image adapts to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Adaptation {
    /// The light the renderer measured ([`seen`]); needs the image's adapting white.
    Light,
    /// The Retinex alone, channel by channel in a cone or RGB space: each channel's white is
    /// the brightest area its paths find (the paper's seen image, and restauro's before it knew
    /// the light). For comparison, and for images that carry no adapting white.
    Retinex(ChannelSpace),
}

impl std::fmt::Display for Adaptation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Adaptation::Light => f.write_str("light"),
            Adaptation::Retinex(space) => write!(f, "retinex ({space})"),
        }
    }
}

/// What a seen image was made with and found, for the EXR's attribute and the reports.
#[derive(Clone, Debug, PartialEq)]
pub struct SeenReport {
    pub adaptation: Adaptation,
    pub retinex: RetinexStats,
    /// With [`Adaptation::Light`].
    pub light: Option<SeenStats>,
}

impl SeenReport {
    /// The settings and findings as `key=value` words.
    pub fn settings(&self, params: &SeenParams) -> String {
        let r = &params.retinex;
        let white = match r.white {
            retinex::WhiteReference::Area => "area",
            retinex::WhiteReference::Paper => "paper",
        };
        let sky = if r.emitters.is_some() { "passed-over" } else { "none" };
        let mut s = format!(
            "paths={} reach={} length={} threshold={} seed={} white={white} light-sources={sky} \
             frameworks={} framework-weight={} plane-weight={}",
            r.paths,
            r.reach,
            self.retinex.length,
            r.threshold,
            r.seed,
            self.retinex.frameworks,
            r.framework_weight,
            params.plane_weight,
        );
        match (&self.adaptation, &self.light) {
            (Adaptation::Light, Some(l)) => {
                let _ = std::fmt::Write::write_fmt(
                    &mut s,
                    format_args!(
                        " adaptation=light mesopic={} white-level-cd-m2={:.4} white-xy={:.4},{:.4} \
                         degree-min-mean-max={:.3},{:.3},{:.3} mesopic-m-min-mean-max={:.3},{:.3},{:.3}",
                        params.mesopic,
                        l.white_level_cd_m2,
                        l.white_xy.0,
                        l.white_xy.1,
                        l.degree[0],
                        l.degree[1],
                        l.degree[2],
                        l.mesopic[0],
                        l.mesopic[1],
                        l.mesopic[2],
                    ),
                );
                let cones = |c: &[f64; 3]| format!("{:e},{:e},{:e}", c[0], c[1], c[2]);
                let _ = std::fmt::Write::write_fmt(
                    &mut s,
                    format_args!(
                        " light-level-cd-m2={:e} light-cones={} eye-level-cd-m2={:e} \
                         eye-slow-cones={}",
                        l.light_eye.level_cd_m2,
                        cones(&l.light_eye.slow_cones),
                        l.eye.level_cd_m2,
                        cones(&l.eye.slow_cones),
                    ),
                );
            }
            (adaptation, _) => {
                let _ =
                    std::fmt::Write::write_fmt(&mut s, format_args!(" adaptation={adaptation}"));
            }
        }
        s
    }
}

/// The seen image of `xyz` (absolute XYZ) by `adaptation`: [`seen`] with the adapting white
/// `white` (refused without it), or the Retinex alone.
pub fn seen_image(
    xyz: &[[f32; 3]],
    white: Option<&[[f32; 4]]>,
    size: (usize, usize),
    params: &SeenParams,
    adaptation: Adaptation,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(Vec<[f32; 3]>, SeenReport)> {
    match adaptation {
        Adaptation::Light => {
            let white = white.ok_or_else(|| Error::Image {
                problem: "the image has no adapting white (the white.X, white.Y, white.Z and \
                          white.scotopic channels restauro's renders write), so the light that \
                          falls in it is unknown; render it again with restauro, or adapt by \
                          the Retinex alone (--adaptation retinex)"
                    .into(),
            })?;
            let (out, stats) = seen(xyz, white, size, params, progress)?;
            let retinex = stats.retinex.clone();
            Ok((out, SeenReport { adaptation, retinex, light: Some(stats) }))
        }
        Adaptation::Retinex(space) => {
            let (w, h) = size;
            let (out, retinex) =
                crate::appearance::retinex_xyz(xyz, w, h, &params.retinex, space, progress)?;
            Ok((out, SeenReport { adaptation, retinex, light: None }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform field of a stone under a known light is seen as the stone's colour under D65
    /// when adaptation is complete: here a daylight at 2000 cd/m² (D ≈ 1), a flat field of
    /// reflectance 0.15 in every channel, with no white in view.
    #[test]
    fn a_field_without_white_keeps_its_lightness() {
        let (w, h) = (48, 32);
        let light = d65_white().scale(2000.0);
        let white = vec![[light.x as f32, light.y as f32, light.z as f32, 5000.0]; w * h];
        let stone = light.scale(0.15);
        let xyz = vec![[stone.x as f32, stone.y as f32, stone.z as f32]; w * h];
        let (out, stats) = seen(&xyz, &white, (w, h), &SeenParams::default(), &|_, _| {}).unwrap();
        let lab = Lab::from_xyz(
            Xyz::new(out[500][0].into(), out[500][1].into(), out[500][2].into()),
            d65_white(),
        );
        let expect =
            Lab::from_xyz(Xyz::new(0.15 * d65_white().x, 0.15, 0.15 * d65_white().z), d65_white());
        assert!((lab.l - expect.l).abs() < 0.5, "{lab:?} against {expect:?}");
        assert!(lab.chroma() < 0.5, "{lab:?}");
        assert!((stats.white_level_cd_m2 - 2000.0).abs() < 1e-3);
    }

    #[test]
    fn bad_whites_are_refused() {
        let xyz = vec![[1.0f32; 3]; 4];
        let p = SeenParams::default();
        assert!(seen(&xyz, &[[1.0; 4]; 3], (2, 2), &p, &|_, _| {}).is_err());
        let e = seen(&xyz, &[[1.0, f32::NAN, 1.0, 1.0]; 4], (2, 2), &p, &|_, _| {}).unwrap_err();
        assert!(e.to_string().contains("adapting white of pixel 0"), "{e}");
        assert!(seen(&xyz, &[[1.0, -1.0, 1.0, 1.0]; 4], (2, 2), &p, &|_, _| {}).is_err());
    }
}
