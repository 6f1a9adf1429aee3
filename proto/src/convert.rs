//! The one conversion of each wire type to its domain type (`TryFrom`, refusing what the domain
//! cannot hold) and back (`From`). Nothing past this module reads a `pb` options message.
//!
//! | wire | domain |
//! |---|---|
//! | `pb::RenderOptions` | `restauro_scene::plan::RenderOptions` |
//! | `pb::Integrator` | `restauro_scene::scene_file::Integrator` (unspecified: the scene's) |
//! | `pb::Exposure` | `restauro_spectral::display::Exposure` |
//! | `pb::RetinexOptions` | `restauro_scene::job::RetinexOptions` |
//! | `pb::SubmitJobRequest` | `restauro_scene::job::JobSpec` (and the manifest) |
//! | `pb::Plan` | `restauro_scene::plan::Plan` |
//! | `pb::SceneLimits` | `restauro_scene::limits::Limits` |
//! | `pb::Rect` | `restauro_scene::plan::Rect` |

use crate::pb;
use restauro_scene::job::{JobName, JobSpec, JobSpecError, RetinexOptions, option_count};
use restauro_scene::limits::Limits;
use restauro_scene::plan::{Plan, Rect, RenderOptions};
use restauro_scene::scene_file::{Integrator, Pose};
use restauro_scene::sequence::Frame;
use restauro_spectral::display::Exposure;
use std::num::NonZeroU32;

/// A wire message the domain cannot hold: the field and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct WireError {
    pub field: String,
    pub problem: String,
}

impl WireError {
    pub fn new(field: impl Into<String>, problem: impl Into<String>) -> Self {
        Self { field: field.into(), problem: problem.into() }
    }

    pub fn missing(field: &str) -> Self {
        Self::new(field, "missing")
    }
}

impl From<JobSpecError> for WireError {
    fn from(e: JobSpecError) -> Self {
        Self::new(e.field, e.problem)
    }
}

/// The integrator a wire value names; `None` for the scene's own.
pub fn integrator_from_wire(value: i32, field: &str) -> Result<Option<Integrator>, WireError> {
    match pb::Integrator::try_from(value) {
        Ok(pb::Integrator::Unspecified) => Ok(None),
        Ok(pb::Integrator::Whitted) => Ok(Some(Integrator::Whitted)),
        Ok(pb::Integrator::Path) => Ok(Some(Integrator::Path)),
        Err(_) => Err(WireError::new(field, format!("unknown integrator {value}"))),
    }
}

impl From<Option<Integrator>> for pb::Integrator {
    fn from(i: Option<Integrator>) -> Self {
        match i {
            None => pb::Integrator::Unspecified,
            Some(Integrator::Whitted) => pb::Integrator::Whitted,
            Some(Integrator::Path) => pb::Integrator::Path,
        }
    }
}

impl TryFrom<pb::RenderOptions> for RenderOptions {
    type Error = WireError;
    fn try_from(o: pb::RenderOptions) -> Result<Self, WireError> {
        let count = |field, value: Option<u32>| value.map(|v| option_count(field, v)).transpose();
        Ok(RenderOptions {
            integrator: integrator_from_wire(o.integrator, "render.integrator")?,
            variant: o.variant,
            samples_per_pixel: count("render.samples_per_pixel", o.samples_per_pixel)?,
            width: count("render.width", o.width)?,
            height: count("render.height", o.height)?,
            spectral: o.spectral,
            tile: count("render.tile", o.tile)?,
            grids: o.grids,
            noise_target: o.noise_target,
        })
    }
}

impl From<&RenderOptions> for pb::RenderOptions {
    fn from(o: &RenderOptions) -> Self {
        pb::RenderOptions {
            variant: o.variant.clone(),
            integrator: pb::Integrator::from(o.integrator) as i32,
            samples_per_pixel: o.samples_per_pixel.map(NonZeroU32::get),
            width: o.width.map(NonZeroU32::get),
            height: o.height.map(NonZeroU32::get),
            spectral: o.spectral,
            tile: o.tile.map(NonZeroU32::get),
            grids: o.grids,
            noise_target: o.noise_target,
        }
    }
}

/// An absent mode (or an absent message: `unwrap_or_default`) is the default exposure.
impl TryFrom<pb::Exposure> for Exposure {
    type Error = WireError;
    fn try_from(e: pb::Exposure) -> Result<Self, WireError> {
        use pb::exposure::Mode;
        let exposure = match e.mode {
            None => Exposure::default(),
            Some(Mode::AutomaticKey(key)) => Exposure::Automatic { key },
            Some(Mode::AbsoluteWhiteCdM2(white_cd_m2)) => Exposure::Absolute { white_cd_m2 },
            Some(Mode::Relative(true)) => Exposure::Relative,
            Some(Mode::Relative(false)) => {
                return Err(WireError::new("exposure.relative", "false; leave the mode out"));
            }
        };
        exposure.checked().map_err(|e| WireError::new("exposure", e.to_string()))
    }
}

impl From<Exposure> for pb::Exposure {
    fn from(e: Exposure) -> Self {
        use pb::exposure::Mode;
        let mode = match e {
            Exposure::Automatic { key } => Mode::AutomaticKey(key),
            Exposure::Absolute { white_cd_m2 } => Mode::AbsoluteWhiteCdM2(white_cd_m2),
            Exposure::Relative => Mode::Relative(true),
        };
        pb::Exposure { mode: Some(mode) }
    }
}

impl TryFrom<pb::RetinexOptions> for RetinexOptions {
    type Error = WireError;
    fn try_from(r: pb::RetinexOptions) -> Result<Self, WireError> {
        Ok(RetinexOptions::new(r.paths, r.seed)?)
    }
}

impl From<RetinexOptions> for pb::RetinexOptions {
    fn from(r: RetinexOptions) -> Self {
        pb::RetinexOptions { paths: Some(r.paths), seed: Some(r.seed) }
    }
}

/// The job of a submission (its manifest stays in the request: it is the scene, checked when
/// the coordinator loads it).
impl TryFrom<&pb::SubmitJobRequest> for JobSpec {
    type Error = WireError;
    fn try_from(r: &pb::SubmitJobRequest) -> Result<Self, WireError> {
        let spec = JobSpec {
            name: JobName::new(&r.name)?,
            priority: r.priority,
            render: r.render.clone().unwrap_or_default().try_into()?,
            exposure: r.exposure.unwrap_or_default().try_into()?,
            retinex: r.retinex.unwrap_or_default().try_into()?,
            frames: r.frames.iter().cloned().map(Frame::try_from).collect::<Result<_, _>>()?,
        };
        Ok(spec.checked()?)
    }
}

/// A submission of `spec` for the scene of `manifest_json`.
pub fn submit_request(manifest_json: String, spec: &JobSpec) -> pb::SubmitJobRequest {
    pb::SubmitJobRequest {
        protocol_version: crate::PROTOCOL_VERSION,
        manifest_json,
        render: Some((&spec.render).into()),
        priority: spec.priority,
        name: spec.name.as_str().to_owned(),
        exposure: Some(spec.exposure.into()),
        retinex: Some(spec.retinex.into()),
        frames: spec.frames.iter().map(pb::Frame::from).collect(),
    }
}

impl From<&Frame> for pb::Frame {
    fn from(f: &Frame) -> Self {
        pb::Frame {
            label: f.label.clone(),
            datetime: f.datetime.clone(),
            camera: f.camera.as_ref().map(|c| pb::Pose {
                position: c.position.to_vec(),
                target: c.target.to_vec(),
                up: c.up.to_vec(),
                vertical_fov_deg: c.vertical_fov_deg,
            }),
            variant: f.variant.clone(),
            elapsed_s: f.elapsed_s,
        }
    }
}

/// A frame as sent; what it holds is checked with the job (`Frame::check`).
impl TryFrom<pb::Frame> for Frame {
    type Error = WireError;
    fn try_from(f: pb::Frame) -> Result<Self, WireError> {
        let three = |field: &str, v: Vec<f64>| {
            <[f64; 3]>::try_from(v).map_err(|v| {
                WireError::new(
                    format!("frames.camera.{field}"),
                    format!("{} numbers; give 3", v.len()),
                )
            })
        };
        let camera = match f.camera {
            Some(c) => Some(Pose {
                position: three("position", c.position)?,
                target: three("target", c.target)?,
                up: three("up", c.up)?,
                vertical_fov_deg: c.vertical_fov_deg,
            }),
            None => None,
        };
        Ok(Frame {
            label: f.label,
            datetime: f.datetime,
            camera,
            variant: f.variant,
            elapsed_s: f.elapsed_s,
        })
    }
}

impl From<&Plan> for pb::Plan {
    fn from(p: &Plan) -> Self {
        pb::Plan {
            width: p.width,
            height: p.height,
            variant: p.variant.clone(),
            integrator: pb::Integrator::from(Some(p.integrator)) as i32,
            samples_per_pixel: p.samples_per_pixel,
            max_depth: p.max_depth,
            seed: p.seed,
            spectral: p.spectral,
            sky: p.sky,
            lit: p.lit,
            white: p.white,
            tile: p.tile,
            grids: p.grids,
            noise_target: p.noise_target,
        }
    }
}

/// A plan as sent; its numbers are checked against the limits it came with by the receiver
/// (`Plan::check`), since only the receiver knows them.
impl TryFrom<pb::Plan> for Plan {
    type Error = WireError;
    fn try_from(p: pb::Plan) -> Result<Self, WireError> {
        let integrator = integrator_from_wire(p.integrator, "plan.integrator")?
            .ok_or_else(|| WireError::new("plan.integrator", "unspecified in a resolved plan"))?;
        Ok(Plan {
            width: p.width,
            height: p.height,
            variant: p.variant,
            integrator,
            samples_per_pixel: p.samples_per_pixel,
            max_depth: p.max_depth,
            seed: p.seed,
            spectral: p.spectral,
            sky: p.sky,
            lit: p.lit,
            white: p.white,
            tile: p.tile,
            grids: p.grids,
            noise_target: p.noise_target,
        })
    }
}

impl From<&Limits> for pb::SceneLimits {
    fn from(l: &Limits) -> Self {
        pb::SceneLimits {
            max_pixels: l.max_pixels,
            max_triangles: l.max_triangles,
            max_samples_per_pixel: l.max_samples_per_pixel,
            max_depth: l.max_depth,
            max_file_bytes: l.max_file_bytes,
            max_spectral_pixels: l.max_spectral_pixels,
            max_tiles: l.max_tiles,
            min_tile: l.min_tile,
            max_instances: l.max_instances,
            max_polygon_vertices: l.max_polygon_vertices,
            max_frames: l.max_frames,
            max_job_tiles: l.max_job_tiles,
        }
    }
}

impl From<pb::SceneLimits> for Limits {
    fn from(l: pb::SceneLimits) -> Self {
        Limits {
            max_pixels: l.max_pixels,
            max_triangles: l.max_triangles,
            max_samples_per_pixel: l.max_samples_per_pixel,
            max_depth: l.max_depth,
            max_file_bytes: l.max_file_bytes,
            max_spectral_pixels: l.max_spectral_pixels,
            max_tiles: l.max_tiles,
            min_tile: l.min_tile.max(1),
            max_instances: l.max_instances,
            max_polygon_vertices: l.max_polygon_vertices,
            max_frames: l.max_frames,
            max_job_tiles: l.max_job_tiles,
        }
    }
}

impl From<Rect> for pb::Rect {
    fn from(r: Rect) -> Self {
        pb::Rect { x: r.x, y: r.y, width: r.width, height: r.height }
    }
}

impl From<pb::Rect> for Rect {
    fn from(r: pb::Rect) -> Self {
        Rect { x: r.x, y: r.y, width: r.width, height: r.height }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_spec_survives_the_wire() {
        let spec = JobSpec {
            name: JobName::new("aosta-cleaned").unwrap(),
            priority: -3,
            render: RenderOptions {
                variant: Some("cleaned".into()),
                integrator: Some(Integrator::Path),
                samples_per_pixel: NonZeroU32::new(9),
                width: NonZeroU32::new(320),
                height: None,
                spectral: true,
                tile: NonZeroU32::new(32),
                grids: true,
                noise_target: Some(0.02),
            },
            exposure: Exposure::Absolute { white_cd_m2: 120.0 },
            retinex: RetinexOptions::new(Some(40), Some(7)).unwrap(),
            frames: Vec::new(),
        };
        let wire = submit_request("{}".into(), &spec);
        assert_eq!(JobSpec::try_from(&wire).unwrap(), spec);
        let pose = Pose {
            position: [1.0, -2.0, 1.7],
            target: [0.0, 0.0, 9.0],
            up: [0.0, 0.0, 1.0],
            vertical_fov_deg: 50.0,
        };
        let frames = vec![
            Frame {
                label: "06:15".into(),
                datetime: Some("2026-07-15T06:15:00+02:00".into()),
                camera: None,
                variant: None,
                elapsed_s: Some(900.0),
            },
            Frame {
                label: "1.00 s".into(),
                datetime: None,
                camera: Some(pose),
                variant: None,
                elapsed_s: Some(901.0),
            },
        ];
        let render = RenderOptions { grids: false, ..spec.render.clone() };
        let sequence = JobSpec { frames, render, ..spec };
        let wire = submit_request("{}".into(), &sequence);
        assert_eq!(JobSpec::try_from(&wire).unwrap(), sequence);
        let mut short = wire.clone();
        short.frames[1].camera.as_mut().unwrap().target.pop();
        let e = JobSpec::try_from(&short).unwrap_err();
        assert_eq!(e.field, "frames.camera.target");
    }

    #[test]
    fn what_the_domain_cannot_hold_is_refused_naming_the_field() {
        let ok = submit_request("{}".into(), &JobSpec::default());
        let field = |r: pb::SubmitJobRequest| JobSpec::try_from(&r).unwrap_err().field;
        let mut r = ok.clone();
        r.render.as_mut().unwrap().integrator = 9;
        assert_eq!(field(r), "render.integrator");
        let mut r = ok.clone();
        r.retinex = Some(pb::RetinexOptions { paths: Some(4_000_000_000), seed: None });
        assert_eq!(field(r), "retinex.paths");
        let mut r = ok.clone();
        r.name = "x".repeat(100_000);
        assert_eq!(field(r), "name");
        let mut r = ok.clone();
        r.exposure =
            Some(pb::Exposure { mode: Some(pb::exposure::Mode::AbsoluteWhiteCdM2(f64::NAN)) });
        assert_eq!(field(r), "exposure");
        for bad in [f32::NAN, -0.01, 0.6, f32::INFINITY] {
            let mut r = ok.clone();
            r.render.as_mut().unwrap().noise_target = Some(bad);
            assert_eq!(field(r), "render.noise_target", "{bad}");
        }
        type Zero = fn(&mut pb::RenderOptions);
        let zeroes: [(&str, Zero); 4] = [
            ("render.samples_per_pixel", |o| o.samples_per_pixel = Some(0)),
            ("render.width", |o| o.width = Some(0)),
            ("render.height", |o| o.height = Some(0)),
            ("render.tile", |o| o.tile = Some(0)),
        ];
        for (name, zero) in zeroes {
            let mut r = ok.clone();
            zero(r.render.as_mut().unwrap());
            assert_eq!(field(r), name);
        }
    }

    #[test]
    fn a_plan_survives_the_wire_and_needs_an_integrator() {
        let plan = Plan {
            width: 64,
            height: 48,
            variant: None,
            integrator: Integrator::Whitted,
            samples_per_pixel: 4,
            max_depth: 5,
            seed: 11,
            spectral: false,
            sky: true,
            lit: true,
            white: true,
            tile: 16,
            grids: true,
            noise_target: 0.05,
        };
        assert_eq!(Plan::try_from(pb::Plan::from(&plan)).unwrap(), plan);
        let unspecified = pb::Plan { integrator: 0, ..pb::Plan::from(&plan) };
        assert_eq!(Plan::try_from(unspecified).unwrap_err().field, "plan.integrator");
        let limits = Limits { max_tiles: 12, ..Limits::default() };
        assert_eq!(Limits::from(pb::SceneLimits::from(&limits)), limits);
    }
}
