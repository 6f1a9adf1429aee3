//! How a reflectance looks under a light: its tristimulus values and CIE 1976 L*a*b* (2°
//! observer, the light's own white as the reference white, CIE 15:2004 Eqs. 7.1–7.3 and
//! §8.2.1), and its linear-sRGB colour (IEC 61966-2-1; not adapted, the colour the absolute
//! render shows it in, scaled so that the light's white has no channel above 1: a warm light's
//! white keeps its hue instead of clipping to yellow). The preview and the material panel
//! colour every spectrum under one of the scene's lights, chosen on the page; D65 is always
//! offered as the reference.

use restauro_scene::load::{LoadedScene, ResolvedLight};
use restauro_spectral::Lab;
use restauro_spectral::Spectrum;
use restauro_spectral::colorimetry::{Observer, relative_xyz, white_point};
use restauro_spectral::illuminant::Illuminant;
use restauro_spectral::photometry::LuminousSpectrum;
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::collections::BTreeMap;

/// The key of the light the page colours under first.
pub const SCENE_LIGHT: &str = "scene";
/// The key of the reference daylight.
pub const D65_KEY: &str = "cie:D65";

/// A light to colour spectra under: its key (the page's choice), what it is in words, and its
/// relative spectral power distribution.
pub struct Light {
    pub key: String,
    pub label: String,
    spd: Spectrum,
}

/// A light as the page lists it.
#[derive(Serialize)]
pub struct LightChoice {
    pub key: String,
    pub label: String,
    /// A white surface (ρ = 1) under it, linear sRGB, each channel at most 1.
    pub white_linear_srgb: [f32; 3],
}

/// One spectrum under one light.
#[derive(Clone, Copy, Serialize)]
pub struct Look {
    /// CIE XYZ relative to the light (Y = 100 for a perfect white), CIE 15:2004 Eq. 7.1.
    pub xyz: [f64; 3],
    pub lab: [f64; 3],
    pub colour_linear_srgb: [f32; 3],
}

/// How `rho` looks under the light `spd`.
pub fn look(rho: &Spectrum, spd: &Spectrum) -> Look {
    let observer = Observer::Cie1931TwoDegree;
    let xyz = relative_xyz(rho, spd, observer);
    let white = white_point(spd, observer);
    let lab = Lab::from_xyz(xyz, white);
    let brightest =
        RgbSpace::Srgb.linear_from_xyz(white.scale(0.01)).into_iter().fold(1.0, f64::max);
    Look {
        xyz: xyz.to_array(),
        lab: [lab.l, lab.a, lab.b],
        colour_linear_srgb: colour(xyz.scale(1.0 / brightest)),
    }
}

/// How `rho` looks under D65 (2° observer): its L*a*b* and its linear-sRGB colour.
pub fn appearance(rho: &Spectrum) -> ([f64; 3], [f32; 3]) {
    let Look { lab, colour_linear_srgb, .. } = look(rho, &d65());
    (lab, colour_linear_srgb)
}

fn d65() -> Spectrum {
    Illuminant::D65.spd().unwrap_or(Spectrum::ONE)
}

/// Relative XYZ (Y = 100 for the light's white) as linear sRGB, clipped to 0–1.
fn colour(xyz: restauro_spectral::Xyz) -> [f32; 3] {
    RgbSpace::Srgb.linear_from_xyz(xyz.scale(0.01)).map(|v| v.clamp(0.0, 1.0) as f32)
}

impl Light {
    pub fn choice(&self) -> LightChoice {
        LightChoice {
            key: self.key.clone(),
            label: self.label.clone(),
            white_linear_srgb: look(&Spectrum::ONE, &self.spd).colour_linear_srgb,
        }
    }

    /// `rho` under each of `lights`, by key.
    pub fn looks(rho: &Spectrum, lights: &[Light]) -> BTreeMap<String, Look> {
        lights.iter().map(|l| (l.key.clone(), look(rho, &l.spd))).collect()
    }
}

/// The lights the page may colour the scene's spectra under: first the scene's own (its
/// daylight, or its first luminaire's light when it has none), then each light spectrum the
/// scene uses, then D65.
pub fn scene_lights(scene: &LoadedScene) -> Vec<Light> {
    let mut out: Vec<Light> = scene_light(scene).into_iter().collect();
    let mut seen = std::collections::BTreeSet::new();
    for (k, l) in scene.lights.iter().enumerate() {
        let (spectrum, what) = match l {
            ResolvedLight::Sun { spectrum, .. } => (spectrum, "the sun".to_owned()),
            ResolvedLight::Sky { spectrum, .. } => (spectrum, "the sky".to_owned()),
            ResolvedLight::Point { spectrum, .. }
            | ResolvedLight::Spot { spectrum, .. }
            | ResolvedLight::Area { spectrum, .. } => (spectrum, format!("light {}", k + 1)),
        };
        if let Some(spd) = scene.spectra.get(spectrum)
            && seen.insert(spectrum.clone())
        {
            let label = format!("{spectrum} ({what} alone)");
            out.push(Light { key: format!("spectrum:{spectrum}"), label, spd: *spd });
        }
    }
    out.push(Light {
        key: D65_KEY.into(),
        label: "CIE D65 (the reference daylight)".into(),
        spd: d65(),
    });
    out
}

/// The scene's own light: the spectral irradiance its sun and sky give a horizontal surface
/// (each spectrum per lux, times its illuminance there: the sun's normal illuminance by the
/// sine of its elevation), or its first luminaire's light when it has no daylight.
fn scene_light(scene: &LoadedScene) -> Option<Light> {
    let per_lux = |name: &str| {
        let spd = scene.spectra.get(name)?;
        LuminousSpectrum::new(spd, name).ok().map(|s| s.per_lumen)
    };
    let mut total = [0.0f32; restauro_spectral::grid::BANDS];
    let mut parts = Vec::new();
    for l in &scene.lights {
        let (name, lux) = match l {
            ResolvedLight::Sun { spectrum, elevation_deg, illuminance_lux, .. } => {
                (spectrum, illuminance_lux * elevation_deg.to_radians().sin().max(0.0))
            }
            ResolvedLight::Sky { spectrum, illuminance_lux, .. } => (spectrum, *illuminance_lux),
            _ => continue,
        };
        let Some(s) = per_lux(name) else { continue };
        if lux > 0.0 {
            for (t, v) in total.iter_mut().zip(s.0) {
                *t += (lux as f32) * v;
            }
            parts.push(format!("{name} {:.1} klx", lux / 1000.0));
        }
    }
    if !parts.is_empty() {
        let label = format!("the scene's daylight ({} on the ground)", parts.join(" + "));
        return Some(Light { key: SCENE_LIGHT.into(), label, spd: Spectrum(total) });
    }
    scene.lights.iter().find_map(|l| match l {
        ResolvedLight::Point { spectrum, .. }
        | ResolvedLight::Spot { spectrum, .. }
        | ResolvedLight::Area { spectrum, .. } => {
            let spd = *scene.spectra.get(spectrum)?;
            let label = format!("the scene's luminaires ({spectrum})");
            Some(Light { key: SCENE_LIGHT.into(), label, spd })
        }
        _ => None,
    })
}
