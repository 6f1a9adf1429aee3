//! A leaf's triangles, four in the lanes of one test: the Möller–Trumbore intersection (Möller &
//! Trumbore 1997, "Fast, minimum storage ray–triangle intersection") in the edge layout obvhs's
//! `RtTriangle` uses (e1 = v0 − v1, e2 = v2 − v0, n = e1 × e2), as Embree's `Triangle4` leaves
//! test theirs.

use super::traverse::BoxRay;
use glam::{BVec4A, Vec3A, Vec4};
use obvhs::triangle::Triangle;

/// Up to four triangles as lanes; an unused lane is all zeros, whose normal is zero, which no
/// ray hits.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Leaf4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    normal: [Vec4; 3],
    /// The slot (BVH order) of lane 0; lane k is slot `first + k`.
    first: u32,
}

impl Leaf4 {
    /// The leaf of `triangles` (one to four), whose first is slot `first`.
    pub(super) fn new<'a>(triangles: impl Iterator<Item = &'a Triangle>, first: u32) -> Self {
        let mut leaf = Leaf4 {
            v0: [Vec4::ZERO; 3],
            e1: [Vec4::ZERO; 3],
            e2: [Vec4::ZERO; 3],
            normal: [Vec4::ZERO; 3],
            first,
        };
        for (lane, t) in triangles.take(4).enumerate() {
            let (e1, e2) = (t.v0 - t.v1, t.v2 - t.v0);
            let columns: [(&mut [Vec4; 3], Vec3A); 4] = [
                (&mut leaf.v0, t.v0),
                (&mut leaf.e1, e1),
                (&mut leaf.e2, e2),
                (&mut leaf.normal, e1.cross(e2)),
            ];
            for (column, value) in columns {
                for axis in 0..3 {
                    column[axis][lane] = value[axis];
                }
            }
        }
        leaf
    }

    /// The closest of the four hits nearer than `t_max` (and not behind the origin): its slot
    /// and distance. Ties go to the lowest lane.
    #[inline(always)]
    pub(super) fn closest(&self, ray: &BoxRay, t_max: f32) -> Option<(u32, f32)> {
        let (t, hit) = self.hits(ray, t_max);
        if !hit.any() {
            return None;
        }
        let t = Vec4::select(hit, t, Vec4::INFINITY);
        let nearest = t.min_element();
        let lane = t.cmpeq(Vec4::splat(nearest)).bitmask().trailing_zeros();
        Some((self.first + lane, nearest))
    }

    /// Whether any of the four is hit nearer than `t_max`.
    #[inline(always)]
    pub(super) fn any(&self, ray: &BoxRay, t_max: f32) -> bool {
        self.hits(ray, t_max).1.any()
    }

    /// The four distances, and the lanes whose triangle the ray meets in [0, `t_max`).
    /// A point on an edge counts as inside (u, v, w ≥ 0), so two triangles sharing an edge leave
    /// no crack between them.
    #[inline(always)]
    fn hits(&self, ray: &BoxRay, t_max: f32) -> (Vec4, BVec4A) {
        let [ox, oy, oz] = ray.origin;
        let [dx, dy, dz] = ray.direction;
        let (cx, cy, cz) = (self.v0[0] - ox, self.v0[1] - oy, self.v0[2] - oz);
        // r = d × c
        let rx = dy * cz - dz * cy;
        let ry = dz * cx - dx * cz;
        let rz = dx * cy - dy * cx;
        let [nx, ny, nz] = self.normal;
        let det = nx * dx + ny * dy + nz * dz;
        let inverse = Vec4::ONE / det;
        let u = (rx * self.e2[0] + ry * self.e2[1] + rz * self.e2[2]) * inverse;
        let v = (rx * self.e1[0] + ry * self.e1[1] + rz * self.e1[2]) * inverse;
        let w = Vec4::ONE - u - v;
        let t = (nx * cx + ny * cy + nz * cz) * inverse;
        let inside = u.cmpge(Vec4::ZERO) & v.cmpge(Vec4::ZERO) & w.cmpge(Vec4::ZERO);
        let ahead = t.cmpge(Vec4::ZERO) & t.cmplt(Vec4::splat(t_max));
        (t, inside & ahead & det.cmpne(Vec4::ZERO))
    }
}
