//! Wavefront OBJ meshes, read with tobj. Parts are named by their `usemtl` material name, or
//! else by their `o`/`g` name, so that a scene can bind each to a spectral material.
//!
//! tobj drops `usemtl` names unless a `.mtl` library loads, and a scene's spectra replace the
//! library's colours anyway; so the reader hands tobj a library made up here with one entry per
//! `usemtl` name in the file, and never opens `.mtl` files (an asset bundle then needs only the
//! `.obj`). Faces are checked before tobj reads them, so that a refusal names its line (tobj's
//! errors carry no position, and it takes a two-vertex face for a degenerate triangle).

use crate::error::{Result, SceneError};
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

/// Find the first face line that tobj would refuse, for a message with a line number.
fn locate_face_problem(text: &str, path: &Path) -> Option<SceneError> {
    let vertices = text.lines().filter(|l| l.trim_start().starts_with("v ")).count() as i64;
    for (i, line) in text.lines().enumerate() {
        let Some(rest) = line.trim_start().strip_prefix("f ") else { continue };
        let corners: Vec<&str> = rest.split_whitespace().collect();
        let place = format!("line {}", i + 1);
        if corners.len() < 3 {
            return Some(SceneError::invalid(
                path,
                place,
                format!(
                    "a face with {} vertices; a polygon needs at least 3 (delete the line or add \
                     the missing corners)",
                    corners.len()
                ),
            ));
        }
        for c in corners {
            let index = c.split('/').next().and_then(|v| v.parse::<i64>().ok());
            match index {
                Some(k) if k != 0 && k.abs() <= vertices => {}
                Some(k) => {
                    return Some(SceneError::invalid(
                        path,
                        place,
                        format!(
                            "vertex index {k} is out of range: the file has {vertices} vertices \
                             (OBJ indices start at 1; negative ones count back from the last)"
                        ),
                    ));
                }
                None => {
                    return Some(SceneError::invalid(
                        path,
                        place,
                        format!("`{c}` is not a vertex reference like 7, 7/2 or 7/2/5"),
                    ));
                }
            }
        }
    }
    None
}

/// Read an OBJ text. `path` names it in messages.
pub fn parse(text: &str, path: &Path) -> Result<Mesh> {
    // tobj accepts two-vertex faces (as degenerate triangles), so faces are checked first.
    if let Some(problem) = locate_face_problem(text, path) {
        return Err(problem);
    }
    let names = usemtl_names(text);
    // A library line first, so that tobj asks for the made-up library even when the file has
    // none; a file's own `mtllib` lines get an empty library.
    let with_library = format!("mtllib restauro-usemtl-names.mtl\n{text}");
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
    let options =
        tobj::LoadOptions { triangulate: true, single_index: false, ..Default::default() };
    let (models, _) =
        tobj::load_obj_buf(&mut with_library.as_bytes(), &options, loader).map_err(|e| {
            locate_face_problem(text, path).unwrap_or_else(|| {
                SceneError::invalid(
                    path,
                    "OBJ",
                    format!("{e}; check the file against the OBJ format"),
                )
            })
        })?;
    let mut mesh = Mesh::default();
    for model in &models {
        let m = &model.mesh;
        let group_name = match m.material_id {
            Some(id) => names.get(id).cloned().unwrap_or_else(|| format!("material{id}")),
            None if !model.name.is_empty() && model.name != "unnamed_object" => model.name.clone(),
            None => "default".to_owned(),
        };
        let group = mesh.group_index(Group::named(group_name));
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        let count = m.positions.len() / 3;
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= count) {
                return Err(locate_face_problem(text, path).unwrap_or_else(|| {
                    SceneError::invalid(
                        path,
                        format!("part {}", model.name),
                        "a face index is out of range",
                    )
                }));
            }
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
            mesh.triangle_group.push(group);
        }
    }
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

    #[test]
    fn a_file_without_materials_is_grouped_by_object() {
        let mesh =
            parse("o block\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Path::new("b.obj")).unwrap();
        assert_eq!(mesh.groups[0].name, "block");
        let mesh = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", Path::new("b.obj")).unwrap();
        assert_eq!(mesh.groups[0].name, "default");
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn bad_faces_are_refused_with_their_line() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", Path::new("bad.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(
                "bad.obj: line 4: vertex index 9 is out of range: the file has 3 vertices"
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
