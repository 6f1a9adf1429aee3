//! Levels of detail (VRML97 `LOD`, ISO/IEC 14772-1 §6.26): a model keeps every level of each
//! LOD node, and each render shows the level its camera calls for.
//!
//! **The rule.** VRML picks level i when the distance d from the viewer to the LOD's `center`
//! (in the LOD's own coordinates, its scaling included) lies between `range[i−1]` and
//! `range[i]`. Those ranges were written for a browser's window; a render is another window,
//! so restauro compares not d but the distance at which the object would look as large as it
//! does in the render, seen in VRML's default view (a 45° field of view, §6.53) 480 pixels high:
//!
//! d_ref = d · (480 / H) · tan(fov/2) / tan(22.5°),
//!
//! H the render's height in pixels and fov its vertical field of view. An object that spans
//! twice the pixels (a 4K render, a narrow lens) shows the level of half the distance: detail
//! follows the object's projected size. A model with LODs nested inside LODs shows a triangle
//! when every enclosing LOD shows the level it is in.

/// One LOD node: where it is, how its own units compare with metres, and its ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct Lod {
    /// `center`, in the file's coordinates (then, once placed, in the scene's).
    pub center_m: [f64; 3],
    /// The LOD's own units per metre of the coordinates `center_m` is in: its enclosing
    /// transforms' scaling, undone.
    pub units_per_m: f64,
    /// `range`, in the LOD's own units, ascending.
    pub ranges: Vec<f64>,
    /// How many `level`s it has.
    pub levels: u32,
}

/// The LODs of a mesh and which level of which LOD each triangle belongs to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Levels {
    pub lods: Vec<Lod>,
    /// The distinct chains of (LOD, level) that triangles lie in; the first is empty (a
    /// triangle outside every LOD).
    pub paths: Vec<Vec<(u32, u32)>>,
    /// Per triangle, its index in `paths`; empty when the mesh has no LOD.
    pub of_triangle: Vec<u32>,
}

/// VRML's default vertical field of view (§6.53: 0.785398 rad) and the reference window's
/// height in pixels.
const REFERENCE_FOV_RAD: f64 = std::f64::consts::FRAC_PI_4;
const REFERENCE_HEIGHT_PX: f64 = 480.0;

/// What the rule needs of the camera.
#[derive(Clone, Copy, Debug)]
pub struct Viewer {
    pub position_m: [f64; 3],
    pub vertical_fov_deg: f64,
    pub height_px: u32,
}

impl Lod {
    /// The level the viewer sees (module documentation).
    pub fn level_for(&self, viewer: &Viewer) -> u32 {
        let d_m =
            (0..3).map(|k| (viewer.position_m[k] - self.center_m[k]).powi(2)).sum::<f64>().sqrt();
        let zoom = (REFERENCE_HEIGHT_PX / f64::from(viewer.height_px.max(1)))
            * (viewer.vertical_fov_deg.to_radians() / 2.0).tan()
            / (REFERENCE_FOV_RAD / 2.0).tan();
        let d = d_m * self.units_per_m * zoom;
        let level = self.ranges.iter().take_while(|&&r| d >= r).count() as u32;
        level.min(self.levels.saturating_sub(1))
    }
}

impl Levels {
    /// Per triangle, whether the viewer sees it; `None` when the mesh has no LOD (all shown).
    pub fn shown(&self, viewer: &Viewer) -> Option<Vec<bool>> {
        if self.lods.is_empty() {
            return None;
        }
        let chosen: Vec<u32> = self.lods.iter().map(|l| l.level_for(viewer)).collect();
        let path_shown: Vec<bool> = self
            .paths
            .iter()
            .map(|p| p.iter().all(|&(lod, level)| chosen[lod as usize] == level))
            .collect();
        Some(self.of_triangle.iter().map(|&p| path_shown[p as usize]).collect())
    }

    /// The index of `path` in `paths`, added if new.
    pub fn path_index(&mut self, path: &[(u32, u32)]) -> u32 {
        if self.paths.is_empty() {
            self.paths.push(Vec::new());
        }
        match self.paths.iter().position(|p| p == path) {
            Some(i) => i as u32,
            None => {
                self.paths.push(path.to_vec());
                (self.paths.len() - 1) as u32
            }
        }
    }

    /// Placed by `m` (the object's transform, file to scene): the centres move, and the
    /// LODs' units per metre follow the transform's scaling (its linear part's cube root of
    /// |det|, exact for a uniform scale).
    pub fn transform(&mut self, m: glam::DMat4) {
        let scale = glam::DMat3::from_mat4(m).determinant().abs().cbrt();
        for lod in &mut self.lods {
            lod.center_m = m.transform_point3(glam::DVec3::from_array(lod.center_m)).to_array();
            if scale > 0.0 {
                lod.units_per_m /= scale;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lod() -> Lod {
        Lod { center_m: [0.0; 3], units_per_m: 1.0, ranges: vec![10.0, 50.0], levels: 3 }
    }

    /// In the reference view the ranges are distances; twice the pixels halves them; a LOD
    /// with fewer levels than ranges shows its last.
    #[test]
    fn levels_follow_the_projected_size() {
        let at = |d: f64, height_px: u32| Viewer {
            position_m: [d, 0.0, 0.0],
            vertical_fov_deg: 45.0,
            height_px,
        };
        assert_eq!(lod().level_for(&at(9.0, 480)), 0);
        assert_eq!(lod().level_for(&at(10.0, 480)), 1);
        assert_eq!(lod().level_for(&at(60.0, 480)), 2);
        // 960 pixels high: at 15 m the object looks as large as at 7.5 m in the reference.
        assert_eq!(lod().level_for(&at(15.0, 960)), 0);
        assert_eq!(lod().level_for(&at(15.0, 480)), 1);
        let two = Lod { levels: 2, ..lod() };
        assert_eq!(two.level_for(&at(60.0, 480)), 1);
    }
}
