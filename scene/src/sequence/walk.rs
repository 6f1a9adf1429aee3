//! A walk through saved views: the eye moves along a smooth curve through the views' positions
//! at a walking speed, and looks along a curve through their targets; one frame every
//! `1 / fps` seconds.
//!
//! The curve is a uniform Catmull–Rom spline (Catmull & Rom, "A class of local interpolating
//! splines", 1974): it passes through every view, with a continuous tangent, and each piece
//! depends only on the four views around it. The ends are extended by reflection (a phantom
//! view beyond each end), so the walk starts and ends heading straight for its neighbour. Frames
//! are spaced by arc length, so the eye moves at the same speed along short and long pieces;
//! the walk ends at the last whole step before the last view.

use super::Frame;
use crate::error::{Result, SceneError};
use crate::limits::Limits;
use crate::scene_file::{Pose, SceneFile, View};
use std::path::Path;

/// A person's walking pace, as the studio's walk mode moves (m/s).
pub const WALKING_SPEED_M_S: f64 = 1.4;

/// Samples of each piece of the curve for its arc length.
const LENGTH_SAMPLES: usize = 64;

type V3 = [f64; 3];

fn lerp(a: V3, b: V3, t: f64) -> V3 {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

fn distance(a: V3, b: V3) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The uniform Catmull–Rom piece from `p1` (t = 0) to `p2` (t = 1).
fn catmull_rom(p0: V3, p1: V3, p2: V3, p3: V3, t: f64) -> V3 {
    let (t2, t3) = (t * t, t * t * t);
    std::array::from_fn(|i| {
        0.5 * (2.0 * p1[i]
            + (p2[i] - p0[i]) * t
            + (2.0 * p0[i] - 5.0 * p1[i] + 4.0 * p2[i] - p3[i]) * t2
            + (3.0 * p1[i] - p0[i] - 3.0 * p2[i] + p3[i]) * t3)
    })
}

/// A spline through `points` (at least two), evaluated on piece `i` at `t`.
fn on_curve(points: &[V3], i: usize, t: f64) -> V3 {
    let n = points.len();
    let reflect = |a: V3, b: V3| lerp(b, a, 2.0); // a + (a − b): the phantom beyond `a`
    let p0 = if i == 0 { reflect(points[0], points[1]) } else { points[i - 1] };
    let p3 = if i + 2 >= n { reflect(points[n - 1], points[n - 2]) } else { points[i + 2] };
    catmull_rom(p0, points[i], points[i + 1], p3, t)
}

/// The views named, in order.
fn named_views<'a>(scene: &'a SceneFile, path: &Path, names: &[String]) -> Result<Vec<&'a View>> {
    if names.len() < 2 {
        return Err(SceneError::invalid(
            path,
            "sequence",
            format!(
                "a walk needs at least two saved views to walk between, and {} given; name them \
                 in order (--path VIEW,VIEW,…; the scene saves {})",
                names.len(),
                list(scene)
            ),
        ));
    }
    names
        .iter()
        .map(|name| {
            scene.views.iter().find(|v| &v.name == name).ok_or_else(|| {
                SceneError::invalid(
                    path,
                    "sequence",
                    crate::load::unknown("view", name, scene.views.iter().map(|v| v.name.as_str())),
                )
            })
        })
        .collect()
}

fn list(scene: &SceneFile) -> String {
    if scene.views.is_empty() {
        return "none: save views in the studio or as [[views]] in the scene file".into();
    }
    scene.views.iter().map(|v| format!("`{}`", v.name)).collect::<Vec<_>>().join(", ")
}

/// The frames of a walk through `names` at `speed_m_s`, `fps` frames a second.
pub(super) fn frames(
    scene: &SceneFile,
    path: &Path,
    names: &[String],
    fps: f64,
    speed_m_s: f64,
    limits: &Limits,
) -> Result<Vec<Frame>> {
    let refuse = |problem: String| SceneError::invalid(path, "sequence", problem);
    if !(fps.is_finite() && fps > 0.0 && fps <= 240.0) {
        return Err(refuse(format!(
            "{fps} frames a second; give a frame rate between 0 and 240, e.g. 25 (--fps)"
        )));
    }
    if !(speed_m_s.is_finite() && speed_m_s > 0.0 && speed_m_s <= 100.0) {
        return Err(refuse(format!(
            "a speed of {speed_m_s} m/s; give a walking speed between 0 and 100 m/s \
             ({WALKING_SPEED_M_S} is a person walking; --speed)"
        )));
    }
    let views = named_views(scene, path, names)?;
    let positions: Vec<V3> = views.iter().map(|v| v.position).collect();
    let targets: Vec<V3> = views.iter().map(|v| v.target).collect();
    for (i, w) in positions.windows(2).enumerate() {
        if distance(w[0], w[1]) < 1e-6 {
            return Err(refuse(format!(
                "views `{}` and `{}` stand at the same place, so the walk between them has no \
                 length; drop one or save it where the eye moves",
                names[i],
                names[i + 1]
            )));
        }
    }
    // The arc length at each sample: (piece, t) ↦ distance walked.
    let pieces = positions.len() - 1;
    let mut table = Vec::with_capacity(pieces * LENGTH_SAMPLES + 1);
    table.push((0usize, 0.0f64, 0.0f64));
    let mut walked = 0.0;
    let mut last = positions[0];
    for i in 0..pieces {
        for k in 1..=LENGTH_SAMPLES {
            let t = k as f64 / LENGTH_SAMPLES as f64;
            let p = on_curve(&positions, i, t);
            walked += distance(last, p);
            last = p;
            table.push((i, t, walked));
        }
    }
    let step_m = speed_m_s / fps;
    let count = (walked / step_m).floor() as u64 + 1;
    super::check_count(usize::try_from(count).unwrap_or(usize::MAX), path, limits)?;
    let mut frames = Vec::with_capacity(count as usize);
    let mut at = 0;
    for k in 0..count {
        let s = k as f64 * step_m;
        while at + 1 < table.len() && table[at + 1].2 < s {
            at += 1;
        }
        let (piece, t) = locate(&table, at, s);
        let up = lerp(views[piece].up, views[piece + 1].up, t);
        let fov = views[piece].vertical_fov_deg
            + (views[piece + 1].vertical_fov_deg - views[piece].vertical_fov_deg) * t;
        frames.push(Frame {
            label: format!("{:.2} s, {s:.1} m", k as f64 / fps),
            datetime: None,
            camera: Some(Pose {
                position: on_curve(&positions, piece, t),
                target: on_curve(&targets, piece, t),
                up,
                vertical_fov_deg: fov,
            }),
            variant: None,
            elapsed_s: Some(k as f64 / fps),
        });
    }
    Ok(frames)
}

/// The piece and parameter at arc length `s`, between samples `at` and `at + 1`.
fn locate(table: &[(usize, f64, f64)], at: usize, s: f64) -> (usize, f64) {
    let (i0, t0, s0) = table[at];
    let Some(&(i1, t1, s1)) = table.get(at + 1) else { return (i0, t0) };
    // Two samples on either side of a piece's end: the later piece starts at t = 0.
    let t0 = if i1 != i0 { 0.0 } else { t0 };
    let f = if s1 > s0 { ((s - s0) / (s1 - s0)).clamp(0.0, 1.0) } else { 0.0 };
    (i1, t0 + (t1 - t0) * f)
}
