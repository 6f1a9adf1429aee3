//! The `[materials]` table: each material's optical numbers for its model (lambert,
//! cook-torrance or glass), the glazing keys only glass has, and the numbers of its degraded and
//! cleaned states and their soiling. Its photo textures and degradation maps are checked with
//! their own tables (`textures.rs`, `maps.rs`), after every material has passed.

use super::Ctx;
use crate::error::Result;
use crate::scene_file::{MaterialModel, Surface, Transmittance};

/// Every material and its states.
pub(super) fn check_materials(ctx: &mut Ctx) -> Result<()> {
    let file = ctx.file;
    for (name, m) in &file.materials {
        let place = format!("materials.{name}");
        check_glazing(ctx, &place, m)?;
        check_surface(ctx, &place, m.model, &m.base_surface())?;
        for (state, o) in [("degraded", &m.degraded), ("cleaned", &m.cleaned)] {
            if let Some(o) = o {
                let p = format!("{place}.{state}");
                check_surface(ctx, &p, m.model, &o.surface())?;
                if let Some(soiling) = &o.soiling {
                    check_soiling(ctx, &format!("{p}.soiling"), soiling)?;
                }
            }
        }
    }
    Ok(())
}

/// Check the optical numbers a state of a material gives (its base, or a state's own).
fn check_surface(
    ctx: &mut Ctx,
    place: &str,
    model: MaterialModel,
    surface: &Surface,
) -> Result<()> {
    let Surface { reflectance, roughness, specular, ior, .. } = *surface;
    if let Some(r) = reflectance {
        ctx.reflectance(r, &format!("{place}.reflectance"))?;
    }
    match model {
        MaterialModel::Glass => {
            if reflectance.is_some() || roughness.is_some() || specular.is_some() {
                return Err(ctx.invalid(
                    place,
                    "glass has no reflectance, roughness or specular: its reflection follows from \
                     its ior; give ior, thickness_mm and transmittance",
                ));
            }
            if let Some(n) = ior
                && !(n.is_finite() && n > 1.0 && n <= 3.0)
            {
                return Err(ctx.invalid(
                    format!("{place}.ior"),
                    format!(
                        "{n} is out of range; glass has an index of refraction above 1, at most 3"
                    ),
                ));
            }
        }
        MaterialModel::Lambert => {
            if roughness.is_some() || specular.is_some() || ior.is_some() {
                return Err(ctx.invalid(place, "a lambert material has no roughness, specular or ior; use model = \"cook-torrance\""));
            }
        }
        MaterialModel::CookTorrance => {
            if let Some(m) = roughness
                && !(m.is_finite() && m > 0.0 && m <= 1.0)
            {
                return Err(ctx.invalid(
                    format!("{place}.roughness"),
                    format!("{m} is out of range; the Beckmann roughness m is in (0, 1]"),
                ));
            }
            if specular.is_some() && ior.is_some() {
                return Err(ctx.invalid(place, "give either specular (F0) or ior, not both"));
            }
            if let Some(f0) = specular
                && !(f0.is_finite() && (0.0..=1.0).contains(&f0))
            {
                return Err(ctx.invalid(
                    format!("{place}.specular"),
                    format!("{f0} is out of range; F0 is a reflectance 0..1"),
                ));
            }
            if let Some(n) = ior
                && !(n.is_finite() && (1.0..=5.0).contains(&n))
            {
                return Err(ctx.invalid(
                    format!("{place}.ior"),
                    format!("{n} is out of range; an index of refraction is 1 to 5"),
                ));
            }
        }
    }
    Ok(())
}

/// A material's glazing keys: only glass has them, and glass needs no reflectance. The pane is
/// at most 100 mm thick and transmits at most what its faces let through, (1 − r)/(1 + r), in
/// every band.
fn check_glazing(ctx: &mut Ctx, place: &str, m: &crate::scene_file::Material) -> Result<()> {
    if m.model != MaterialModel::Glass {
        if m.thickness_mm.is_some() || m.transmittance.is_some() {
            return Err(
                ctx.invalid(place, "thickness_mm and transmittance are for model = \"glass\"")
            );
        }
        if m.reflectance.is_empty() {
            return Err(ctx.invalid(
                format!("{place}.reflectance"),
                "a material needs its reflectance, a spectrum name",
            ));
        }
        return Ok(());
    }
    if !m.reflectance.is_empty() {
        return Err(ctx.invalid(
            format!("{place}.reflectance"),
            "glass has no reflectance: its reflection follows from its ior",
        ));
    }
    if let Some(d) = m.thickness_mm
        && !(d.is_finite() && d > 0.0 && d <= 100.0)
    {
        return Err(ctx.invalid(
            format!("{place}.thickness_mm"),
            format!("{d} mm is out of range; a pane is more than 0 and at most 100 mm thick"),
        ));
    }
    let n = m.ior.unwrap_or(crate::glazing::DEFAULT_IOR);
    let most = crate::glazing::max_transmittance(n).min(1.0);
    let field = format!("{place}.transmittance");
    let (t, band) = match &m.transmittance {
        None => return Ok(()),
        Some(Transmittance::Neutral(t)) => (*t, String::new()),
        Some(Transmittance::Spectral(name)) => {
            let s = ctx.spectrum(name, &field, &mut Vec::new())?;
            // The first band out of range, to name it (its value as the spectrum holds it).
            let inside = |v: f32| (0.0..=most).contains(&f64::from(v));
            let Some(i) = s.0.iter().position(|&v| !inside(v)) else { return Ok(()) };
            let nm = restauro_spectral::grid::wavelength_nm(i);
            let t = format!("{}", s.0[i]).parse().unwrap_or(f64::NAN);
            (t, format!("spectrum `{name}` at {nm} nm: "))
        }
    };
    if !(t.is_finite() && (0.0..=most).contains(&t)) {
        return Err(ctx.invalid(
            field,
            format!("{band}{t} is out of range; glass of index {n} transmits 0 to {most:.4} at normal incidence (its faces reflect the rest)"),
        ));
    }
    Ok(())
}

/// A state's soiling: a reflectance for its deposit, its numbers in range.
fn check_soiling(ctx: &mut Ctx, place: &str, s: &crate::scene_file::Soiling) -> Result<()> {
    ctx.reflectance(&s.spectrum, &format!("{place}.spectrum"))?;
    let checks = [
        ("max_fraction", Some(s.max_fraction), 0.0, 1.0),
        ("rain_azimuth_deg", s.rain_azimuth_deg, -360.0, 360.0),
        ("rain_angle_deg", s.rain_angle_deg, 0.0, 80.0),
        ("sky_weight", s.sky_weight, 0.0, 10.0),
        ("rain_weight", s.rain_weight, 0.0, 10.0),
    ];
    for (key, value, low, high) in checks {
        if let Some(v) = value
            && !(v.is_finite() && (low..=high).contains(&v))
        {
            return Err(ctx.invalid(
                format!("{place}.{key}"),
                format!("{v} is out of range; use {low} to {high}"),
            ));
        }
    }
    Ok(())
}
