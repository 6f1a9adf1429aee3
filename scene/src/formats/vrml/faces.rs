//! Polygons to triangles with per-vertex normals (§6.23's rules, which §6.17 ElevationGrid and
//! §6.18 Extrusion refer to): what an IndexedFaceSet, an ElevationGrid, an Extrusion and a Box
//! all become, in their own coordinates, before a transform places them.

use std::collections::HashMap;

use super::math::{V3, add, cross, dot, normalized, sub};

/// Polygons with more vertices than this are fanned even when `convex FALSE`: ear clipping is
/// quadratic to cubic in the vertex count.
const MAX_EAR_CLIP_VERTICES: usize = 512;
/// Vertices shared by more faces than this get faceted normals: smoothing compares every pair
/// of faces around a vertex.
const MAX_SMOOTHED_FACES: usize = 256;

/// A geometry node triangulated in its own coordinates (what every `USE` of it shares).
#[derive(Debug, Default)]
pub(super) struct Local {
    /// Point and unit normal of each vertex.
    pub vertices: Vec<(V3, V3)>,
    /// Counter-clockwise triangles, as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// `solid FALSE`.
    pub double_sided: bool,
}

impl Local {
    /// A vertex, returning its index.
    pub fn vertex(&mut self, point: V3, normal: V3) -> u32 {
        self.vertices.push((point, normal));
        (self.vertices.len() - 1) as u32
    }
}

/// Polygons ready to triangulate: point indices of every face, flat.
#[derive(Debug, Default)]
pub(super) struct Faces {
    /// Point indices, face after face, in counter-clockwise order.
    pub corners: Vec<u32>,
    /// `(start, len)` of each face in `corners`.
    pub spans: Vec<(usize, usize)>,
}

impl Faces {
    /// Appends a face (at least 3 corners, counter-clockwise seen from its front).
    pub fn push(&mut self, corners: impl IntoIterator<Item = u32>) {
        let start = self.corners.len();
        self.corners.extend(corners);
        self.spans.push((start, self.corners.len() - start));
    }
}

/// How polygons become triangles: §6.23's `convex`, `creaseAngle` and `solid`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rules {
    pub convex: bool,
    pub crease: f64,
    pub solid: bool,
}

/// Triangulates `faces` over `points`, with normals from the crease angle; `None` when the
/// triangles would exceed `max_triangles`. Zero-area triangles are dropped: they draw nothing.
pub(super) fn triangulate_faces(
    points: &[V3],
    faces: &Faces,
    rules: Rules,
    max_triangles: u64,
) -> Option<Local> {
    // Face normals, area-weighted (Newell's method: exact for planar polygons).
    let area_normals: Vec<V3> = faces
        .spans
        .iter()
        .map(|&(start, len)| newell(&faces.corners[start..start + len], points))
        .collect();
    let unit_normals: Vec<Option<V3>> = area_normals.iter().map(|&n| normalized(n)).collect();
    let around = Around::new(points.len(), faces);
    let cos_crease = rules.crease.cos();
    let mut local =
        Local { vertices: Vec::new(), triangles: Vec::new(), double_sided: !rules.solid };
    let mut vertex_of: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    let mut fan = Vec::new();
    for (f, &(start, len)) in faces.spans.iter().enumerate() {
        let face = &faces.corners[start..start + len];
        let Some(face_normal) = unit_normals[f] else { continue };
        fan.clear();
        triangulate(face, points, face_normal, rules.convex, &mut fan);
        for &[a, b, c] in &fan {
            let (pa, pb, pc) = (face[a], face[b], face[c]);
            let area = cross(
                sub(points[pb as usize], points[pa as usize]),
                sub(points[pc as usize], points[pa as usize]),
            );
            if dot(area, area).is_nan() || dot(area, area) <= 0.0 {
                continue; // zero-area triangles draw nothing
            }
            if local.triangles.len() as u64 >= max_triangles {
                return None;
            }
            let mut tri = [0u32; 3];
            for (slot, p) in tri.iter_mut().zip([pa, pb, pc]) {
                let normal = if rules.crease > 0.0 {
                    around
                        .smooth_normal(f, p, &area_normals, &unit_normals, cos_crease)
                        .unwrap_or(face_normal)
                } else {
                    face_normal
                };
                let key = (p, normal.map(|c| (c as f32).to_bits()));
                *slot = *vertex_of
                    .entry(key)
                    .or_insert_with(|| local.vertex(points[p as usize], normal));
            }
            local.triangles.push(tri);
        }
    }
    Some(local)
}

/// The faces around each point (compressed rows), for smoothing.
struct Around {
    first: Vec<usize>,
    faces: Vec<u32>,
}

impl Around {
    fn new(points: usize, faces: &Faces) -> Self {
        let mut first = vec![0usize; points + 1];
        for &p in &faces.corners {
            first[p as usize + 1] += 1;
        }
        for i in 0..points {
            first[i + 1] += first[i];
        }
        let mut fill = first.clone();
        let mut around = vec![0u32; faces.corners.len()];
        for (f, &(start, len)) in faces.spans.iter().enumerate() {
            for &p in &faces.corners[start..start + len] {
                around[fill[p as usize]] = f as u32;
                fill[p as usize] += 1;
            }
        }
        Around { first, faces: around }
    }

    /// §6.23 creaseAngle: the normal at point `p` of face `f` averages (weighted by area) the
    /// faces around `p` whose normals are within the crease angle of `f`'s.
    fn smooth_normal(
        &self,
        f: usize,
        p: u32,
        area_normals: &[V3],
        unit_normals: &[Option<V3>],
        cos_crease: f64,
    ) -> Option<V3> {
        let own = unit_normals.get(f).copied().flatten()?;
        let range = *self.first.get(p as usize)?..*self.first.get(p as usize + 1)?;
        let faces = self.faces.get(range)?;
        if faces.len() > MAX_SMOOTHED_FACES {
            return None;
        }
        let mut sum = [0.0; 3];
        let mut seen_self = false;
        for (k, &g) in faces.iter().enumerate() {
            if k > 0 && faces[k - 1] == g {
                continue; // a face that visits the point twice counts once (adjacent entries)
            }
            let Some(unit) = unit_normals.get(g as usize).copied().flatten() else { continue };
            if g as usize == f || dot(own, unit) > cos_crease {
                seen_self |= g as usize == f;
                sum = add(sum, area_normals[g as usize]);
            }
        }
        if !seen_self {
            sum = add(sum, area_normals[f]);
        }
        normalized(sum)
    }
}

pub(super) fn newell(face: &[u32], points: &[V3]) -> V3 {
    let mut n = [0.0; 3];
    for (k, &i) in face.iter().enumerate() {
        let a = points[i as usize];
        let b = points[face[(k + 1) % face.len()] as usize];
        n = add(
            n,
            [
                (a[1] - b[1]) * (a[2] + b[2]),
                (a[2] - b[2]) * (a[0] + b[0]),
                (a[0] - b[0]) * (a[1] + b[1]),
            ],
        );
    }
    n
}

/// Triangles (as corner numbers of `face`) covering the polygon: a fan for convex faces, ear
/// clipping in the polygon's dominant plane for `convex FALSE` (a fan when that fails).
pub(super) fn triangulate(
    face: &[u32],
    points: &[V3],
    normal: V3,
    convex: bool,
    out: &mut Vec<[usize; 3]>,
) {
    let n = face.len();
    if n == 3 || convex || n > MAX_EAR_CLIP_VERTICES {
        out.extend((1..n - 1).map(|k| [0, k, k + 1]));
        return;
    }
    // Drop the normal's largest axis; order the other two so the polygon turns
    // counter-clockwise in the plane.
    let axis =
        (0..3).fold(0, |best, k| if normal[k].abs() > normal[best].abs() { k } else { best });
    let (mut u, mut v) = ((axis + 1) % 3, (axis + 2) % 3);
    if normal[axis] < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let flat: Vec<[f64; 2]> =
        face.iter().map(|&i| [points[i as usize][u], points[i as usize][v]]).collect();
    let turn = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let mut left: Vec<usize> = (0..n).collect();
    let mut k = 0;
    let mut misses = 0;
    while left.len() > 3 {
        let m = left.len();
        let (ia, ib, ic) = (left[(k + m - 1) % m], left[k % m], left[(k + 1) % m]);
        let (a, b, c) = (flat[ia], flat[ib], flat[ic]);
        let is_ear = turn(a, b, c) > 0.0
            && !left.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let p = flat[j];
                if p == a || p == b || p == c {
                    return false;
                }
                turn(a, b, p) >= 0.0 && turn(b, c, p) >= 0.0 && turn(c, a, p) >= 0.0
            });
        if is_ear {
            out.push([ia, ib, ic]);
            left.remove(k % m);
            misses = 0;
            k %= m - 1;
        } else {
            misses += 1;
            k = (k + 1) % m;
            if misses >= m {
                // No ear: a self-intersecting or degenerate polygon. Fan what is left.
                out.extend((1..m - 1).map(|j| [left[0], left[j], left[j + 1]]));
                return;
            }
        }
    }
    out.push([left[0], left[1], left[2]]);
}
