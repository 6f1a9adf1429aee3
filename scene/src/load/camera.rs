//! The `[camera]` table and the saved `[[views]]`: the camera resolved into world coordinates
//! (from its position and target, or through a viewpoint of an imported model), its image
//! within the pixel limit, and every pose, the camera's and each view's, one the tracer can
//! look from.

use super::objects::Viewpoints;
use super::{Ctx, Limits, check_point, unknown};
use crate::error::Result;
use crate::scene_file::{self, Pose};
use glam::{DMat3, DVec3};
use serde::Serialize;

/// The camera: a [`Pose`] in world coordinates and the image it takes. The studio sends it to
/// the page in the preview's coordinates, the same fields side by side.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ResolvedCamera {
    #[serde(flatten)]
    pub pose: Pose,
    pub width: u32,
    pub height: u32,
}

/// The camera: an image of at least one pixel and within the pixel limit, looking from its
/// position at its target or through a model's viewpoint, in a pose [`check_pose`] accepts.
pub(super) fn resolve_camera(
    ctx: &Ctx,
    limits: &Limits,
    viewpoints: &Viewpoints,
) -> Result<ResolvedCamera> {
    let c = &ctx.file.camera;
    if c.width == 0 || c.height == 0 {
        return Err(ctx.invalid("camera", "width and height must be at least 1 pixel"));
    }
    let pixels = u64::from(c.width) * u64::from(c.height);
    if pixels > limits.max_pixels {
        return Err(ctx.limit(
            "the image size (pixels)",
            pixels,
            limits.max_pixels,
            "render smaller, or raise the limit with --max-pixels",
        ));
    }
    let camera = match &c.viewpoint {
        Some(vp) => viewpoint_camera(ctx, c, vp, viewpoints)?,
        None => {
            let (Some(position), Some(target)) = (c.position, c.target) else {
                return Err(ctx.invalid("camera", "give position and target, or a viewpoint"));
            };
            ResolvedCamera {
                pose: Pose { position, target, up: c.up, vertical_fov_deg: c.vertical_fov_deg },
                width: c.width,
                height: c.height,
            }
        }
    };
    check_pose(ctx, "camera", &camera.pose)?;
    Ok(camera)
}

/// The camera looking through viewpoint `vp` of an imported model, carried into the world by
/// the model's placement.
fn viewpoint_camera(
    ctx: &Ctx,
    c: &scene_file::Camera,
    vp: &scene_file::ViewpointRef,
    viewpoints: &Viewpoints,
) -> Result<ResolvedCamera> {
    let file = ctx.file;
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
    Ok(ResolvedCamera {
        pose: Pose {
            position: position.to_array(),
            target: to_world(pos + look).to_array(),
            up: matrix.transform_vector3(up).normalize_or(DVec3::Z).to_array(),
            vertical_fov_deg: f64::from(v.field_of_view).to_degrees(),
        },
        width: c.width,
        height: c.height,
    })
}

/// A pose (the camera's, a view's) the tracer can look from: every point in range, the target
/// away from the eye, up not along the line of sight, a field of view between 0° and 180°.
pub(super) fn check_pose(ctx: &Ctx, place: &str, pose: &Pose) -> Result<()> {
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

/// Every saved view: a name of its own, and a pose [`check_pose`] accepts.
pub(super) fn check_views(ctx: &Ctx, views: &[scene_file::View]) -> Result<()> {
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
        check_pose(ctx, &place, &v.pose())?;
    }
    Ok(())
}
