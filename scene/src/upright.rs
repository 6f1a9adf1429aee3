//! Whether a mesh read as Z-up probably lies on its back: a model exported Y-up (as most
//! modelling tools and many scanners write OBJ and PLY) read without `up_axis = "y"`.
//!
//! The evidence is the mesh's *net area vector*, Σ ½ (b − a) × (c − a) over its triangles. For
//! a closed surface it is zero (the divergence theorem); a survey is never closed, and what is
//! missing is what nobody could see: the underside. A scan of a statue lacks its base, a
//! building's survey has its ground and roofs but no ceilings of the earth below, so the net
//! vector of what remains points *up*. When it points along +Y instead of +Z, the model was most
//! likely written Y-up.
//!
//! Guards keep the hint quiet where it would be a guess. The net vector must be a noticeable
//! part of the whole area: a closed model, or one whose faces are wound inconsistently, has
//! none to speak of (the Stanford bunny, Y-up with small holes in its base, has 1.7 % of its
//! area, 19° from +Y). And the mesh must not be a *sheet* facing +Y, most of its area facing one
//! way or nearly flat: a Z-up facade scanned from the north and a Y-up terrain are the same
//! triangles, and nothing can tell them apart. A false hint costs more than a missed one, since
//! `scene new` acts on it.

use crate::mesh::Mesh;

/// The net area vector must be at least this share of the total area…
const MIN_NET_SHARE: f64 = 0.01;
/// …and at most this: beyond it, the mesh is mostly one sheet facing one way.
const MAX_NET_SHARE: f64 = 0.6;
/// …and within this angle of +Y.
const MAX_ANGLE_DEG: f64 = 30.0;
/// A mesh thinner than this share of its other extents along Y is a sheet, and ambiguous.
const MIN_DEPTH_SHARE: f64 = 0.05;

/// What the hint rests on, for the note that gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct YUpEvidence {
    /// The angle between the net area vector and +Y, in degrees.
    pub angle_to_y_deg: f64,
    /// The net area vector's length as a share of the total area.
    pub net_share: f64,
}

/// The evidence that `mesh`, in its file's coordinates, is Y-up, if it is strong enough.
pub fn y_up_evidence(mesh: &Mesh) -> Option<YUpEvidence> {
    let (net, total) = net_area_vector(mesh);
    let length = (net[0] * net[0] + net[1] * net[1] + net[2] * net[2]).sqrt();
    if !(total > 0.0 && length >= MIN_NET_SHARE * total && length <= MAX_NET_SHARE * total) {
        return None;
    }
    let angle_to_y_deg = (net[1] / length).clamp(-1.0, 1.0).acos().to_degrees();
    if angle_to_y_deg > MAX_ANGLE_DEG {
        return None;
    }
    let b = mesh.bounds()?;
    let size: [f64; 3] = std::array::from_fn(|k| f64::from(b.max[k]) - f64::from(b.min[k]));
    if size[1] < MIN_DEPTH_SHARE * size[0].max(size[2]) {
        return None;
    }
    Some(YUpEvidence { angle_to_y_deg, net_share: length / total })
}

/// Σ ½ (b − a) × (c − a), and Σ of the triangles' areas (m²), in f64.
fn net_area_vector(mesh: &Mesh) -> ([f64; 3], f64) {
    let mut net = [0.0f64; 3];
    let mut total = 0.0f64;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].map(f64::from));
        let u: [f64; 3] = std::array::from_fn(|k| b[k] - a[k]);
        let v: [f64; 3] = std::array::from_fn(|k| c[k] - a[k]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if area.is_finite() {
            total += area;
            for k in 0..3 {
                net[k] += 0.5 * n[k];
            }
        }
    }
    (net, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Group;

    /// A Z-up house without a floor: four walls (width × depth × height) and a flat roof, faces
    /// wound outwards, plus an optional sheet of ground around it.
    fn house(width: f32, depth: f32, height: f32, ground: bool) -> Mesh {
        let mut mesh = Mesh { groups: vec![Group::named("stone")], ..Mesh::default() };
        let mut quad = |p: [[f32; 3]; 4]| {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend_from_slice(&p);
            mesh.triangles.push([base, base + 1, base + 2]);
            mesh.triangles.push([base, base + 2, base + 3]);
            mesh.triangle_group.extend([0, 0]);
        };
        let (x, y, z) = (width, depth, height);
        quad([[0., 0., 0.], [x, 0., 0.], [x, 0., z], [0., 0., z]]); // south, facing −Y
        quad([[x, y, 0.], [0., y, 0.], [0., y, z], [x, y, z]]); // north, +Y
        quad([[0., y, 0.], [0., 0., 0.], [0., 0., z], [0., y, z]]); // west, −X
        quad([[x, 0., 0.], [x, y, 0.], [x, y, z], [x, 0., z]]); // east, +X
        quad([[0., 0., z], [x, 0., z], [x, y, z], [0., y, z]]); // roof, +Z
        if ground {
            // A path 1 m wide along the south wall, facing +Z.
            quad([[0., -1., 0.], [x, -1., 0.], [x, 0., 0.], [0., 0., 0.]]);
        }
        mesh
    }

    /// The same mesh as a Y-up exporter writes it: world +Z becomes file +Y, world +Y file −Z.
    fn written_y_up(mut mesh: Mesh) -> Mesh {
        for p in &mut mesh.positions {
            *p = [p[0], p[2], -p[1]];
        }
        mesh
    }

    #[test]
    fn a_y_up_house_is_recognised_and_a_z_up_one_is_not() {
        for ground in [false, true] {
            let z_up = house(12.0, 8.0, 6.0, ground);
            assert_eq!(y_up_evidence(&z_up), None, "ground {ground}");
            let e = y_up_evidence(&written_y_up(z_up)).expect("the Y-up house is recognised");
            // Its net area vector is exactly the roof (and ground), pointing along +Y.
            assert!(e.angle_to_y_deg < 1e-6, "{e:?}");
            let area = if ground { 96.0 + 12.0 } else { 96.0 };
            let total = area + 2.0 * 12.0 * 6.0 + 2.0 * 8.0 * 6.0;
            assert!((e.net_share - area / total).abs() < 1e-9, "{e:?}");
        }
    }

    #[test]
    fn a_closed_model_and_a_single_wall_give_no_hint() {
        // Closed: the house with its floor (facing −Z).
        let mut closed = house(12.0, 8.0, 6.0, false);
        let n = closed.positions.len() as u32;
        closed.positions.extend([[0., 0., 0.], [0., 8., 0.], [12., 8., 0.], [12., 0., 0.]]);
        closed.triangles.extend([[n, n + 1, n + 2], [n, n + 2, n + 3]]);
        closed.triangle_group.extend([0, 0]);
        assert_eq!(net_area_vector(&closed).0.map(|v| (v.abs() < 1e-9) as u8), [1, 1, 1]);
        assert_eq!(y_up_evidence(&written_y_up(closed)), None);
        // A north wall alone, Z-up: it faces +Y but is a sheet.
        let mut wall = Mesh { groups: vec![Group::named("wall")], ..Mesh::default() };
        wall.positions = vec![[10., 0., 0.], [0., 0., 0.], [0., 0., 5.], [10., 0., 5.]];
        wall.triangles = vec![[0, 1, 2], [0, 2, 3]];
        wall.triangle_group = vec![0, 0];
        assert!(net_area_vector(&wall).0[1] > 0.0);
        assert_eq!(y_up_evidence(&wall), None);
        // …and with a buttress 1 m deep it is no longer flat, but still mostly one sheet.
        let n = wall.positions.len() as u32;
        wall.positions.extend([[6., 1., 0.], [4., 1., 0.], [4., 1., 5.], [6., 1., 5.]]);
        wall.positions.extend([[4., 1., 0.], [4., 0., 0.], [4., 0., 5.], [4., 1., 5.]]);
        wall.positions.extend([[6., 0., 0.], [6., 1., 0.], [6., 1., 5.], [6., 0., 5.]]);
        for q in 0..3 {
            let b = n + 4 * q;
            wall.triangles.extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
            wall.triangle_group.extend([0, 0]);
        }
        let (net, total) = net_area_vector(&wall);
        assert!((net[1] - 60.0).abs() < 1e-9 && (total - 70.0).abs() < 1e-9, "{net:?} {total}");
        assert_eq!(y_up_evidence(&wall), None);
    }
}
