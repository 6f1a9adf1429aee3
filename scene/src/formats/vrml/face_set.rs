//! IndexedFaceSet (§6.23): its points and faces, checked, triangulated with normals.

use super::builder::{Builder, place};
use super::faces::{Faces, Local, Rules, triangulate_faces};
use super::lexer::Pos;
use super::math::{V3, fits_f32};
use super::parser::{Node, Value};
use crate::error::SceneError;

impl Builder<'_> {
    /// An IndexedFaceSet in its own coordinates: triangles with counter-clockwise fronts and
    /// per-vertex normals.
    pub(super) fn face_set(&self, node: &Node, name: &str) -> crate::Result<Local> {
        let ccw = self.boolean(node, "ccw", true)?;
        let rules = Rules {
            solid: self.boolean(node, "solid", true)?,
            convex: self.boolean(node, "convex", true)?,
            crease: self.numbers(node, "creaseAngle", [0.0])?[0],
        };
        let points = self.points(node)?;
        let faces = self.faces(node, points.len(), name, ccw)?;
        triangulate_faces(&points, &faces, rules, self.max_triangles)
            .ok_or_else(|| self.too_many_triangles(name))
    }

    /// §6.12: the points of the `coord` Coordinate node, each finite.
    fn points(&self, node: &Node) -> crate::Result<Vec<V3>> {
        let Some(coord) = node.first_node("coord") else { return Ok(Vec::new()) };
        let Some(field) = coord.field("point") else { return Ok(Vec::new()) };
        let (nums, places): (&[f64], &[Pos]) = match &*field.value {
            Value::Nums(nums, places) => (nums, places),
            _ => (&[], &[]),
        };
        if nums.len() % 3 != 0 {
            return Err(SceneError::invalid(
                &*self.path,
                place(field, coord),
                format!(
                    "{} numbers is not a whole number of points (3 numbers each); add or remove \
                     numbers so each point has x, y and z",
                    nums.len()
                ),
            ));
        }
        for (i, &n) in nums.iter().enumerate() {
            if !fits_f32(n) {
                let at = places.get(i).copied().unwrap_or(field.pos);
                return Err(SceneError::syntax(
                    &*self.path,
                    at.line as usize,
                    at.column as usize,
                    format!(
                        "coordinate {} of point {} of the Coordinate is not a finite number \
                         ({n}); fix the coordinate",
                        i % 3,
                        i / 3
                    ),
                ));
            }
        }
        Ok(nums.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// §6.23: `coordIndex`, faces separated by −1 (the last may lack it), each index a point.
    fn faces(&self, node: &Node, count: usize, name: &str, ccw: bool) -> crate::Result<Faces> {
        let mut faces = Faces::default();
        let Some(field) = node.field("coordIndex") else { return Ok(faces) };
        let (nums, places): (&[f64], &[Pos]) = match &*field.value {
            Value::Nums(nums, places) => (nums, places),
            _ => (&[], &[]),
        };
        let mut start = 0usize;
        let mut face_start_pos = places.first().copied().unwrap_or(field.pos);
        let at = |i: usize| places.get(i).copied().unwrap_or(field.pos);
        for (i, &n) in nums.iter().enumerate() {
            let end_of_face = n == -1.0;
            if !end_of_face {
                if n.fract() != 0.0 || n < 0.0 || n >= count as f64 {
                    let pos = at(i);
                    return Err(SceneError::syntax(
                        &*self.path,
                        pos.line as usize,
                        pos.column as usize,
                        format!(
                            "coordIndex {n} (entry {i} of shape `{name}`) is out of range: the \
                             Coordinate has {count} points, so indices run from 0 to {} (−1 ends \
                             a face); fix the index or add the point",
                            count as i64 - 1
                        ),
                    ));
                }
                faces.corners.push(n as u32);
            }
            if (faces.corners.len() - start) as u64 > self.max_polygon_vertices {
                let pos = face_start_pos;
                return Err(SceneError::Limit {
                    path: self.path.to_path_buf(),
                    what: format!(
                        "the number of vertices of face {} of shape `{name}` at {}:{}",
                        faces.spans.len(),
                        pos.line,
                        pos.column
                    ),
                    value: (faces.corners.len() - start) as u64,
                    limit: self.max_polygon_vertices,
                    fix: "split the polygon into smaller faces, or raise the limit with \
                          --max-polygon-vertices"
                        .to_string(),
                });
            }
            if end_of_face || i + 1 == nums.len() {
                let len = faces.corners.len() - start;
                if len < 3 {
                    return Err(SceneError::syntax(
                        &*self.path,
                        face_start_pos.line as usize,
                        face_start_pos.column as usize,
                        format!(
                            "face {} of shape `{name}` has {len} vert{} but a face needs at least \
                             3; remove the face or add vertices",
                            faces.spans.len(),
                            if len == 1 { "ex" } else { "ices" }
                        ),
                    ));
                }
                if !ccw {
                    faces.corners[start..].reverse();
                }
                faces.spans.push((start, len));
                start = faces.corners.len();
                face_start_pos = at(i + 1);
            }
        }
        Ok(faces)
    }
}
