//! Extrusion (§6.18): a cross-section swept along a spine, scaled and turned at each spine
//! point, in the spine-aligned cross-section plane (SCP) the standard defines.

use super::builder::Builder;
use super::faces::{Faces, Local, Rules, triangulate_faces};
use super::math::{V3, add, apply_linear, cross, dot, linear, normalized, rotation, sub};
use super::parser::Node;

/// The fields of an Extrusion, read and checked.
pub(super) struct Sweep {
    pub spine: Vec<V3>,
    pub section: Vec<[f64; 2]>,
    /// One per spine point, or one for all.
    pub scale: Vec<[f64; 2]>,
    pub orientation: Vec<[f64; 4]>,
    pub begin_cap: bool,
    pub end_cap: bool,
    pub ccw: bool,
}

/// The SCP of one spine point: its X, Y and Z axes (§6.18).
type Frame = [V3; 3];

impl Builder<'_> {
    /// §6.18's fields, with their defaults: a 2 × 2 square swept from y = 0 to y = 1.
    pub(super) fn extrusion(&self, node: &Node, name: &str) -> crate::Result<Local> {
        let sweep = Sweep {
            spine: self.tuples(node, "spine", &[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])?,
            section: self.tuples(
                node,
                "crossSection",
                &[[1.0, 1.0], [1.0, -1.0], [-1.0, -1.0], [-1.0, 1.0], [1.0, 1.0]],
            )?,
            scale: self.per_spine_point(node, "scale", [1.0, 1.0])?,
            orientation: self.per_spine_point(node, "orientation", [0.0, 0.0, 1.0, 0.0])?,
            begin_cap: self.boolean(node, "beginCap", true)?,
            end_cap: self.boolean(node, "endCap", true)?,
            ccw: self.boolean(node, "ccw", true)?,
        };
        if sweep.scale.len() != 1 && sweep.scale.len() != sweep.spine.len()
            || sweep.orientation.len() != 1 && sweep.orientation.len() != sweep.spine.len()
        {
            let which =
                if sweep.orientation.len() != 1 && sweep.orientation.len() != sweep.spine.len() {
                    "orientation"
                } else {
                    "scale"
                };
            return Err(self.invalid_field(
                node,
                which,
                format!(
                    "give one {which} for all {} spine points or one for each (§6.18)",
                    sweep.spine.len()
                ),
            ));
        }
        if let Some(s) = sweep.scale.iter().flatten().find(|s| **s < 0.0) {
            return Err(self.invalid_field(
                node,
                "scale",
                format!("{s} is negative; a scale of the cross-section is 0 or more (§6.18)"),
            ));
        }
        let rules = Rules {
            convex: self.boolean(node, "convex", true)?,
            crease: self.numbers(node, "creaseAngle", [0.0])?[0],
            solid: self.boolean(node, "solid", true)?,
        };
        let points = (sweep.spine.len() as u64).saturating_mul(sweep.section.len() as u64);
        self.check_points(node, points)?;
        let (points, faces) = sweep.faces();
        if let Some(&(_, len)) = faces.spans.iter().find(|s| s.1 as u64 > self.max_polygon_vertices)
        {
            return Err(crate::error::SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!(
                    "the number of vertices of a cap of the Extrusion at {}:{}",
                    node.pos.line, node.pos.column
                ),
                value: len as u64,
                limit: self.max_polygon_vertices,
                fix: "use fewer crossSection points, or raise the limit with \
                      --max-polygon-vertices"
                    .to_string(),
            });
        }
        triangulate_faces(&points, &faces, rules, self.max_triangles)
            .ok_or_else(|| self.too_many_triangles(name))
    }

    /// A list field of `N`-number values (`default` when absent).
    fn tuples<const N: usize>(
        &self,
        node: &Node,
        name: &str,
        default: &[[f64; N]],
    ) -> crate::Result<Vec<[f64; N]>> {
        let Some(nums) = self.finite_list(node, name)? else { return Ok(default.to_vec()) };
        if nums.len() % N != 0 {
            return Err(self.invalid_field(
                node,
                name,
                format!(
                    "{} numbers is not a whole number of values of {N}; add or remove numbers",
                    nums.len()
                ),
            ));
        }
        Ok(nums.chunks_exact(N).map(|c| std::array::from_fn(|k| c[k])).collect())
    }

    fn per_spine_point<const N: usize>(
        &self,
        node: &Node,
        name: &str,
        default: [f64; N],
    ) -> crate::Result<Vec<[f64; N]>> {
        let values = self.tuples(node, name, &[default])?;
        Ok(if values.is_empty() { vec![default] } else { values })
    }
}

impl Sweep {
    /// §6.18: "the first and last spine points are the same" makes a closed spine (three
    /// points at least, or it is a point).
    fn closed_spine(&self) -> bool {
        self.spine.len() > 2 && self.spine.first() == self.spine.last()
    }

    fn closed_section(&self) -> bool {
        self.section.len() > 2 && self.section.first() == self.section.last()
    }

    /// The points of every spine point's cross-section and the faces over them: the sides,
    /// then the caps. A closed spine or cross-section shares its seam's points, so the
    /// surface is closed there and smooth normals cross it.
    pub fn faces(&self) -> (Vec<V3>, Faces) {
        let mut faces = Faces::default();
        let (n, m) = (self.spine.len(), self.section.len());
        let Some(frames) = frames(&self.spine) else { return (Vec::new(), faces) };
        let rings: Vec<Vec<V3>> = (0..n).map(|i| self.ring(i, &frames[i])).collect();
        let width = if self.closed_section() { m - 1 } else { m };
        let seam = self.closed_spine() && rings[0] == rings[n - 1];
        let distinct = if seam { n - 1 } else { n };
        let points: Vec<V3> = rings[..distinct].iter().flat_map(|r| r[..width].to_vec()).collect();
        let at = |i: usize, j: usize| ((i % distinct) * width + j % width) as u32;
        for i in 0..n.saturating_sub(1) {
            for j in 0..m.saturating_sub(1) {
                // Along the cross-section, then along the spine: outward for a cross-section
                // counter-clockwise seen from the spine's direction (like the default one).
                let quad = [at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)];
                self.push(&mut faces, quad.to_vec(), false);
            }
        }
        // Caps of a closed spine would meet back to back inside the solid: they are left out.
        if width >= 3 && !seam {
            if self.begin_cap {
                self.push(&mut faces, (0..width).map(|j| at(0, j)).collect(), true);
            }
            if self.end_cap {
                self.push(&mut faces, (0..width).map(|j| at(n - 1, j)).collect(), false);
            }
        }
        (points, faces)
    }

    /// A face in the order given (reversed when `reverse`, once more for `ccw FALSE`).
    fn push(&self, faces: &mut Faces, mut corners: Vec<u32>, reverse: bool) {
        if reverse == self.ccw {
            corners.reverse();
        }
        faces.push(corners);
    }

    /// The cross-section at spine point `i`: scaled, turned by the orientation, then placed
    /// in the SCP (§6.18).
    fn ring(&self, i: usize, frame: &Frame) -> Vec<V3> {
        let [sx, sz] = self.scale[i.min(self.scale.len() - 1)];
        let [ax, ay, az, angle] = self.orientation[i.min(self.orientation.len() - 1)];
        let turn = linear(&rotation([ax, ay, az], angle));
        let [x, y, z] = *frame;
        self.section
            .iter()
            .map(|&[cx, cz]| {
                let p = apply_linear(&turn, [sx * cx, 0.0, sz * cz]);
                let offset =
                    add(add(x.map(|c| c * p[0]), y.map(|c| c * p[1])), z.map(|c| c * p[2]));
                add(self.spine[i], offset)
            })
            .collect()
    }
}

/// §6.18's SCP at every spine point; `None` when all the spine points are one point.
pub(super) fn frames(spine: &[V3]) -> Option<Vec<Frame>> {
    let n = spine.len();
    if n < 2 {
        return None;
    }
    let closed = n > 2 && spine[0] == spine[n - 1];
    let ys = fill(&y_axes(spine, closed))?;
    let Some(zs) = fill(&z_axes(spine, closed)) else {
        // The entire spine is collinear: the SCP is the rotation taking +Y to the spine's
        // direction, applied to the standard X and Z axes.
        let turn = turn_y_to(ys[0]);
        let frame = [0, 2].map(|k| apply_linear(&turn, std::array::from_fn(|c| f64::from(c == k))));
        return Some(ys.iter().map(|&y| [frame[0], y, frame[1]]).collect());
    };
    let mut frames = Vec::with_capacity(n);
    let mut previous: Option<V3> = None;
    for (&y, &z) in ys.iter().zip(&zs) {
        // "If the angle between two consecutive Z-axes is greater than 90°, the Z-axis is
        // flipped", so the cross-section does not turn over at an inflection.
        let mut z = match previous {
            Some(p) if dot(p, z) < 0.0 => z.map(|c| -c),
            _ => z,
        };
        previous = Some(z);
        // Z is perpendicular to Y by construction; this only removes rounding.
        z = normalized(sub(z, y.map(|c| c * dot(y, z)))).unwrap_or(z);
        let x = normalized(cross(y, z)).unwrap_or([1.0, 0.0, 0.0]);
        frames.push([x, y, z]);
    }
    Some(frames)
}

/// Y: the spine's direction at each point (the difference of its neighbours; at the ends of
/// an open spine, of the end segment; at the seam of a closed one, across the seam).
fn y_axes(spine: &[V3], closed: bool) -> Vec<Option<V3>> {
    let n = spine.len();
    (0..n)
        .map(|i| {
            let (a, b) = match i {
                _ if closed && (i == 0 || i == n - 1) => (spine[1], spine[n - 2]),
                0 => (spine[1], spine[0]),
                _ if i == n - 1 => (spine[n - 1], spine[n - 2]),
                _ => (spine[i + 1], spine[i - 1]),
            };
            normalized(sub(a, b))
        })
        .collect()
}

/// Z: the normal of the spine's bend at each point, `(next − here) × (previous − here)`; the
/// ends of an open spine take their neighbour's; undefined (`None`) where the spine is
/// straight.
fn z_axes(spine: &[V3], closed: bool) -> Vec<Option<V3>> {
    let n = spine.len();
    let bend = |here: usize, next: usize, previous: usize| {
        normalized(cross(sub(spine[next], spine[here]), sub(spine[previous], spine[here])))
    };
    let mut zs: Vec<Option<V3>> =
        (0..n).map(|i| if i == 0 || i == n - 1 { None } else { bend(i, i + 1, i - 1) }).collect();
    if closed {
        zs[0] = bend(0, 1, n - 2);
        zs[n - 1] = zs[0];
    } else if n > 2 {
        zs[0] = zs[1];
        zs[n - 1] = zs[n - 2];
    }
    zs
}

/// §6.18: an undefined axis takes the previous point's; the first ones take the first defined
/// one. `None` when no point defines it.
fn fill(axes: &[Option<V3>]) -> Option<Vec<V3>> {
    let first = axes.iter().flatten().next().copied()?;
    let mut last = first;
    Some(
        axes.iter()
            .map(|a| {
                last = a.unwrap_or(last);
                last
            })
            .collect(),
    )
}

/// The rotation taking +Y onto the unit vector `to` (about their common perpendicular).
fn turn_y_to(to: V3) -> [[f64; 3]; 3] {
    let from = [0.0, 1.0, 0.0];
    let axis = cross(from, to);
    let angle = dot(from, to).clamp(-1.0, 1.0).acos();
    if normalized(axis).is_none() {
        // Parallel or opposite: no turn, or a half turn about X.
        return linear(&rotation([1.0, 0.0, 0.0], if dot(from, to) < 0.0 { angle } else { 0.0 }));
    }
    linear(&rotation(axis, angle))
}
