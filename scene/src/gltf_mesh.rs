//! glTF 2.0 meshes (`.glb`, or `.gltf` with its buffers embedded as base64 `data:` URIs), read
//! with the gltf crate: the triangles of every mesh instance in the default scene, with each
//! node's transform applied down the hierarchy (glTF 2.0 §5.25, column-major matrices). Parts
//! are named by the primitive's material name (or `material<index>`, or `default`).
//!
//! Buffers in separate files are refused rather than looked up: a scene's assets must each be
//! one self-contained file so that an asset bundle carries them by hash. glTF is Y-up; the
//! scene loader turns it Z-up.

use crate::error::{Result, SceneError};
use crate::mesh::{Group, Mesh};
use base64::Engine;
use glam::{Mat4, Vec3};
use gltf::mesh::Mode;
use std::path::Path;

fn buffers(doc: &gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>> {
    doc.buffers()
        .map(|b| match b.source() {
            gltf::buffer::Source::Bin => doc.blob.clone().ok_or_else(|| {
                SceneError::invalid(
                    path,
                    format!("buffer {}", b.index()),
                    "refers to a GLB binary chunk the file does not have",
                )
            }),
            gltf::buffer::Source::Uri(uri) => {
                let data = uri
                    .strip_prefix("data:")
                    .and_then(|rest| rest.split_once(";base64,"))
                    .map(|(_, d)| d);
                match data {
                    Some(d) => base64::engine::general_purpose::STANDARD.decode(d).map_err(|e| {
                        SceneError::invalid(
                            path,
                            format!("buffer {}", b.index()),
                            format!("bad base64 data: {e}"),
                        )
                    }),
                    None => Err(SceneError::invalid(
                        path,
                        format!("buffer {}", b.index()),
                        format!(
                            "refers to the separate file `{uri}`; save the model as .glb (or \
                             with embedded buffers) so that it is one file"
                        ),
                    )),
                }
            }
        })
        .collect()
}

fn add_node(
    node: gltf::Node,
    parent: Mat4,
    buffers: &[Vec<u8>],
    mesh: &mut Mesh,
    path: &Path,
    depth: usize,
) -> Result<()> {
    if depth > 256 {
        return Err(SceneError::invalid(path, "node hierarchy", "nested more than 256 deep"));
    }
    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
    let world = parent * local;
    if let Some(m) = node.mesh() {
        for (p, prim) in m.primitives().enumerate() {
            let place = || {
                format!(
                    "mesh {} primitive {p}",
                    m.name().map_or(m.index().to_string(), str::to_owned)
                )
            };
            if prim.mode() != Mode::Triangles {
                return Err(SceneError::invalid(
                    path,
                    place(),
                    format!(
                        "primitive mode {:?}; only triangle lists are read (re-export with triangles)",
                        prim.mode()
                    ),
                ));
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| SceneError::invalid(path, place(), "no POSITION attribute"))?
                .map(|p| world.transform_point3(Vec3::from(p)).to_array())
                .collect();
            let count = positions.len() as u32;
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..count).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(SceneError::invalid(
                    path,
                    place(),
                    "the index count is not a multiple of 3",
                ));
            }
            if let Some(bad) = indices.iter().find(|&&i| i >= count) {
                return Err(SceneError::invalid(
                    path,
                    place(),
                    format!(
                        "vertex index {bad} is out of range: the primitive has {count} vertices"
                    ),
                ));
            }
            let material = prim.material();
            let name = match (material.name(), material.index()) {
                (Some(n), _) => n.to_owned(),
                (None, Some(i)) => format!("material{i}"),
                (None, None) => "default".to_owned(),
            };
            let [r, g, b, _] = material.pbr_metallic_roughness().base_color_factor();
            let group = mesh.group_index(Group {
                name,
                colour: Some([r, g, b]),
                double_sided: material.double_sided(),
            });
            // A mirroring transform (negative determinant) turns the winding around.
            let flip = world.determinant() < 0.0;
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(positions);
            for t in indices.chunks_exact(3) {
                let tri = if flip { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };
                mesh.triangles.push(tri.map(|i| base + i));
                mesh.triangle_group.push(group);
            }
        }
    }
    for child in node.children() {
        add_node(child, world, buffers, mesh, path, depth + 1)?;
    }
    Ok(())
}

/// Read glTF bytes (JSON or GLB). `path` names the file in messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let doc = gltf::Gltf::from_slice(bytes).map_err(|e| {
        SceneError::invalid(path, "glTF", format!("{e}; the file is not valid glTF 2.0"))
    })?;
    let buffers = buffers(&doc, path)?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::invalid(path, "scenes", "the file has no scene"))?;
    let mut mesh = Mesh::default();
    for node in scene.nodes() {
        add_node(node, Mat4::IDENTITY, &buffers, &mut mesh, path, 0)?;
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A glTF with one triangle mesh used by two nodes, one of them translated and scaled
    /// under a rotated parent.
    fn two_instances() -> String {
        let mut bin = Vec::new();
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for i in [0u16, 1, 2] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let data = base64::engine::general_purpose::STANDARD.encode(&bin);
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
            "nodes":[{{"mesh":0}},{{"rotation":[0,0,0.7071068,0.7071068],"children":[2]}},
                     {{"mesh":0,"translation":[10,0,0],"scale":[2,2,2]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
            "materials":[{{"name":"marble","doubleSided":true,"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.8,0.7,1]}}}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
            "buffers":[{{"byteLength":42,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#
        )
    }

    #[test]
    fn reads_instances_with_their_transforms() {
        let mesh = parse(two_instances().as_bytes(), Path::new("t.gltf")).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(
            mesh.groups,
            vec![Group {
                name: "marble".into(),
                colour: Some([0.9, 0.8, 0.7]),
                double_sided: true
            }]
        );
        // The second instance: scaled by 2, moved to x = 10, then turned 90° about +Z, so its
        // corners are (0, 10, 0), (0, 12, 0), (−2, 10, 0).
        let p: Vec<[f32; 3]> = mesh.positions[3..].to_vec();
        let expect = [[0.0, 10.0, 0.0], [0.0, 12.0, 0.0], [-2.0, 10.0, 0.0]];
        for (a, b) in p.iter().zip(expect) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-5, "{p:?}");
            }
        }
    }

    #[test]
    fn external_buffers_and_bad_indices_are_refused() {
        let ext =
            two_instances().replacen("data:application/octet-stream;base64,", "meshes.bin#", 1);
        let err = parse(ext.as_bytes(), Path::new("e.gltf")).unwrap_err().to_string();
        assert!(err.contains("refers to the separate file"), "{err}");
        assert!(err.contains("save the model as .glb"), "{err}");
        let err = parse(b"{not json", Path::new("j.gltf")).unwrap_err().to_string();
        assert!(err.starts_with("j.gltf: glTF: "), "{err}");
    }
}
