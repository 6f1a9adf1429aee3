//! Where the sun is: from a site (latitude, longitude, height) and a date-time, by NREL's Solar
//! Position Algorithm (Reda & Andreas, "Solar position algorithm for solar radiation
//! applications", Solar Energy 76(5), 2004; ±0.0003°) as the `solar-positioning` crate
//! implements it; and the direction towards it in restauro's world frame.
//!
//! World frame: +X east, +Y north, +Z up (right-handed), metres. Azimuth is measured from
//! north towards east, as in SPA.

use chrono::{DateTime, FixedOffset};
use solar_positioning::{Location, RefractionCorrection, SolarPositions, delta_t};

/// A position of the sun in the sky, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPosition {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

/// A site on the Earth and its atmosphere (for refraction near the horizon).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    pub height_m: f64,
    /// Mean annual air pressure (mbar) and temperature (°C); refraction is applied with them.
    pub pressure_mbar: f64,
    pub temperature_c: f64,
}

impl Site {
    pub fn new(latitude_deg: f64, longitude_deg: f64, height_m: f64) -> Self {
        // The standard atmosphere at sea level; SPA's refraction term depends weakly on them.
        Self { latitude_deg, longitude_deg, height_m, pressure_mbar: 1013.25, temperature_c: 15.0 }
    }
}

/// Why the sun's position cannot be computed: the date-time, ΔT, the atmosphere or the site.
#[derive(Debug, thiserror::Error)]
pub enum SunError {
    #[error(
        "`{datetime}` is not an RFC 3339 date-time ({error}); write it with its UTC offset, e.g. \
         2026-07-15T16:30:00+02:00"
    )]
    DateTime { datetime: String, error: chrono::ParseError },
    #[error("ΔT for {datetime}: {error}")]
    DeltaT { datetime: String, error: solar_positioning::Error },
    #[error("atmosphere for refraction: {0}")]
    Atmosphere(solar_positioning::Error),
    #[error("solar position at latitude {latitude_deg}, longitude {longitude_deg}: {error}")]
    Position { latitude_deg: f64, longitude_deg: f64, error: solar_positioning::Error },
}

/// The sun's topocentric position at `site` at `datetime` (RFC 3339 with a UTC offset, e.g.
/// `2026-07-15T16:30:00+02:00`). ΔT (TT − UT1) is estimated from the date unless given.
pub fn sun_position(
    site: Site,
    datetime: &str,
    delta_t_s: Option<f64>,
) -> Result<SunPosition, SunError> {
    let time: DateTime<FixedOffset> = DateTime::parse_from_rfc3339(datetime)
        .map_err(|error| SunError::DateTime { datetime: datetime.to_owned(), error })?;
    let dt = match delta_t_s {
        Some(v) => v,
        None => delta_t::estimate_from_date_like(&time)
            .map_err(|error| SunError::DeltaT { datetime: datetime.to_owned(), error })?,
    };
    let refraction = RefractionCorrection::new(site.pressure_mbar, site.temperature_c)
        .map_err(SunError::Atmosphere)?;
    let location = Location { latitude: site.latitude_deg, longitude: site.longitude_deg };
    let p = SolarPositions::new()
        .at(&time, location, site.height_m, dt, Some(refraction))
        .map_err(|error| SunError::Position {
            latitude_deg: site.latitude_deg,
            longitude_deg: site.longitude_deg,
            error,
        })?;
    Ok(SunPosition { azimuth_deg: p.azimuth(), elevation_deg: p.elevation_angle() })
}

/// The unit vector towards the sun in the world frame (+X east, +Y north, +Z up).
pub fn direction_to_sun(position: SunPosition) -> [f64; 3] {
    let (az, el) = (position.azimuth_deg.to_radians(), position.elevation_deg.to_radians());
    [az.sin() * el.cos(), az.cos() * el.cos(), el.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The worked example of Reda & Andreas (2004), Table A4.1: Golden, Colorado,
    /// 2003-10-17 12:30:30 local standard time (UTC−7), ΔT = 67 s, 820 mbar, 11 °C:
    /// topocentric zenith angle 50.11162°, azimuth 194.34024°.
    #[test]
    fn matches_the_nrel_spa_reference_example() {
        let site = Site {
            latitude_deg: 39.742476,
            longitude_deg: -105.1786,
            height_m: 1830.14,
            pressure_mbar: 820.0,
            temperature_c: 11.0,
        };
        let p = sun_position(site, "2003-10-17T12:30:30-07:00", Some(67.0)).unwrap();
        assert!((90.0 - p.elevation_deg - 50.11162).abs() < 1e-4, "{p:?}");
        assert!((p.azimuth_deg - 194.34024).abs() < 1e-4, "{p:?}");
    }

    #[test]
    fn direction_follows_azimuth_and_elevation() {
        let d = direction_to_sun(SunPosition { azimuth_deg: 90.0, elevation_deg: 0.0 });
        assert!(
            (d[0] - 1.0).abs() < 1e-12 && d[1].abs() < 1e-12 && d[2].abs() < 1e-12,
            "east: {d:?}"
        );
        let d = direction_to_sun(SunPosition { azimuth_deg: 180.0, elevation_deg: 50.0 });
        assert!(d[0].abs() < 1e-12 && (d[1] + 50f64.to_radians().cos()).abs() < 1e-12);
        assert!((d[2] - 50f64.to_radians().sin()).abs() < 1e-12);
    }

    #[test]
    fn bad_dates_are_refused_with_the_fix() {
        let err = sun_position(Site::new(45.7, 7.3, 580.0), "15/07/2026 16:30", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("write it with its UTC offset"), "{err}");
        let err = sun_position(Site::new(95.0, 7.3, 580.0), "2026-07-15T16:30:00+02:00", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("latitude 95"), "{err}");
    }
}
