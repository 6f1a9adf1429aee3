//! A sequence: frames of one scene that differ by the sun's time, by where the eye stands, or by
//! the restoration hypothesis. A [`Frame`] is what one frame changes; applied to the scene file
//! ([`Frame::apply`]) it gives exactly the scene that frame is, so a frame rendered on the farm
//! within its sequence is bit for bit the same frame rendered alone (the seed never depends on
//! the frame).
//!
//! A sequence as a person asks for it ([`Sequence`]: the day from 06:00 to 21:00 every 15
//! minutes, noon at the solstices, a walk through saved views at 1.4 m/s) is expanded into its
//! frames here, once, by the client; the farm receives the frames.

mod sun_times;
mod walk;

use crate::error::{Result, SceneError};
use crate::job::{JobSpecError, check_label};
use crate::limits::Limits;
use crate::scene_file::{Light, Pose, SceneFile};
use serde::{Deserialize, Serialize};
use std::path::Path;

pub use sun_times::{Every, parse_every};
pub use walk::WALKING_SPEED_M_S;

/// What one frame changes of the scene; `None` keeps the scene's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    /// What the frame is, as a contact sheet or a timeline shows it (`06:15`, `2026-12-21
    /// 12:00`, `3.20 s, 4.5 m`, `cleaned`).
    pub label: String,
    /// The date-time (RFC 3339 with its UTC offset) of every light with a site: the sun, and a
    /// sky shaped by its own sun.
    #[serde(default)]
    pub datetime: Option<String>,
    /// The camera's pose, in the scene file's coordinates.
    #[serde(default)]
    pub camera: Option<Pose>,
    /// The restoration hypothesis.
    #[serde(default)]
    pub variant: Option<String>,
    /// The time (s) at which the viewer sees the frame, from the sequence's start: frames in a
    /// row that both have one are seen by an eye that has been adapting between them
    /// (`restauro_spectral::seen::time_course`). A day's frames have their clock's, a walk's
    /// its frame rate's; frames on different dates, or of different hypotheses, have none and
    /// are each seen alone.
    #[serde(default)]
    pub elapsed_s: Option<f64>,
}

/// The latest time of a frame in a sequence (s): a year.
pub const MAX_ELAPSED_S: f64 = 3.15e7;

/// Refuses frames whose times go back: `frames[index]` against the frame before it.
pub fn check_times(frames: &[Frame]) -> std::result::Result<(), JobSpecError> {
    for (index, pair) in frames.windows(2).enumerate() {
        if let (Some(a), Some(b)) = (pair[0].elapsed_s, pair[1].elapsed_s)
            && b < a
        {
            return Err(JobSpecError {
                field: "frames",
                problem: format!(
                    "frame {} is at {b} s, before frame {index} at {a} s; a sequence's times \
                     must not go back",
                    index + 1
                ),
            });
        }
    }
    Ok(())
}

/// The most characters of a frame's label.
pub const MAX_LABEL_CHARS: usize = 64;

impl Frame {
    /// The scene of this frame: `scene` with the frame's date-time and camera. Refused when the
    /// frame has a date-time and no light of the scene has a site to give it to.
    pub fn apply(&self, scene: &mut SceneFile, path: &Path) -> Result<()> {
        if let Some(datetime) = &self.datetime {
            let mut given = false;
            for light in &mut scene.lights {
                if let Light::Sun { site: Some(site), .. } | Light::Sky { site: Some(site), .. } =
                    light
                {
                    site.datetime.clone_from(datetime);
                    given = true;
                }
            }
            if !given {
                return Err(SceneError::invalid(path, "lights", NO_SITE));
            }
        }
        if let Some(pose) = &self.camera {
            let camera = &mut scene.camera;
            camera.position = Some(pose.position);
            camera.target = Some(pose.target);
            camera.up = pose.up;
            camera.vertical_fov_deg = pose.vertical_fov_deg;
            camera.viewpoint = None;
        }
        Ok(())
    }

    /// Checks what a frame from the wire carries: its label printable, its date-time one the
    /// sun's position can be computed for, its camera finite, its variant named. `index`
    /// counts from 0.
    pub fn check(&self, index: usize) -> std::result::Result<(), JobSpecError> {
        let refuse = |problem: String| JobSpecError {
            field: "frames",
            problem: format!(
                "frame {index} ({}): {problem}",
                crate::job::printable(&self.label, 64)
            ),
        };
        check_label("frames", &self.label, MAX_LABEL_CHARS)
            .map_err(|e| refuse(format!("label: {}", e.problem)))?;
        if let Some(datetime) = &self.datetime {
            chrono::DateTime::parse_from_rfc3339(datetime).map_err(|e| {
                refuse(format!(
                    "datetime `{}` is not RFC 3339 ({e}); write it with its UTC offset, e.g. \
                     2026-07-15T16:30:00+02:00",
                    crate::job::printable(datetime, 64)
                ))
            })?;
        }
        if let Some(pose) = &self.camera {
            let placeable = |v: &[f64; 3]| {
                v.iter().all(|x| x.is_finite() && x.abs() <= crate::limits::MAX_COORDINATE_M)
            };
            if !(placeable(&pose.position) && placeable(&pose.target) && placeable(&pose.up)) {
                return Err(refuse(format!(
                    "camera: every coordinate must be a finite number within ±{:e} m",
                    crate::limits::MAX_COORDINATE_M
                )));
            }
            if pose.position == pose.target {
                return Err(refuse("camera: the target is the position; look somewhere".into()));
            }
            if !(pose.vertical_fov_deg > 0.0 && pose.vertical_fov_deg < 180.0) {
                return Err(refuse(format!(
                    "camera: vertical_fov_deg {} must be between 0 and 180",
                    pose.vertical_fov_deg
                )));
            }
        }
        if let Some(t) = self.elapsed_s
            && !(t.is_finite() && (0.0..=MAX_ELAPSED_S).contains(&t))
        {
            return Err(refuse(format!(
                "elapsed_s {t} must be a number of seconds from 0 to {MAX_ELAPSED_S:e} (a year)"
            )));
        }
        if self.variant.as_deref().is_some_and(str::is_empty) {
            return Err(refuse("an empty variant name; leave it out instead".into()));
        }
        Ok(())
    }
}

const NO_SITE: &str = "no light has a site and a date-time to change: a sequence of the sun's \
                       times needs a sun placed by `site = { latitude_deg, longitude_deg, \
                       datetime }` (see docs/scene-format.md), not by azimuth and elevation";

/// A sequence as a person asks for it.
#[derive(Clone, Debug, PartialEq)]
pub enum Sequence {
    /// The day at the scene's site: from `from` to `to` (local clock times of the site's UTC
    /// offset) every `every`, on `date` (the scene's own date when `None`).
    Day {
        date: Option<chrono::NaiveDate>,
        from: chrono::NaiveTime,
        to: chrono::NaiveTime,
        every: Every,
    },
    /// The same hour on several dates (the solstices and the equinoxes).
    Dates { dates: Vec<chrono::NaiveDate>, at: chrono::NaiveTime },
    /// A walk through saved views, along a smooth curve at `speed_m_s`, `fps` frames a second.
    Walk { views: Vec<String>, fps: f64, speed_m_s: f64 },
    /// The restoration hypotheses, one frame each.
    Hypotheses { variants: Vec<String> },
}

impl Sequence {
    /// The frames of this sequence of `scene` (the file `path`, for messages), at most
    /// `limits.max_frames`.
    pub fn frames(&self, scene: &SceneFile, path: &Path, limits: &Limits) -> Result<Vec<Frame>> {
        let frames = match self {
            Sequence::Day { date, from, to, every } => {
                sun_times::day(scene, path, *date, *from, *to, *every, limits)?
            }
            Sequence::Dates { dates, at } => sun_times::dates(scene, path, dates, *at)?,
            Sequence::Walk { views, fps, speed_m_s } => {
                walk::frames(scene, path, views, *fps, *speed_m_s, limits)?
            }
            Sequence::Hypotheses { variants } => hypotheses(scene, path, variants)?,
        };
        check_count(frames.len(), path, limits)?;
        Ok(frames)
    }
}

/// Refuses more frames than `limits.max_frames`.
pub fn check_count(frames: usize, path: &Path, limits: &Limits) -> Result<()> {
    if frames as u64 > u64::from(limits.max_frames) {
        return Err(SceneError::Limit {
            path: path.to_owned(),
            what: "frames of a sequence".into(),
            value: frames as u64,
            limit: u64::from(limits.max_frames),
            fix: "take a longer step, a lower --fps or a shorter range, or raise --max-frames"
                .into(),
        });
    }
    Ok(())
}

fn hypotheses(scene: &SceneFile, path: &Path, variants: &[String]) -> Result<Vec<Frame>> {
    if variants.len() < 2 {
        return Err(SceneError::invalid(
            path,
            "variants",
            "a sequence of hypotheses needs at least two variants, e.g. --variants \
             as-found,cleaned",
        ));
    }
    variants
        .iter()
        .map(|v| {
            if !scene.variants.contains_key(v) {
                let known = scene.variants.keys().map(String::as_str);
                return Err(SceneError::invalid(
                    path,
                    "variants",
                    crate::load::unknown("variant", v, known),
                ));
            }
            Ok(Frame {
                label: v.clone(),
                datetime: None,
                camera: None,
                variant: Some(v.clone()),
                elapsed_s: None,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests;
