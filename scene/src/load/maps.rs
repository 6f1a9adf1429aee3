//! The `[[maps]]` table: the degradation maps, each a PNG whose colours mark classes of decay
//! on a rectangle of the scene, and the material states that draw their classes from one.

use super::{Ctx, Limits, MAX_MAP_CLASSES, finite3, unknown};
use crate::assets::extension;
use crate::error::Result;
use glam::DVec3;
use std::collections::{BTreeMap, BTreeSet};

/// The degradation maps: their images decoded (PNG only: a JPEG's compression would blur
/// the class colours), their rectangles, classes and spectra checked; and each material state
/// that names a map, checked against it.
pub(super) fn check_maps(
    ctx: &mut Ctx,
    limits: &Limits,
    textures: &mut BTreeMap<String, std::sync::Arc<crate::texture::Texture>>,
) -> Result<()> {
    let file = ctx.file;
    let mut names = BTreeSet::new();
    for (i, m) in file.maps.iter().enumerate() {
        let place = format!("maps[{i}] ({})", m.name);
        if !names.insert(m.name.as_str()) {
            return Err(ctx.invalid(place, "two maps have this name; names must be unique"));
        }
        let ext = extension(&m.image);
        if ext != "png" {
            return Err(ctx.invalid(
                format!("{place}.image"),
                format!("`{}`: a map must be a PNG image, whose class colours stay exact (a JPEG's compression blurs them)", m.image),
            ));
        }
        let bytes = ctx.assets.read(&m.image, &format!("{place}.image"))?;
        let shown = ctx.assets.display_path(&m.image);
        let texture = crate::texture::decode(&bytes, &ext, &shown, limits.max_pixels)?;
        textures.insert(m.image.clone(), std::sync::Arc::new(texture));
        let (u, v) = (DVec3::from_array(m.u), DVec3::from_array(m.v));
        if !(finite3(m.corner) && finite3(m.u) && finite3(m.v)) || u.cross(v).length() < 1e-9 {
            return Err(ctx.invalid(
                &place,
                "`corner`, `u` and `v` must be finite, and `u` and `v` edges of a rectangle (not zero, not parallel)",
            ));
        }
        if m.classes.is_empty() || m.classes.len() > MAX_MAP_CLASSES {
            return Err(ctx.invalid(
                format!("{place}.classes"),
                format!("a map needs 1 to {MAX_MAP_CLASSES} classes; it has {}", m.classes.len()),
            ));
        }
        for (k, c) in m.classes.iter().enumerate() {
            let here = format!("{place}.classes[{k}] ({})", c.name);
            if m.classes[..k].iter().any(|o| o.name == c.name || o.colour == c.colour) {
                return Err(
                    ctx.invalid(here, "another class has this name or colour; each needs its own")
                );
            }
            ctx.reflectance(&c.spectrum, &format!("{here}.spectrum"))?;
        }
    }
    for (name, material) in &file.materials {
        for (state, o) in [("degraded", &material.degraded), ("cleaned", &material.cleaned)] {
            let Some(o) = o else { continue };
            let place = format!("materials.{name}.{state}");
            let map = match (&o.map, &o.classes) {
                (None, None) => continue,
                (None, Some(_)) => {
                    return Err(ctx.invalid(place, "`classes` needs the `map` they are classes of"));
                }
                (Some(map), _) => file.maps.iter().find(|m| &m.name == map).ok_or_else(|| {
                    ctx.invalid(
                        format!("{place}.map"),
                        unknown("map", map, file.maps.iter().map(|m| m.name.as_str())),
                    )
                })?,
            };
            for class in o.classes.iter().flatten() {
                if !map.classes.iter().any(|c| &c.name == class) {
                    return Err(ctx.invalid(
                        format!("{place}.classes"),
                        unknown("class", class, map.classes.iter().map(|c| c.name.as_str()))
                            .replace("the scene defines", &format!("map `{}` has", map.name)),
                    ));
                }
            }
        }
    }
    Ok(())
}
