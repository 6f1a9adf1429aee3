//! The `[[lights]]` table: each light resolved by its kind, every number in range. A point or
//! spot luminaire has a spectrum that emits, its photometric file, and its intensity given or
//! following from its flux or the file; an area light is a rectangle; the sun has its
//! illuminance and its position, given or computed for a site and time (a sun that has set then
//! is left out, and noted); the sky has its illuminance and model. Then the scene must have a
//! light that shines and at most one sky, whose shape is settled against the sun last
//! ([`super::sky_shape`]), since the sun may come after the sky in the file.

use super::spectra::sky_spectrum;
use super::{Ctx, MAX_ILLUMINANCE_LUX, MAX_INTENSITY_CD, check_point};
use crate::assets::extension;
use crate::error::Result;
use crate::formats::photometric::{self, Photometry};
use crate::scene_file::{Light, SiteTime, SkyModel, SkyPreset, SunPreset};
use crate::sun::{Site, SunPosition, direction_to_sun, sun_position};
use glam::DVec3;

/// A light with everything resolved.
#[derive(Clone, Debug)]
pub enum ResolvedLight {
    Point {
        position: [f64; 3],
        intensity_cd: f64,
        spectrum: String,
        photometry: Option<Photometry>,
        aim: Option<[f64; 3]>,
    },
    Spot {
        position: [f64; 3],
        intensity_cd: f64,
        spectrum: String,
        aim: [f64; 3],
        cone_deg: f64,
        falloff_deg: f64,
        photometry: Option<Photometry>,
    },
    Sun {
        /// Unit vector towards the sun (+X east, +Y north, +Z up).
        direction: [f64; 3],
        azimuth_deg: f64,
        elevation_deg: f64,
        illuminance_lux: f64,
        spectrum: String,
    },
    /// The sky dome: `illuminance_lux` on a horizontal surface open to the whole sky.
    Sky {
        illuminance_lux: f64,
        model: SkyModel,
        spectrum: String,
        /// With [`SkyModel::CieGeneral`]: its type and the sun that shapes it.
        general: Option<crate::cie_sky::GeneralSky>,
        /// The luminance of the ground below the horizon (0: none, or black).
        ground_cd_m2: f64,
    },
    /// A Lambertian emitting rectangle.
    Area { panel: crate::area_light::Panel, luminance_cd_m2: f64, spectrum: String },
}

impl ResolvedLight {
    /// A luminaire's luminous flux as rendered, lm: its photometric file's, scaled to the
    /// intensity rendered, or that of its intensity in its shape (isotropic, or the spot's
    /// cone). `None` for the sun and the sky.
    pub fn flux_lm(&self) -> Option<f64> {
        match self {
            ResolvedLight::Point { intensity_cd, photometry, .. } => {
                Some(intensity_cd * lumens_per_cd(photometry.as_ref(), 4.0 * std::f64::consts::PI))
            }
            ResolvedLight::Area { panel, luminance_cd_m2, .. } => {
                Some(std::f64::consts::PI * luminance_cd_m2 * panel.area_m2())
            }
            ResolvedLight::Spot { intensity_cd, photometry, cone_deg, falloff_deg, .. } => Some(
                intensity_cd
                    * lumens_per_cd(
                        photometry.as_ref(),
                        spot_lumens_per_cd(*cone_deg, *falloff_deg),
                    ),
            ),
            _ => None,
        }
    }
}

/// One line describing the light, for people: what `restauro scene check` lists and the demo's
/// report records.
impl std::fmt::Display for ResolvedLight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ResolvedLight::Sun {
                azimuth_deg, elevation_deg, illuminance_lux, spectrum, ..
            } => {
                write!(
                    f,
                    "sun: {illuminance_lux} lux, azimuth {azimuth_deg:.2}°, elevation {elevation_deg:.2}°, spectrum {spectrum}"
                )
            }
            ResolvedLight::Point { position, intensity_cd, photometry, .. } => {
                write!(f, "point luminaire at {position:?}: {intensity_cd} cd")?;
                write_photometry(f, *intensity_cd, photometry.as_ref())
            }
            ResolvedLight::Spot { position, intensity_cd, cone_deg, photometry, .. } => {
                write!(f, "spot at {position:?}: {intensity_cd} cd")?;
                match photometry {
                    Some(_) => write_photometry(f, *intensity_cd, photometry.as_ref()),
                    None => write!(f, ", cone {cone_deg}°"),
                }
            }
            ResolvedLight::Sky { illuminance_lux, model, spectrum, general, ground_cd_m2 } => {
                write!(f, "{model}")?;
                if let Some(g) = general {
                    let el = g.sun[2].clamp(-1.0, 1.0).asin().to_degrees();
                    write!(f, " type {} (sun {el:.1}° high)", g.sky_type)?;
                }
                write!(f, ": {illuminance_lux} lux on the horizontal, spectrum {spectrum}")?;
                if *ground_cd_m2 > 0.0 {
                    write!(f, "; ground below the horizon at {ground_cd_m2:.1} cd/m²")?;
                }
                Ok(())
            }
            ResolvedLight::Area { panel, luminance_cd_m2, spectrum } => {
                let area = panel.area_m2();
                write!(
                    f,
                    "area luminaire at {:?}: {luminance_cd_m2} cd/m² over {area:.3} m², {:.0} lm, \
                     spectrum {spectrum}",
                    panel.corner,
                    std::f64::consts::PI * luminance_cd_m2 * area
                )
            }
        }
    }
}

/// What `scene check` says of a luminaire's photometric file, at the intensity rendered:
/// its flux, peak intensity and beam angle (50 % of the peak).
fn write_photometry(
    f: &mut std::fmt::Formatter<'_>,
    intensity_cd: f64,
    photometry: Option<&Photometry>,
) -> std::fmt::Result {
    let Some(p) = photometry else { return Ok(()) };
    let scale = if p.peak_cd() > 0.0 { intensity_cd / p.peak_cd() } else { 0.0 };
    write!(
        f,
        " (photometric file: {:.0} lm, peak {:.0} cd, beam {:.1}°)",
        scale * p.flux_lm(),
        intensity_cd,
        p.beam_angle_deg()
    )
}

/// Every light, in the file's order; then the checks of the lights together.
pub(super) fn resolve_lights(ctx: &mut Ctx) -> Result<Vec<ResolvedLight>> {
    let file = ctx.file;
    if file.lights.is_empty() {
        return Err(ctx.invalid("lights", "the scene has no light; add a sun or a luminaire"));
    }
    let mut lights = Vec::new();
    for (i, l) in file.lights.iter().enumerate() {
        let place = format!("lights[{i}]");
        let resolved = match l {
            Light::Point { .. } => point_light(ctx, &place, l)?,
            Light::Area { .. } => area_light(ctx, &place, l)?,
            Light::Spot { .. } => spot_light(ctx, &place, l)?,
            Light::Sun { .. } => match sun_light(ctx, &place, l)? {
                Some(sun) => sun,
                None => continue,
            },
            Light::Sky { .. } => sky_light(ctx, &place, l)?,
        };
        lights.push(resolved);
    }
    if lights.is_empty() {
        return Err(ctx.invalid(
            "lights",
            "the sun is below the horizon at that time and the scene has no other light; \
             choose a daytime date-time, or add a sky or a luminaire",
        ));
    }
    if file.lights.iter().filter(|l| matches!(l, Light::Sky { .. })).count() > 1 {
        return Err(ctx.invalid(
            "lights",
            "more than one sky; a scene has one sky dome (give its total illuminance_lux)",
        ));
    }
    super::sky_shape::settle(&ctx.path, &file.lights, &mut lights)?;
    Ok(lights)
}

/// A point luminaire: isotropic, or shaped by its photometric file.
fn point_light(ctx: &mut Ctx, place: &str, light: &Light) -> Result<ResolvedLight> {
    let Light::Point { position, intensity_cd, flux_lm, spectrum, ies, aim } = light else {
        unreachable!("resolve_lights gives point_light point lights")
    };
    ctx.emission(spectrum, &format!("{place}.spectrum"))?;
    let photometry = photometry(ctx, ies, &format!("{place}.ies"))?;
    let given = given_intensity(ctx, place, *intensity_cd, *flux_lm, || {
        lumens_per_cd(photometry.as_ref(), 4.0 * std::f64::consts::PI)
    })?;
    let intensity_cd = luminaire_intensity(ctx, place, given, photometry.as_ref())?;
    check_luminaire(ctx, place, *position, intensity_cd, *aim)?;
    Ok(ResolvedLight::Point {
        position: *position,
        intensity_cd,
        spectrum: spectrum.clone(),
        photometry,
        aim: *aim,
    })
}

/// An area luminaire: a Lambertian rectangle, its luminance given or following from its flux.
fn area_light(ctx: &mut Ctx, place: &str, light: &Light) -> Result<ResolvedLight> {
    let Light::Area { corner, u, v, normal, luminance_cd_m2, flux_lm, spectrum } = light else {
        unreachable!("resolve_lights gives area_light area lights")
    };
    ctx.emission(spectrum, &format!("{place}.spectrum"))?;
    let panel = crate::area_light::Panel::new(*corner, *u, *v, *normal)
        .map_err(|(field, problem)| ctx.invalid(format!("{place}.{field}"), problem))?;
    let luminance_cd_m2 = crate::area_light::luminance(&panel, *luminance_cd_m2, *flux_lm)
        .map_err(|(field, problem)| ctx.invalid(format!("{place}{field}"), problem))?;
    Ok(ResolvedLight::Area { panel, luminance_cd_m2, spectrum: spectrum.clone() })
}

/// A spot: a cone of full intensity with a falloff outside it, or its photometric file.
fn spot_light(ctx: &mut Ctx, place: &str, light: &Light) -> Result<ResolvedLight> {
    let Light::Spot { position, intensity_cd, flux_lm, spectrum, aim, cone_deg, falloff_deg, ies } =
        light
    else {
        unreachable!("resolve_lights gives spot_light spots")
    };
    if !(cone_deg.is_finite()
        && *cone_deg > 0.0
        && falloff_deg.is_finite()
        && *falloff_deg >= 0.0
        && cone_deg + falloff_deg <= 180.0)
    {
        return Err(
            ctx.invalid(place, "cone_deg must be > 0 and falloff_deg ≥ 0, their sum at most 180")
        );
    }
    ctx.emission(spectrum, &format!("{place}.spectrum"))?;
    let photometry = photometry(ctx, ies, &format!("{place}.ies"))?;
    let given = given_intensity(ctx, place, *intensity_cd, *flux_lm, || {
        lumens_per_cd(photometry.as_ref(), spot_lumens_per_cd(*cone_deg, *falloff_deg))
    })?;
    let intensity_cd = luminaire_intensity(ctx, place, given, photometry.as_ref())?;
    check_luminaire(ctx, place, *position, intensity_cd, Some(*aim))?;
    Ok(ResolvedLight::Spot {
        position: *position,
        intensity_cd,
        spectrum: spectrum.clone(),
        aim: *aim,
        cone_deg: *cone_deg,
        falloff_deg: *falloff_deg,
        photometry,
    })
}

/// The sun: its illuminance (given or a preset's) and its position; `None` when a site's time
/// puts it below the horizon (noted), where a direction given below the horizon is refused.
fn sun_light(ctx: &mut Ctx, place: &str, light: &Light) -> Result<Option<ResolvedLight>> {
    let Light::Sun { illuminance_lux, preset, azimuth_deg, elevation_deg, site, spectrum } = light
    else {
        unreachable!("resolve_lights gives sun_light suns")
    };
    ctx.emission(spectrum, &format!("{place}.spectrum"))?;
    let lux = match (illuminance_lux, preset) {
        (Some(_), Some(_)) => {
            return Err(ctx.invalid(place, "give illuminance_lux or a preset, not both"));
        }
        (Some(e), None) => *e,
        (None, Some(SunPreset::Sun)) => 100_000.0,
        (None, Some(SunPreset::Cloudy)) => 10_000.0,
        (None, Some(SunPreset::FullMoon)) => 0.2,
        (None, None) => {
            return Err(ctx.invalid(
                place,
                "give illuminance_lux, or preset = \"sun\", \"cloudy\" or \"full-moon\"",
            ));
        }
    };
    check_illuminance(ctx, place, lux)?;
    let position = sun_position_of(ctx, place, azimuth_deg, elevation_deg, site, preset)?;
    if position.elevation_deg <= 0.0 {
        // A moment after sunset is a real question (the facade at dusk): that sun
        // lights nothing, and the other lights still do. A direction given below
        // the horizon is a slip, and refused.
        let Some(s) = site else {
            return Err(ctx.invalid(
                place,
                format!(
                    "the sun is below the horizon (elevation {:.2}°, azimuth {:.2}°); choose a daytime date-time or a positive elevation",
                    position.elevation_deg, position.azimuth_deg
                ),
            ));
        };
        ctx.notes.push(format!(
            "{place}: at {} the sun is below the horizon (elevation {:.2}°, azimuth {:.2}°): it lights nothing, the other lights still do",
            s.datetime, position.elevation_deg, position.azimuth_deg
        ));
        return Ok(None);
    }
    Ok(Some(ResolvedLight::Sun {
        direction: direction_to_sun(position),
        azimuth_deg: position.azimuth_deg,
        elevation_deg: position.elevation_deg,
        illuminance_lux: lux,
        spectrum: spectrum.clone(),
    }))
}

/// Where the sun stands: computed for a site and its date-time, or given by azimuth and
/// elevation (or the `sun` preset's), each in range.
fn sun_position_of(
    ctx: &Ctx,
    place: &str,
    azimuth_deg: &Option<f64>,
    elevation_deg: &Option<f64>,
    site: &Option<SiteTime>,
    preset: &Option<SunPreset>,
) -> Result<SunPosition> {
    let position = match (azimuth_deg, elevation_deg, site) {
        (Some(_), _, Some(_)) | (_, Some(_), Some(_)) => {
            return Err(
                ctx.invalid(place, "give azimuth/elevation or a site and date-time, not both")
            );
        }
        (None, None, Some(s)) => {
            let site = Site::new(s.latitude_deg, s.longitude_deg, s.height_m);
            sun_position(site, &s.datetime, None)
                .map_err(|e| ctx.invalid(format!("{place}.site"), e.to_string()))?
        }
        (az, el, None) => {
            // The paper's sun preset stands 50° above the horizon; due south
            // unless an azimuth is given.
            let el = el.or((*preset == Some(SunPreset::Sun)).then_some(50.0));
            let az = az.or(el.map(|_| 180.0));
            match (az, el) {
                (Some(az), Some(el)) if az.is_finite() && el.is_finite() && (-90.0..=90.0).contains(&el) => SunPosition { azimuth_deg: az, elevation_deg: el },
                (Some(az), Some(_)) if !az.is_finite() => return Err(ctx.invalid(format!("{place}.azimuth_deg"), format!("{az} is not a direction; give degrees from north towards east (0 north, 90 east, 180 south)"))),
                (Some(_), Some(el)) => return Err(ctx.invalid(format!("{place}.elevation_deg"), format!("{el} is out of range; use −90 to 90 degrees"))),
                _ => return Err(ctx.invalid(place, "give azimuth_deg and elevation_deg, or a site with latitude, longitude and date-time")),
            }
        }
    };
    Ok(position)
}

/// The sky: its illuminance (given or a preset's), model and spectrum (D65 unless given).
fn sky_light(ctx: &mut Ctx, place: &str, light: &Light) -> Result<ResolvedLight> {
    let Light::Sky { illuminance_lux, preset, model, spectrum, .. } = light else {
        unreachable!("resolve_lights gives sky_light skies")
    };
    let spectrum = &sky_spectrum(ctx, spectrum)?;
    ctx.emission(spectrum, &format!("{place}.spectrum"))?;
    let (lux, preset_model) = match (illuminance_lux, preset) {
        (Some(_), Some(_)) => {
            return Err(ctx.invalid(place, "give illuminance_lux or a preset, not both"));
        }
        (Some(e), None) => (*e, SkyModel::CieOvercast),
        (None, Some(SkyPreset::Overcast)) => (10_000.0, SkyModel::CieOvercast),
        (None, Some(SkyPreset::Clear)) => (15_000.0, SkyModel::Uniform),
        (None, None) => {
            return Err(
                ctx.invalid(place, "give illuminance_lux, or preset = \"overcast\" or \"clear\"")
            );
        }
    };
    check_illuminance(ctx, place, lux)?;
    // The general sky's sun and the ground are settled once every light is
    // resolved (`super::sky_shape`): the scene's sun may come after the sky.
    Ok(ResolvedLight::Sky {
        illuminance_lux: lux,
        model: model.unwrap_or(preset_model),
        spectrum: spectrum.clone(),
        general: None,
        ground_cd_m2: 0.0,
    })
}

fn photometry(ctx: &Ctx, reference: &Option<String>, place: &str) -> Result<Option<Photometry>> {
    let Some(reference) = reference else { return Ok(None) };
    let bytes = ctx.assets.read(reference, place)?;
    let text = photometric::decode_text(bytes);
    let name = ctx.assets.display_path(reference);
    Ok(Some(match extension(reference).as_str() {
        "ies" => photometric::parse_ies(&text, &name)?,
        "ldt" => photometric::parse_ldt(&text, &name)?,
        other => {
            return Err(ctx.invalid(place, format!("`{reference}`: `.{other}` is not a photometric format; use .ies (LM-63) or .ldt (EULUMDAT)")));
        }
    }))
}

/// An illuminance (sun or sky): finite, ≥ 0 and at most [`MAX_ILLUMINANCE_LUX`].
fn check_illuminance(ctx: &Ctx, place: &str, lux: f64) -> Result<()> {
    if !(lux.is_finite() && lux >= 0.0) {
        return Err(ctx.invalid(
            format!("{place}.illuminance_lux"),
            format!("{lux} is not a finite illuminance ≥ 0 lux"),
        ));
    }
    if lux > MAX_ILLUMINANCE_LUX {
        return Err(ctx.invalid(
            format!("{place}.illuminance_lux"),
            format!(
                "{lux:e} lux is more than the {MAX_ILLUMINANCE_LUX:e} lux restauro accepts (full \
                 sunlight is about 1e5 lux); give the illuminance in lux"
            ),
        ));
    }
    Ok(())
}

/// The intensity a luminaire is given: `intensity_cd`, or `flux_lm` over the lumens one
/// candela of its distribution emits (`per_cd`), or neither (its photometric file's own).
fn given_intensity(
    ctx: &Ctx,
    place: &str,
    intensity_cd: Option<f64>,
    flux_lm: Option<f64>,
    per_cd: impl FnOnce() -> f64,
) -> Result<Option<f64>> {
    match (intensity_cd, flux_lm) {
        (Some(_), Some(_)) => Err(ctx
            .invalid(place, "give intensity_cd or flux_lm, not both (one follows from the other)")),
        (None, Some(lm)) if !(lm.is_finite() && (0.0..=1e10).contains(&lm)) => Err(ctx.invalid(
            format!("{place}.flux_lm"),
            format!("{lm} is not a luminous flux; give lumens from 0 to 1e10"),
        )),
        (None, Some(lm)) => {
            let per = per_cd();
            if per > 0.0 { Ok(Some(lm / per)) } else { Ok(Some(0.0)) }
        }
        (cd, None) => Ok(cd),
    }
}

/// The lumens a luminaire emits per candela of its peak: its photometric file's flux over its
/// peak, or `shape`'s (the lumens of one candela in the distribution without a file).
fn lumens_per_cd(photometry: Option<&Photometry>, shape: f64) -> f64 {
    match photometry {
        Some(p) if p.peak_cd() > 0.0 => p.flux_lm() / p.peak_cd(),
        Some(_) => 0.0,
        None => shape,
    }
}

/// The lumens of a spot of one candela inside its cone: Φ = 2π ∫ f(cos θ) d(cos θ), with f = 1
/// inside `cone_deg` and the smoothstep of the render between it and `cone_deg + falloff_deg`,
/// whose mean over the band is ½: 2π [(1 − cos θ_in) + ½ (cos θ_in − cos θ_out)].
fn spot_lumens_per_cd(cone_deg: f64, falloff_deg: f64) -> f64 {
    let inner = cone_deg.to_radians().cos();
    let outer = (cone_deg + falloff_deg.max(1e-3)).to_radians().cos();
    2.0 * std::f64::consts::PI * ((1.0 - inner) + 0.5 * (inner - outer))
}

/// A luminaire's peak intensity (cd): the photometric file's own unless `intensity_cd`
/// overrides it (noted when it departs from the file by more than 1 %); without a file,
/// `intensity_cd` itself, which is then required.
fn luminaire_intensity(
    ctx: &mut Ctx,
    place: &str,
    intensity_cd: Option<f64>,
    photometry: Option<&Photometry>,
) -> Result<f64> {
    match (intensity_cd, photometry) {
        (None, Some(p)) => Ok(p.peak_cd()),
        (Some(cd), Some(p)) => {
            let peak = p.peak_cd();
            if cd.is_finite() && peak > 0.0 && (cd / peak - 1.0).abs() > 0.01 {
                ctx.notes.push(format!(
                    "{place}: intensity_cd = {cd} cd overrides the photometric file's peak of \
                     {peak:.1} cd (× {:.3}); leave intensity_cd out to render the luminaire as \
                     measured",
                    cd / peak
                ));
            }
            Ok(cd)
        }
        (Some(cd), None) => Ok(cd),
        (None, None) => Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            "a luminaire without a photometric file (ies) needs its intensity_cd (candela) or its flux_lm (lumens)",
        )),
    }
}

fn check_luminaire(
    ctx: &Ctx,
    place: &str,
    position: [f64; 3],
    intensity_cd: f64,
    aim: Option<[f64; 3]>,
) -> Result<()> {
    check_point(ctx, &format!("{place}.position"), position)?;
    if !(intensity_cd.is_finite() && intensity_cd >= 0.0) {
        return Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            format!("{intensity_cd} is not a luminous intensity; give candela ≥ 0"),
        ));
    }
    if intensity_cd > MAX_INTENSITY_CD {
        return Err(ctx.invalid(
            format!("{place}.intensity_cd"),
            format!(
                "{intensity_cd:e} cd is more than the {MAX_INTENSITY_CD:e} cd restauro accepts (the \
                 brightest searchlights reach about 1e9 cd); give the luminaire's intensity in \
                 candela"
            ),
        ));
    }
    if let Some(a) = aim {
        check_point(ctx, &format!("{place}.aim"), a)?;
        if (DVec3::from_array(a) - DVec3::from_array(position)).length() < 1e-9 {
            return Err(ctx
                .invalid(format!("{place}.aim"), "the aim point is the luminaire's own position"));
        }
    }
    Ok(())
}
