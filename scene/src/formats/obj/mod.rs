//! Wavefront OBJ meshes, read with tobj. Parts are named by their `usemtl` material name, or
//! else by their `o`/`g` name, so that a scene can bind each to a spectral material.
//!
//! tobj drops `usemtl` names unless a `.mtl` library loads, and a scene's spectra replace the
//! library's colours anyway; so the reader hands tobj a library made up here with one entry per
//! `usemtl` name in the file, and never opens `.mtl` files itself (the library's photos are
//! read by [`crate::formats::obj::library`]). Faces are checked before tobj reads them, so that a refusal names its line (tobj's
//! errors carry no position, and it takes a two-vertex face for a degenerate triangle).

pub mod library;

use crate::error::{Result, SceneError};
use crate::guard;
use crate::limits::Limits;
use crate::mesh::{Group, Mesh};
use std::collections::{BTreeSet, HashMap};
use std::path::Path;

/// The `usemtl` names of an OBJ text, in first-use order.
fn usemtl_names(text: &str) -> Vec<String> {
    let mut seen = BTreeSet::new();
    let mut names = Vec::new();
    for line in text.lines() {
        if let Some(name) = line.trim_start().strip_prefix("usemtl") {
            let name = name.trim().to_owned();
            if !name.is_empty() && seen.insert(name.clone()) {
                names.push(name);
            }
        }
    }
    names
}

/// One line of an OBJ text split at whitespace, with its number for messages.
struct ObjLine<'a> {
    path: &'a Path,
    /// 1-based line number.
    number: usize,
    line: &'a str,
    keyword: &'a str,
    rest: Vec<&'a str>,
}

impl ObjLine<'_> {
    fn refuse(&self, problem: String) -> SceneError {
        SceneError::invalid(self.path, format!("line {}", self.number), problem)
    }

    /// Whether the line has at least `n` words after its keyword, the first `n` numbers.
    fn floats(&self, n: usize) -> bool {
        self.rest.len() >= n && self.rest[..n].iter().all(|w| w.parse::<f32>().is_ok())
    }
}

/// The vertices, texture coordinates and normals defined so far.
#[derive(Default)]
struct Defined {
    positions: i64,
    texcoords: i64,
    normals: i64,
}

/// A `v` line: x y z, then optionally w (not 0) or r g b.
fn check_vertex(line: &ObjLine) -> Result<()> {
    let rest = &line.rest;
    if !line.floats(3) {
        return Err(line.refuse(
            "a vertex needs three numbers `v x y z` (then optionally w, or r g b); \
             fix the line"
                .into(),
        ));
    }
    match rest.len() {
        3 | 6 => {}
        4 => match rest[3].parse::<f32>() {
            Ok(w) if w != 0.0 => {}
            Ok(_) => {
                return Err(line.refuse("the vertex weight w is 0; use 1 or leave it out".into()));
            }
            Err(_) => {
                return Err(
                    line.refuse(format!("`{}` is not a number (the vertex weight w)", rest[3]))
                );
            }
        },
        n => {
            return Err(line.refuse(format!(
                "a vertex with {n} numbers; give x y z, x y z w, or x y z r g b"
            )));
        }
    }
    Ok(())
}

/// One corner of a face or line: `v`, `v/vt`, `v//vn` or `v/vt/vn`, each index against what is
/// defined before the line.
fn check_corner(line: &ObjLine, corner: &str, defined: &Defined) -> Result<()> {
    let mut parts = corner.split('/');
    for (k, (what, defined)) in [
        ("vertex", defined.positions),
        ("texture coordinate", defined.texcoords),
        ("normal", defined.normals),
    ]
    .into_iter()
    .enumerate()
    {
        let Some(part) = parts.next() else { break };
        if part.is_empty() && k > 0 {
            continue;
        }
        match part.parse::<i64>() {
            Ok(index) if index != 0 && index.abs() <= defined => {}
            Ok(index) => {
                return Err(line.refuse(format!(
                    "{what} index {index} is out of range: {defined} come before \
                     this line (OBJ indices start at 1 and refer to lines above; \
                     negative ones count back from the last)"
                )));
            }
            Err(_) => {
                return Err(line.refuse(format!(
                    "`{corner}` is not a vertex reference like 7, 7/2, 7//5 or 7/2/5"
                )));
            }
        }
    }
    if parts.next().is_some() {
        return Err(
            line.refuse(format!("`{corner}` is not a vertex reference like 7, 7/2, 7//5 or 7/2/5"))
        );
    }
    Ok(())
}

/// An `f` or `l` line: enough corners, not more than `max_polygon_vertices`, each a reference
/// to what is defined before it.
fn check_face(line: &ObjLine, defined: &Defined, max_polygon_vertices: u64) -> Result<()> {
    let rest = &line.rest;
    if line.keyword == "f" && rest.len() < 3 {
        return Err(line.refuse(format!(
            "a face with {} vertices; a polygon needs at least 3 (delete the line or \
             add the missing corners)",
            rest.len()
        )));
    }
    if rest.len() as u64 > max_polygon_vertices {
        return Err(SceneError::Limit {
            path: line.path.to_owned(),
            what: format!("the number of vertices of the polygon on line {}", line.number),
            value: rest.len() as u64,
            limit: max_polygon_vertices,
            fix: "split the polygon into smaller faces, or raise the limit with \
                  --max-polygon-vertices"
                .into(),
        });
    }
    for corner in rest {
        check_corner(line, corner, defined)?;
    }
    Ok(())
}

/// One line by its keyword, counting what it defines.
fn check_line(line: &ObjLine, defined: &mut Defined, max_polygon_vertices: u64) -> Result<()> {
    match line.keyword {
        "v" => {
            check_vertex(line)?;
            defined.positions += 1;
        }
        "vt" => {
            if !line.floats(2) {
                return Err(line.refuse(
                    "a texture coordinate needs two numbers `vt u v`; fix the line".into(),
                ));
            }
            defined.texcoords += 1;
        }
        "vn" => {
            if !line.floats(3) {
                return Err(
                    line.refuse("a normal needs three numbers `vn x y z`; fix the line".into())
                );
            }
            defined.normals += 1;
        }
        "usemtl" if line.line.split_once(' ').is_none_or(|(_, n)| n.trim().is_empty()) => {
            return Err(line.refuse(
                "`usemtl` without a material name after a space; name the material".into(),
            ));
        }
        "f" | "l" => check_face(line, defined, max_polygon_vertices)?,
        _ => {}
    }
    Ok(())
}

/// Find the first line that tobj would refuse (or that would make a polygon beyond
/// `max_polygon_vertices`), for a message with its line number. tobj's own errors carry no
/// position, so every check it makes is made here first, the same way: words split at
/// whitespace, numbers as 32-bit floats, indices against the vertices defined *before* the line.
fn locate_problem(text: &str, path: &Path, max_polygon_vertices: u64) -> Option<SceneError> {
    let mut defined = Defined::default();
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let line = ObjLine { path, number: i + 1, line, keyword, rest: words.collect() };
        if let Err(problem) = check_line(&line, &mut defined, max_polygon_vertices) {
            return Some(problem);
        }
    }
    None
}

/// The text tobj is given: a library line first, so that tobj asks for the made-up library
/// even when the file has none, and vertex colours (`v x y z r g b`) dropped. restauro does not
/// use them, and tobj refuses a file where only some vertices have them ("face vertex color
/// index out of bounds", found by the fuzz harness), which the OBJ format allows. Lines keep
/// their numbers.
fn for_tobj(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 40);
    out.push_str("mtllib restauro-usemtl-names.mtl\n");
    for line in text.split_inclusive('\n') {
        let mut words = line.split_whitespace();
        if words.next() == Some("v") && line.split_whitespace().count() == 7 {
            let xyz: Vec<&str> = words.take(3).collect();
            out.push_str("v ");
            out.push_str(&xyz.join(" "));
            out.push('\n');
        } else {
            out.push_str(line);
        }
    }
    out
}

/// Read an OBJ text. `path` names it in messages.
pub fn parse(text: &str, path: &Path) -> Result<Mesh> {
    parse_limited(text, path, &Limits::default())
}

/// [`parse`] within `limits` (the vertices of one polygon).
pub fn parse_limited(text: &str, path: &Path, limits: &Limits) -> Result<Mesh> {
    // tobj's errors carry no line, and it takes a two-vertex face for a degenerate triangle, so
    // every line it would refuse is found first.
    if let Some(problem) = locate_problem(text, path, limits.max_polygon_vertices) {
        return Err(problem);
    }
    let names = usemtl_names(text);
    // The file's own `mtllib` lines get an empty library.
    let with_library = for_tobj(text);
    let first_library = std::cell::Cell::new(true);
    let loader = |_: &Path| -> tobj::MTLLoadResult {
        if !first_library.replace(false) {
            return Ok((Vec::new(), HashMap::new()));
        }
        let materials: Vec<tobj::Material> = names
            .iter()
            .map(|n| tobj::Material { name: n.clone(), ..Default::default() })
            .collect();
        let map = names.iter().enumerate().map(|(i, n)| (n.clone(), i)).collect();
        Ok((materials, map))
    };
    // One index per corner: a vertex with two normals (a crease) becomes two vertices.
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) = guard::catch(|| {
        tobj::load_obj_buf(&mut with_library.as_bytes(), &options, loader)
    })
    .map_err(|_| SceneError::invalid(path, "OBJ", guard::gave_up("OBJ")))?
    .map_err(|e| {
        SceneError::invalid(
            path,
            "OBJ",
            format!("the OBJ reader refused the file ({e}); check the file against the OBJ format"),
        )
    })?;
    let mut mesh = Mesh::default();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let group_name = match m.material_id {
            Some(id) => names.get(id).cloned().unwrap_or_else(|| format!("material{id}")),
            None if !model.name.is_empty() && model.name != "unnamed_object" => model.name.clone(),
            None => "default".to_owned(),
        };
        let group = mesh.group_index(Group::named(group_name));
        let base = mesh.positions.len() as u32;
        for p in m.positions.chunks_exact(3) {
            mesh.push_position([p[0], p[1], p[2]]);
        }
        let count = m.positions.len() / 3;
        // `vn` normals where the faces give them; a part without them stays flat (zero normals).
        if m.normals.len() == m.positions.len() {
            // tobj reads in 64 bits (its `use_f64`), for survey coordinates.
            let unit = |n: &[f64]| crate::mesh::unit_or_zero([n[0], n[1], n[2]].map(|c| c as f32));
            normals.extend(m.normals.chunks_exact(3).map(unit));
        } else {
            normals.resize(mesh.positions.len(), [0.0; 3]);
        }
        // `vt` where the faces give them, v turned to count from the top (glTF's convention).
        if m.texcoords.len() == 2 * count {
            let uv = m.texcoords.chunks_exact(2).map(|t| [t[0] as f32, (1.0 - t[1]) as f32]);
            texcoords.extend(uv);
        } else {
            texcoords.resize(mesh.positions.len(), [f32::NAN; 2]);
        }
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= count) {
                return Err(SceneError::invalid(
                    path,
                    format!("part {}", model.name),
                    "a face index is out of range; check the file's `f` lines",
                ));
            }
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            mesh.triangle_group.push(group);
        }
    }
    mesh.normals = Some(normals);
    mesh.texcoords = Some(texcoords);
    mesh.drop_flat_normals();
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_parts_by_usemtl_and_group() {
        let text = "# two parts\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng wall\nusemtl travertine\nf 1 2 3 4\nusemtl puddinga\nf 1 3 4\ng floor\nf 1 2 3\n";
        let mesh = parse(text, Path::new("m.obj")).unwrap();
        assert_eq!(mesh.triangles.len(), 4);
        let parts = mesh.triangles_per_group();
        assert_eq!(
            parts.iter().map(|(n, c)| (n.as_str(), *c)).collect::<Vec<_>>(),
            [("puddinga", 2), ("travertine", 2)]
        );
        let b = mesh.bounds().unwrap();
        assert_eq!((b.min, b.max), ([0.0; 3], [1.0, 1.0, 0.0]));
    }

    /// Each corner keeps the normal its `f` line names (a vertex with two becomes two), scaled
    /// to unit length; a part without `vn` stays flat (zero normals), and a file without any
    /// has none.
    #[test]
    fn vertex_normals_are_read_per_corner() {
        let text = "o bent\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 2\nvn 0 3 4\n\
                    f 1//1 2//1 3//2\nf 1//1 3//1 4//1\n\
                    o plain\nv 5 0 0\nv 6 0 0\nv 6 1 0\nf 5 6 7\n";
        let mesh = parse(text, Path::new("n.obj")).unwrap();
        let normals = mesh.normals.as_ref().expect("normals");
        assert_eq!(normals.len(), mesh.positions.len());
        let corners: Vec<([f32; 3], [f32; 3])> = mesh
            .triangles
            .iter()
            .flatten()
            .map(|&i| (mesh.positions[i as usize], normals[i as usize]))
            .collect();
        let (up, bent, none) = ([0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0; 3]);
        assert_eq!(
            corners,
            vec![
                ([0.0, 0.0, 0.0], up),
                ([1.0, 0.0, 0.0], up),
                ([1.0, 1.0, 0.0], bent),
                ([0.0, 0.0, 0.0], up),
                ([1.0, 1.0, 0.0], up),
                ([0.0, 1.0, 0.0], up),
                ([5.0, 0.0, 0.0], none),
                ([6.0, 0.0, 0.0], none),
                ([6.0, 1.0, 0.0], none),
            ]
        );
        let flat = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Path::new("f.obj")).unwrap();
        assert_eq!(flat.normals, None);
    }

    #[test]
    fn a_file_without_materials_is_grouped_by_object() {
        let mesh =
            parse("o block\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Path::new("b.obj")).unwrap();
        assert_eq!(mesh.groups[0].name, "block");
        let mesh = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", Path::new("b.obj")).unwrap();
        assert_eq!(mesh.groups[0].name, "default");
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    /// Found by the fuzz harness: tobj refuses faces on vertices without colours once any vertex
    /// has them; the OBJ format allows it, and restauro does not use the colours.
    #[test]
    fn vertex_colours_on_some_vertices_only_are_read() {
        let text = "v 0 0 0\nv 1 0 0 0.2 0.3 0.4\nv 0 1 0\nf 1 2 3\n";
        let mesh = parse(text, Path::new("c.obj")).unwrap();
        assert_eq!(mesh.positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    }

    #[test]
    fn polygons_and_references_are_checked_as_tobj_counts_them() {
        // Indices refer to the lines above (tobj counts what it has read so far).
        let err = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", Path::new("f.obj")).unwrap_err();
        assert!(
            err.to_string().contains("line 1: vertex index 1 is out of range: 0 come before"),
            "{err}"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/4 2/1 3/1\nvt 0 0\n", Path::new("t.obj"))
            .unwrap_err();
        assert!(
            err.to_string().contains("line 4: texture coordinate index 4 is out of range"),
            "{err}"
        );
        let err = parse("v 0 0\n", Path::new("v.obj")).unwrap_err();
        assert!(err.to_string().contains("line 1: a vertex needs three numbers"), "{err}");
        let limits = Limits { max_polygon_vertices: 3, ..Limits::default() };
        let err = parse_limited(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
            Path::new("p.obj"),
            &limits,
        )
        .unwrap_err();
        assert!(err.to_string().contains("polygon on line 5 is 4, over the limit of 3"), "{err}");
    }

    #[test]
    fn bad_faces_are_refused_with_their_line() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", Path::new("bad.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(
                "bad.obj: line 4: vertex index 9 is out of range: 3 come before this line"
            ),
            "{err}"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nf 1 2\n", Path::new("bad.obj")).unwrap_err().to_string();
        assert!(
            err.contains("line 3: a face with 2 vertices; a polygon needs at least 3"),
            "{err}"
        );
    }
}
