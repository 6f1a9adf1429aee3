//! Stanford PLY meshes, ASCII and binary, read with ply-rs: the `vertex` element's x, y, z and
//! the `face` element's `vertex_indices` (or `vertex_index`) lists. Polygons are split into
//! fans. PLY has no materials, so the whole mesh is one part, named after the file.

use crate::error::{Result, SceneError};
use crate::guard;
use crate::load::Limits;
use crate::mesh::{Group, Mesh, unit_or_zero};
use crate::ply_layout;
use ply_rs::parser::Parser;
use ply_rs::ply::{DefaultElement, Property};
use std::path::Path;

fn number(p: &Property) -> Option<f64> {
    Some(match p {
        Property::Char(v) => f64::from(*v),
        Property::UChar(v) => f64::from(*v),
        Property::Short(v) => f64::from(*v),
        Property::UShort(v) => f64::from(*v),
        Property::Int(v) => f64::from(*v),
        Property::UInt(v) => f64::from(*v),
        Property::Float(v) => f64::from(*v),
        Property::Double(v) => *v,
        _ => return None,
    })
}

fn list(p: &Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUChar(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUShort(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        Property::ListUInt(v) => v.iter().map(|&x| i64::from(x)).collect(),
        _ => return None,
    })
}

/// Read PLY bytes. `path` names the file in messages and, by its stem, the mesh's one part.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh> {
    parse_limited(bytes, path, &Limits::default())
}

/// [`parse`] within `limits` (faces, vertices of one polygon).
pub fn parse_limited(bytes: &[u8], path: &Path, limits: &Limits) -> Result<Mesh> {
    // Everything ply-rs would refuse, panic on or loop over is refused first, in words.
    let header = ply_layout::read_header(bytes, path)?;
    ply_layout::check_body(&header, bytes, path, limits)?;
    let parser = Parser::<DefaultElement>::new();
    let mut reader = bytes;
    let ply = guard::catch(move || parser.read_ply(&mut reader))
        .map_err(|_| SceneError::invalid(path, "PLY", guard::gave_up("PLY")))?
        .map_err(|e| {
            // Not expected after the checks above; its first line only (the rest is a dump of
            // ply-rs's parser state).
            let first = e.to_string().lines().next().unwrap_or("").to_owned();
            SceneError::invalid(
                path,
                "PLY",
                format!(
                    "the PLY reader refused the file ({first}); check it with another PLY tool"
                ),
            )
        })?;
    let vertices = ply.payload.get("vertex").ok_or_else(|| {
        SceneError::invalid(
            path,
            "header",
            "no `vertex` element; a PLY mesh needs vertices with x, y, z",
        )
    })?;
    let faces = ply.payload.get("face").ok_or_else(|| {
        SceneError::invalid(
            path,
            "header",
            "no `face` element; restauro needs faces, not a point cloud",
        )
    })?;
    let mut mesh = Mesh::default();
    let mut normals = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        let coord = |k: &str| -> Result<f32> {
            v.get(k).and_then(number).map(|x| x as f32).ok_or_else(|| {
                SceneError::invalid(
                    path,
                    format!("vertex {i}"),
                    format!("no numeric `{k}` property"),
                )
            })
        };
        mesh.positions.push([coord("x")?, coord("y")?, coord("z")?]);
        // nx, ny, nz (the names scanners write, as the Stanford format's examples do).
        let normal = ["nx", "ny", "nz"].map(|k| v.get(k).and_then(number).map(|x| x as f32));
        normals.push(match normal {
            [Some(x), Some(y), Some(z)] => unit_or_zero([x, y, z]),
            _ => [0.0; 3],
        });
    }
    mesh.normals = Some(normals);
    mesh.drop_flat_normals();
    // One part, named as an OBJ's part without groups: not after the file, whose name a
    // bundle replaces by its hash.
    let group = mesh.group_index(Group::named("default"));
    let n = mesh.positions.len() as i64;
    for (i, f) in faces.iter().enumerate() {
        let indices =
            f.get("vertex_indices").or_else(|| f.get("vertex_index")).and_then(list).ok_or_else(
                || SceneError::invalid(path, format!("face {i}"), "no `vertex_indices` list"),
            )?;
        if indices.len() < 3 {
            return Err(SceneError::invalid(
                path,
                format!("face {i}"),
                format!("a polygon with {} vertices; it needs at least 3", indices.len()),
            ));
        }
        if let Some(bad) = indices.iter().find(|&&k| !(0..n).contains(&k)) {
            return Err(SceneError::invalid(
                path,
                format!("face {i}"),
                format!(
                    "vertex index {bad} is out of range: the file has {n} vertices (0 to {})",
                    n - 1
                ),
            ));
        }
        for k in 1..indices.len() - 1 {
            mesh.triangles.push([indices[0] as u32, indices[k] as u32, indices[k + 1] as u32]);
            mesh.triangle_group.push(group);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n2 0 0\n2 3 0\n0 3 1\n4 0 1 2 3\n";

    fn binary() -> Vec<u8> {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 5.0]] {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        b
    }

    #[test]
    fn reads_ascii_and_binary() {
        let mesh = parse(ASCII.as_bytes(), Path::new("scan.ply")).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.groups[0].name, "default");
        assert_eq!(mesh.bounds().unwrap().max, [2.0, 3.0, 1.0]);
        let mesh = parse(&binary(), Path::new("b.ply")).unwrap();
        assert_eq!(mesh.triangles.len(), 1);
        assert_eq!(mesh.bounds().unwrap().max, [1.0, 1.0, 5.0]);
    }

    /// A scanner's `nx ny nz` become the vertices' shading normals, scaled to unit length; a
    /// file without them has none.
    #[test]
    fn vertex_normals_are_read() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                    element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0 0 0 2\n1 0 0 0 3 4\n0 1 0 0 0 0\n3 0 1 2\n";
        let mesh = parse(text.as_bytes(), Path::new("n.ply")).unwrap();
        assert_eq!(mesh.normals, Some(vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0; 3]]));
        assert_eq!(parse(ASCII.as_bytes(), Path::new("scan.ply")).unwrap().normals, None);
    }

    #[test]
    fn truncated_and_bad_files_are_refused() {
        let full = binary();
        for cut in [full.len() - 1, full.len() - 5, full.len() - 20, 40] {
            let err = parse(&full[..cut], Path::new("cut.ply")).unwrap_err().to_string();
            assert!(err.starts_with("cut.ply:"), "{err}");
            assert!(err.contains("truncated"), "{err}");
        }
        let err = parse(ASCII.replace("4 0 1 2 3", "4 0 1 2 7").as_bytes(), Path::new("i.ply"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("face 0: vertex index 7 is out of range: the file has 4 vertices"),
            "{err}"
        );
        let err = parse(ASCII.replace("4 0 1 2 3", "2 0 1").as_bytes(), Path::new("p.ply"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("a polygon with 2 vertices"), "{err}");
    }
}
