//! A georeferenced scene's `origin`: survey coordinates (UTM eastings and northings in the
//! millions of metres) are moved near zero before anything becomes a 32-bit float, where a step
//! of a millimetre would otherwise round to half a metre.
//!
//! Everything the file places is moved by the same offset, in 64 bits: the camera, saved views,
//! notes, lights, calculation grids and the objects' translations. A mesh's own coordinates
//! are moved as it is placed (its [`crate::mesh::Mesh::anchor_m`] and the object's transform,
//! with the offset, in one 64-bit product), so the scene restauro renders is the file's, shifted
//! by `−origin`. Results that report positions (the calculation grids) add it back.

use crate::scene_file::{Light, SceneFile};

/// The file with every position moved by `−origin` and its `origin` taken out, so that loading
/// it again would not move it twice; returns the origin it took out (zero when none).
pub fn recentre(mut file: SceneFile) -> (SceneFile, [f64; 3]) {
    let Some(origin) = file.origin.take() else { return (file, [0.0; 3]) };
    let back = origin.map(|c| -c);
    let at = |p: &mut [f64; 3]| move_point(p, back);
    let c = &mut file.camera;
    c.position.iter_mut().chain(c.target.iter_mut()).for_each(at);
    for v in &mut file.views {
        at(&mut v.position);
        at(&mut v.target);
    }
    for a in &mut file.annotations {
        at(&mut a.position);
        if let Some(pose) = &mut a.pose {
            at(&mut pose.position);
            at(&mut pose.target);
        }
    }
    file.lights.iter_mut().for_each(|l| move_light(l, back));
    for g in &mut file.grids {
        g.origin.iter_mut().for_each(at);
        g.points.iter_mut().flatten().for_each(at);
    }
    for o in &mut file.objects {
        at(o.transform.translate.get_or_insert([0.0; 3]));
    }
    for m in &mut file.maps {
        at(&mut m.corner);
    }
    (file, origin)
}

/// A position of the recentred scene in the file's coordinates.
pub fn to_file(p: [f64; 3], origin: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| p[k] + origin[k])
}

/// A light of the recentred scene as the file gives it.
pub fn light_in_file(light: &Light, origin: [f64; 3]) -> Light {
    let mut light = light.clone();
    move_light(&mut light, origin);
    light
}

fn move_point(p: &mut [f64; 3], by: [f64; 3]) {
    *p = std::array::from_fn(|k| p[k] + by[k]);
}

/// Moves the points of a light (its position, its aim, a panel's corner), not its directions.
fn move_light(light: &mut Light, by: [f64; 3]) {
    match light {
        Light::Point { position, aim, .. } => {
            move_point(position, by);
            aim.iter_mut().for_each(|a| move_point(a, by));
        }
        Light::Spot { position, aim, .. } => {
            move_point(position, by);
            move_point(aim, by);
        }
        Light::Area { corner, .. } => move_point(corner, by),
        Light::Sun { .. } | Light::Sky { .. } => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A luminaire's position and aim move with the origin, and come back as the file had them.
    #[test]
    fn a_light_goes_back_to_the_file_as_it_came() {
        let light = Light::Spot {
            position: [5_000_000.25, 4_000_000.5, 3.0],
            intensity_cd: Some(1000.0),
            flux_lm: None,
            spectrum: "lamp".into(),
            aim: [5_000_010.0, 4_000_000.5, 0.0],
            cone_deg: 20.0,
            falloff_deg: 5.0,
            ies: None,
        };
        let origin = [5_000_000.0, 4_000_000.0, 0.0];
        let mut moved = light.clone();
        move_light(&mut moved, origin.map(|c| -c));
        let Light::Spot { position, aim, .. } = &moved else { unreachable!() };
        assert_eq!((*position, *aim), ([0.25, 0.5, 3.0], [10.0, 0.5, 0.0]));
        assert_eq!(light_in_file(&moved, origin), light);
    }
}
