//! What a sky needs of the rest of the scene, settled once every light is resolved: the sun
//! that shapes a CIE general sky, and the ground below the horizon, whose luminance follows from
//! the horizontal illuminance of the sky and the sun together.
//!
//! The general sky's sun is the scene's sun light (its first, if it has several); without one,
//! the sky's own `sun_elevation_deg` and `sun_azimuth_deg`, or its `site` and date-time. A sun
//! given both ways is refused, so the sky's shape and the scene's shadows cannot disagree.
//!
//! The ground is a uniform Lambertian plane of reflectance ρ lit by everything above it:
//! L_ground = ρ · E_h / π, E_h = D_v + E_sun · sin(elevation) (its own shadows ignored).

use super::ResolvedLight;
use crate::cie_sky::GeneralSky;
use crate::error::{Result, SceneError};
use crate::scene_file::{Light, SkyModel};
use crate::sun::{Site, SunPosition, direction_to_sun, sun_position};
use std::path::Path;

/// Fills in the sky of `lights` (resolved from `file_lights` of the scene at `path`).
pub fn settle(path: &Path, file_lights: &[Light], lights: &mut [ResolvedLight]) -> Result<()> {
    let Some((index, given)) = file_lights.iter().enumerate().find_map(|(i, l)| match l {
        Light::Sky {
            cie_type,
            sun_elevation_deg,
            sun_azimuth_deg,
            site,
            ground_reflectance,
            ..
        } => Some((
            i,
            (*cie_type, *sun_elevation_deg, *sun_azimuth_deg, site.clone(), *ground_reflectance),
        )),
        _ => None,
    }) else {
        return Ok(());
    };
    let (cie_type, elevation, azimuth, site, ground) = given;
    let place = format!("lights[{index}]");
    let invalid = |field: &str, problem: String| {
        SceneError::invalid(path, format!("{place}{field}"), problem)
    };
    let scene_sun = lights.iter().find_map(|l| match l {
        ResolvedLight::Sun { direction, illuminance_lux, elevation_deg, .. } => {
            Some((*direction, illuminance_lux * elevation_deg.to_radians().sin().max(0.0)))
        }
        _ => None,
    });
    let own_sun = elevation.is_some() || azimuth.is_some() || site.is_some();
    let Some(ResolvedLight::Sky { illuminance_lux, model, general, ground_cd_m2, .. }) =
        lights.iter_mut().find(|l| matches!(l, ResolvedLight::Sky { .. }))
    else {
        return Ok(());
    };
    match (*model, cie_type) {
        (SkyModel::CieGeneral, None) => {
            let problem = "a CIE general sky needs its type: cie_type = 1 to 15 (12 is the CIE \
                           standard clear sky)";
            return Err(invalid(".cie_type", problem.into()));
        }
        (SkyModel::CieGeneral, Some(t)) if !(1..=15).contains(&t) => {
            return Err(invalid(".cie_type", format!("{t} is not a sky type; use 1 to 15")));
        }
        (SkyModel::CieGeneral, Some(t)) => {
            let sun = match (scene_sun, own_sun) {
                (Some(_), true) => {
                    let problem = "the scene has a sun light, which places the sky's sun; \
                                   remove sun_elevation_deg, sun_azimuth_deg and site from the sky";
                    return Err(invalid("", problem.into()));
                }
                (Some((direction, _)), false) => direction,
                (None, _) => own_sun_direction(elevation, azimuth, site.as_ref(), &invalid)?,
            };
            *general = Some(GeneralSky::new(t, sun));
        }
        (_, Some(_)) => {
            let problem = "cie_type is for model = \"cie-general\"; set the model, or remove it";
            return Err(invalid(".cie_type", problem.into()));
        }
        (_, None) if own_sun => {
            let problem = "only a CIE general sky (model = \"cie-general\") has a sun that shapes \
                           it; remove sun_elevation_deg, sun_azimuth_deg and site";
            return Err(invalid("", problem.into()));
        }
        (_, None) => {}
    }
    if let Some(rho) = ground {
        if !(rho.is_finite() && (0.0..=1.0).contains(&rho)) {
            let problem = format!("{rho} is not a reflectance; give a fraction from 0 to 1");
            return Err(invalid(".ground_reflectance", problem));
        }
        let horizontal = *illuminance_lux + scene_sun.map_or(0.0, |(_, e)| e);
        *ground_cd_m2 = rho * horizontal / std::f64::consts::PI;
    }
    Ok(())
}

/// The sky's own sun: by elevation and azimuth, or by site and date-time; above the horizon.
fn own_sun_direction(
    elevation: Option<f64>,
    azimuth: Option<f64>,
    site: Option<&crate::scene_file::SiteTime>,
    invalid: &dyn Fn(&str, String) -> SceneError,
) -> Result<[f64; 3]> {
    let position = match (elevation, azimuth, site) {
        (Some(el), Some(az), None) => {
            if !(el.is_finite() && el > 0.0 && el <= 90.0) {
                let problem = format!(
                    "{el} is not a daytime sun; give degrees above the horizon, 0 < elevation ≤ 90"
                );
                return Err(invalid(".sun_elevation_deg", problem));
            }
            if !az.is_finite() {
                return Err(invalid(".sun_azimuth_deg", format!("{az} is not a direction")));
            }
            SunPosition { azimuth_deg: az, elevation_deg: el }
        }
        (None, None, Some(s)) => {
            let site = Site::new(s.latitude_deg, s.longitude_deg, s.height_m);
            let p = sun_position(site, &s.datetime, None)
                .map_err(|e| invalid(".site", e.to_string()))?;
            if p.elevation_deg <= 0.0 {
                let problem = format!(
                    "at {} the sun is below the horizon (elevation {:.2}°); a CIE general sky is \
                     a daylight sky: choose a daytime date-time",
                    s.datetime, p.elevation_deg
                );
                return Err(invalid(".site", problem));
            }
            p
        }
        (None, None, None) => {
            let problem = "a CIE general sky is shaped by the sun: add a sun light, or give the \
                           sky sun_elevation_deg and sun_azimuth_deg, or a site and date-time";
            return Err(invalid("", problem.into()));
        }
        _ => {
            let problem = "give the sky's sun as sun_elevation_deg and sun_azimuth_deg together, \
                           or as a site, not both";
            return Err(invalid("", problem.into()));
        }
    };
    Ok(direction_to_sun(position))
}
