//! The scene's calculation grids as the page lists and draws them: each as the file gives it
//! (the page edits the file: a georeferenced scene's `origin` back in), and where it is in the
//! GLB's frame — a rectangle's four corners, or a list's points — with the direction its
//! sensors face and its number of points.

use restauro_scene::load::LoadedScene;
use restauro_scene::scene_file::Grid;
use serde::Serialize;

#[derive(Serialize)]
pub struct GridView {
    pub name: String,
    /// As the file gives it.
    pub grid: Grid,
    /// A rectangle's corners in the GLB's frame: origin, origin + u, origin + u + v,
    /// origin + v (so that u runs along the first edge and v along the last).
    pub corners: Option<[[f64; 3]; 4]>,
    /// A list's points in the GLB's frame (empty for a rectangle).
    pub points: Vec<[f64; 3]>,
    /// The unit direction the sensors face, in the GLB's frame.
    pub normal: [f64; 3],
    pub divisions: Option<[u32; 2]>,
    pub point_count: usize,
}

/// The grids of `scene`, placed in the GLB's frame by `to_glb` (a point of the recentred scene)
/// and `direction_to_glb` (a direction).
pub fn grid_views(
    scene: &LoadedScene,
    to_glb: impl Fn([f64; 3]) -> [f64; 3],
    direction_to_glb: impl Fn([f64; 3]) -> [f64; 3],
) -> Vec<GridView> {
    // The grids resolve one to one and in the file's order.
    scene
        .file
        .grids
        .iter()
        .zip(&scene.grids)
        .map(|(file, resolved)| {
            let corners = match (file.origin, file.u, file.v) {
                (Some(o), Some(u), Some(v)) if resolved.divisions.is_some() => {
                    let at = |a: f64, b: f64| {
                        to_glb(std::array::from_fn(|k| o[k] + a * u[k] + b * v[k]))
                    };
                    Some([at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)])
                }
                _ => None,
            };
            let points = if corners.is_some() {
                Vec::new()
            } else {
                resolved.points.iter().map(|&p| to_glb(p)).collect()
            };
            let mut grid = file.clone();
            let back = |p: [f64; 3]| restauro_scene::origin::to_file(p, scene.origin_m);
            grid.origin = grid.origin.map(back);
            grid.points = grid.points.map(|ps| ps.into_iter().map(back).collect());
            GridView {
                name: file.name.clone(),
                grid,
                corners,
                points,
                normal: direction_to_glb(resolved.normal),
                divisions: resolved.divisions,
                point_count: resolved.points.len(),
            }
        })
        .collect()
}
