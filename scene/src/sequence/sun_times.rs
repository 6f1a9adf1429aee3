//! Frames of the sun's times at the scene's site: a day from one clock time to another at a
//! step, or one clock time on several dates. Clock times are the site's: the UTC offset of the
//! scene's own date-time (a summer scene written `+02:00` keeps `+02:00`).

use super::Frame;
use crate::error::{Result, SceneError};
use crate::limits::Limits;
use crate::scene_file::{Light, SceneFile, SiteTime, SkyModel};
use crate::sun::{Site, sun_position};
use chrono::{DateTime, FixedOffset, NaiveDate, NaiveTime, TimeDelta};
use std::path::Path;

/// The step between two frames of a day, in whole seconds (at least one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Every(std::num::NonZeroU32);

impl Every {
    pub fn seconds(self) -> u32 {
        self.0.get()
    }
}

/// A step as a person writes it: `15m`, `1h`, `90s`, `1h30m`. Zero is refused.
pub fn parse_every(text: &str) -> std::result::Result<Every, String> {
    let usage = "write it as minutes, hours or seconds, e.g. 15m, 1h, 90s or 1h30m";
    let mut seconds: u64 = 0;
    let mut digits = String::new();
    for c in text.trim().chars() {
        if c.is_ascii_digit() {
            digits.push(c);
            continue;
        }
        let unit = match c {
            'h' => 3600,
            'm' => 60,
            's' => 1,
            _ => return Err(format!("`{text}`: `{c}` is not a unit; {usage}")),
        };
        let n: u64 =
            digits.parse().map_err(|_| format!("`{text}`: a number before `{c}`; {usage}"))?;
        seconds = seconds.saturating_add(n.saturating_mul(unit));
        digits.clear();
    }
    if !digits.is_empty() || text.trim().is_empty() {
        return Err(format!("`{text}` has no unit; {usage}"));
    }
    let seconds = u32::try_from(seconds).unwrap_or(u32::MAX);
    std::num::NonZeroU32::new(seconds)
        .map(Every)
        .ok_or_else(|| format!("a step of zero never moves the sun; {usage}"))
}

/// The scene's site and its own date-time: the first light with a site.
fn scene_site<'a>(scene: &'a SceneFile, path: &Path) -> Result<&'a SiteTime> {
    scene
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Sun { site: Some(s), .. } | Light::Sky { site: Some(s), .. } => Some(s),
            _ => None,
        })
        .ok_or_else(|| SceneError::invalid(path, "lights", super::NO_SITE))
}

fn scene_time(site: &SiteTime, path: &Path) -> Result<DateTime<FixedOffset>> {
    DateTime::parse_from_rfc3339(&site.datetime).map_err(|e| {
        SceneError::invalid(path, "lights.site.datetime", format!("`{}`: {e}", site.datetime))
    })
}

/// `date` at `time` in `offset`, as RFC 3339.
fn at(date: NaiveDate, time: NaiveTime, offset: FixedOffset) -> String {
    let local = date.and_time(time);
    // A fixed offset has exactly one local time for every instant.
    let instant = local.and_local_timezone(offset).single().expect("a fixed offset is unambiguous");
    instant.to_rfc3339()
}

/// The sun's elevation at `site` at `datetime`, degrees.
fn elevation_deg(site: &SiteTime, datetime: &str, path: &Path) -> Result<f64> {
    let s = Site::new(site.latitude_deg, site.longitude_deg, site.height_m);
    sun_position(s, datetime, None)
        .map(|p| p.elevation_deg)
        .map_err(|e| SceneError::invalid(path, "lights.site", e.to_string()))
}

/// Whether a sky of `scene` takes its shape from the scene's sun (a CIE general sky given
/// neither its own sun position nor its own site): it has no shape while the sun is down.
fn sky_shaped_by_the_sun(scene: &SceneFile) -> bool {
    scene.lights.iter().any(|l| {
        matches!(
            l,
            Light::Sky {
                model: Some(SkyModel::CieGeneral),
                site: None,
                sun_elevation_deg: None,
                ..
            }
        )
    })
}

/// Refuses a sequence of times in which the sun never rises, and one with a time at which it is
/// down when the scene's sky is shaped by it.
fn check_sees_sun(scene: &SceneFile, site: &SiteTime, frames: &[Frame], path: &Path) -> Result<()> {
    let mut highest: Option<(f64, &str)> = None;
    let shaped = sky_shaped_by_the_sun(scene);
    for f in frames {
        let e = elevation_deg(site, f.datetime.as_deref().unwrap_or_default(), path)?;
        if highest.is_none_or(|(h, _)| e > h) {
            highest = Some((e, &f.label));
        }
        if shaped && e <= 0.0 {
            return Err(SceneError::invalid(
                path,
                "sequence",
                format!(
                    "at {} the sun is below the horizon ({e:.1}°), and the scene's CIE general \
                     sky takes its shape from the sun; choose times between sunrise and sunset, \
                     or give the sky a shape of its own (sun_elevation_deg and sun_azimuth_deg)",
                    f.label
                ),
            ));
        }
    }
    match highest {
        Some((e, label)) if e <= 0.0 => Err(SceneError::invalid(
            path,
            "sequence",
            format!(
                "the sun never rises in this range at latitude {:.4}°, longitude {:.4}° (highest \
                 {e:.1}° at {label}); choose hours between sunrise and sunset, or another date",
                site.latitude_deg, site.longitude_deg
            ),
        )),
        _ => Ok(()),
    }
}

/// The day from `from` to `to` every `every`, on `date` or the scene's own date.
pub(super) fn day(
    scene: &SceneFile,
    path: &Path,
    date: Option<NaiveDate>,
    from: NaiveTime,
    to: NaiveTime,
    every: Every,
    limits: &Limits,
) -> Result<Vec<Frame>> {
    let site = scene_site(scene, path)?;
    let own = scene_time(site, path)?;
    let date = date.unwrap_or_else(|| own.date_naive());
    if to < from {
        return Err(SceneError::invalid(
            path,
            "sequence",
            format!(
                "the day runs from {from} to {to}, backwards; give an end after the start \
                 (--to after --sun-from)"
            ),
        ));
    }
    let span_s = (to - from).num_seconds().max(0) as u64;
    let count = span_s / u64::from(every.seconds()) + 1;
    super::check_count(count as usize, path, limits)?;
    let frames: Vec<Frame> = (0..count)
        .map(|k| {
            let time = from + TimeDelta::seconds((k * u64::from(every.seconds())) as i64);
            let label = if every.seconds().is_multiple_of(60) {
                time.format("%H:%M").to_string()
            } else {
                time.format("%H:%M:%S").to_string()
            };
            Frame {
                label,
                datetime: Some(at(date, time, *own.offset())),
                camera: None,
                variant: None,
                elapsed_s: Some((k * u64::from(every.seconds())) as f64),
            }
        })
        .collect();
    check_sees_sun(scene, site, &frames, path)?;
    Ok(frames)
}

/// One clock time on each of `dates`.
pub(super) fn dates(
    scene: &SceneFile,
    path: &Path,
    dates: &[NaiveDate],
    time: NaiveTime,
) -> Result<Vec<Frame>> {
    let site = scene_site(scene, path)?;
    let own = scene_time(site, path)?;
    if dates.is_empty() {
        return Err(SceneError::invalid(
            path,
            "sequence",
            "no dates; give them as --dates 2026-03-20,2026-06-21,2026-12-21",
        ));
    }
    let frames: Vec<Frame> = dates
        .iter()
        .map(|&d| Frame {
            label: format!("{d} {}", time.format("%H:%M")),
            datetime: Some(at(d, time, *own.offset())),
            camera: None,
            variant: None,
            elapsed_s: None,
        })
        .collect();
    check_sees_sun(scene, site, &frames, path)?;
    Ok(frames)
}
