//! A coarser copy of a big model for the studio to draw while the view moves: vertex clustering
//! (Rossignac & Borrel, "Multi-resolution 3D approximations for rendering complex scenes",
//! 1993). Space is cut into cubes of one size; every vertex in a cube is replaced by the first
//! vertex found there, and the triangles that collapse (two corners in one cube) or repeat
//! vanish. No vertex is moved or added, so the coarse triangles index the model's own vertex
//! buffer and cost only their indices. The cube's edge is chosen from the model's surface area
//! so that about [`TARGET_TRIANGLES`] remain.

use restauro_scene::load::LoadedScene;
use std::collections::{HashMap, HashSet};

/// About how many triangles the coarse copy keeps.
pub const TARGET_TRIANGLES: usize = 100_000;

/// The cube edge (m) that leaves about `target` of the visible triangles of `scene`, or `None`
/// when it has no more than twice that (drawn whole while moving, too).
pub fn cell_size_m(scene: &LoadedScene, target: usize) -> Option<f64> {
    let (mut area_m2, mut count) = (0.0f64, 0usize);
    for o in &scene.objects {
        for (t, g) in o.mesh.triangles.iter().zip(&o.mesh.triangle_group) {
            if o.hidden_groups[*g as usize] {
                continue;
            }
            let [a, b, c] = t.map(|i| o.mesh.positions[i as usize].map(f64::from));
            let (u, v) = (sub(b, a), sub(c, a));
            let n =
                [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            area_m2 += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            count += 1;
        }
    }
    // A surface cut by cubes of edge s keeps about two triangles per s² of its area.
    (count > 2 * target && area_m2 > 0.0).then(|| (2.0 * area_m2 / target as f64).sqrt())
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// For each vertex, the vertex that stands for its cube of edge `cell_m`.
pub fn representatives(positions: &[[f32; 3]], cell_m: f64) -> Vec<u32> {
    let mut first: HashMap<[i64; 3], u32> = HashMap::new();
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let key = p.map(|c| (f64::from(c) / cell_m).floor() as i64);
            *first.entry(key).or_insert(i as u32)
        })
        .collect()
}

/// `triangles` (vertex indices, three by three) with every vertex replaced by its
/// representative, those collapsed or repeated left out.
pub fn coarse_indices(triangles: &[u32], representative: &[u32]) -> Vec<u32> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for t in triangles.chunks_exact(3) {
        let r = [t[0], t[1], t[2]].map(|v| representative[v as usize]);
        if r[0] == r[1] || r[1] == r[2] || r[0] == r[2] {
            continue;
        }
        let mut key = r;
        key.sort_unstable();
        if seen.insert(key) {
            out.extend_from_slice(&r);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat grid of n × n squares (2 n² triangles) over 1 m × 1 m.
    fn grid(n: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
        let step = 1.0 / n as f32;
        let positions = (0..=n)
            .flat_map(|y| (0..=n).map(move |x| [x as f32 * step, y as f32 * step, 0.0]))
            .collect();
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let triangles = (0..n)
            .flat_map(|y| {
                (0..n).flat_map(move |x| {
                    [
                        at(x, y),
                        at(x + 1, y),
                        at(x + 1, y + 1),
                        at(x, y),
                        at(x + 1, y + 1),
                        at(x, y + 1),
                    ]
                })
            })
            .collect();
        (positions, triangles)
    }

    #[test]
    fn a_grid_keeps_about_two_triangles_per_cell_and_its_winding() {
        let (positions, triangles) = grid(100);
        // Cubes of 0.1 m over 1 m²: 10 × 10 cells, so about 200 triangles of 20 000.
        let reps = representatives(&positions, 0.1);
        let coarse = coarse_indices(&triangles, &reps);
        let kept = coarse.len() / 3;
        assert!((150..=250).contains(&kept), "{kept} triangles kept");
        // Every kept triangle faces the way the grid does (+z): none is turned over.
        for t in coarse.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(z > 0.0, "{t:?} turned over");
        }
        // A cube larger than the model leaves nothing; one smaller than a square, everything.
        assert!(coarse_indices(&triangles, &representatives(&positions, 10.0)).is_empty());
        assert_eq!(
            coarse_indices(&triangles, &representatives(&positions, 0.001)).len(),
            triangles.len()
        );
    }
}
