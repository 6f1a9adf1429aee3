//! A loaded scene's geometry as glTF 2.0 binary (GLB, Khronos glTF 2.0 §4.4), for the studio's
//! real-time view: one node per object, one primitive per visible part (level-of-detail
//! replacements applied), one material per scene material with the colour the caller computes
//! from its spectrum.
//!
//! Coordinates are re-centred: a survey's coordinates (easting and northing in the hundreds of
//! thousands of metres) would lose their centimetres in the 32-bit floats a GPU draws with, so
//! the centre of the scene's bounds is subtracted and kept, as `offset_m`, in the file's
//! `asset.extras.restauro` and in [`Preview`]. glTF is Y-up (§3.4): world (x, y, z), Z up, is
//! written (x, z, −y).
//!
//! A model of more than twice [`vertex_clustering::TARGET_TRIANGLES`] triangles carries a
//! coarser copy for drawing while the view moves: one more node per object, marked
//! `extras.restauro_coarse`, whose primitives index the same vertices (see
//! [`vertex_clustering`]).

use crate::load::LoadedScene;
use crate::vertex_clustering;
use serde_json::{Value, json};

/// The GLB and what the page needs to place it.
pub struct Preview {
    pub glb: Vec<u8>,
    /// World coordinates (Z up, metres) of the GLB's origin.
    pub offset_m: [f64; 3],
    pub triangles: usize,
    /// The triangles of the coarse copy drawn while moving (0: none, the model is drawn whole).
    pub coarse_triangles: usize,
}

/// World (Z up) to glTF (Y up), relative to `offset`.
fn to_gltf(p: [f32; 3], offset: [f64; 3]) -> [f32; 3] {
    let [x, y, z] = std::array::from_fn(|k| f64::from(p[k]) - offset[k]);
    [x as f32, z as f32, -y as f32]
}

/// The centre of the bounds of every visible triangle's vertices.
fn centre(scene: &LoadedScene) -> [f64; 3] {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for o in &scene.objects {
        for (t, g) in o.mesh.triangles.iter().zip(&o.mesh.triangle_group) {
            if o.hidden_groups[*g as usize] {
                continue;
            }
            for &i in t {
                let p = o.mesh.positions[i as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(f64::from(p[k]));
                    hi[k] = hi[k].max(f64::from(p[k]));
                }
            }
        }
    }
    if lo[0] > hi[0] {
        return [0.0; 3];
    }
    std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]))
}

/// The binary chunk and the accessors and buffer views that describe it.
#[derive(Default)]
struct Writer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Writer {
    /// Appends `bytes` as a buffer view (4-byte aligned, §3.6.2.4); its index.
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target
        }));
        self.views.len() - 1
    }

    fn accessor(&mut self, value: Value) -> usize {
        self.accessors.push(value);
        self.accessors.len() - 1
    }

    fn vec3s(&mut self, data: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let mut a = json!({
            "bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC3"
        });
        if with_bounds {
            let min: Vec<f32> =
                (0..3).map(|k| data.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min)).collect();
            let max: Vec<f32> = (0..3)
                .map(|k| data.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max))
                .collect();
            a["min"] = json!(min);
            a["max"] = json!(max);
        }
        self.accessor(a)
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessor(json!({
            "bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR"
        }))
    }
}

/// The scene as GLB; `colour` gives each scene material's linear-sRGB base colour (0–1).
pub fn scene_glb(scene: &LoadedScene, colour: impl Fn(&str) -> [f32; 3]) -> Preview {
    let offset = centre(scene);
    let names: Vec<&String> = scene.file.materials.keys().collect();
    let materials: Vec<Value> = names
        .iter()
        .map(|name| {
            let m = &scene.file.materials[*name];
            let [r, g, b] = colour(name);
            json!({
                "name": name,
                "doubleSided": true,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [r, g, b, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": m.roughness.map_or(1.0, |r| r.clamp(0.0, 1.0)),
                }
            })
        })
        .collect();
    let mut w = Writer::default();
    let (mut meshes, mut nodes, mut triangles) = (Vec::new(), Vec::new(), 0);
    let cell_m = vertex_clustering::cell_size_m(scene, vertex_clustering::TARGET_TRIANGLES);
    let (mut coarse_nodes, mut coarse_triangles) = (Vec::new(), 0);
    for o in &scene.objects {
        let positions: Vec<[f32; 3]> =
            o.mesh.positions.iter().map(|&p| to_gltf(p, offset)).collect();
        let position = w.vec3s(&positions, true);
        // glTF normals must be unit vectors: a mesh with flat parts (zero normals) goes
        // without, and the viewer shades it flat, as it does a mesh that has none.
        let normal =
            o.mesh.normals.as_ref().filter(|n| n.iter().all(|v| *v != [0.0; 3])).map(|n| {
                let turned: Vec<[f32; 3]> = n.iter().map(|v| [v[0], v[2], -v[1]]).collect();
                w.vec3s(&turned, false)
            });
        let representative =
            cell_m.map(|c| vertex_clustering::representatives(&o.mesh.positions, c));
        let (mut primitives, mut coarse) = (Vec::new(), Vec::new());
        // The levels of detail the scene's camera shows, as a render does.
        let shown = o.mesh.levels.shown(&scene.viewer());
        for (g, group) in o.mesh.groups.iter().enumerate() {
            if o.hidden_groups[g] {
                continue;
            }
            let tris: Vec<u32> = o
                .mesh
                .triangles
                .iter()
                .zip(&o.mesh.triangle_group)
                .enumerate()
                .filter(|(k, (_, tg))| **tg as usize == g && shown.as_ref().is_none_or(|s| s[*k]))
                .flat_map(|(_, (t, _))| *t)
                .collect();
            if tris.is_empty() {
                continue;
            }
            triangles += tris.len() / 3;
            let indices = w.indices(&tris);
            let material = names.iter().position(|n| **n == o.group_materials[g]);
            let mut attributes = json!({ "POSITION": position });
            if let Some(normal) = normal {
                attributes["NORMAL"] = json!(normal);
            }
            let extras =
                json!({ "object": o.name, "part": group.name, "material": o.group_materials[g] });
            if let Some(r) = &representative {
                let fewer = vertex_clustering::coarse_indices(&tris, r);
                if !fewer.is_empty() {
                    coarse_triangles += fewer.len() / 3;
                    let indices = w.indices(&fewer);
                    coarse.push(json!({
                        "attributes": attributes.clone(), "indices": indices, "material": material,
                        "extras": extras.clone()
                    }));
                }
            }
            primitives.push(json!({
                "attributes": attributes, "indices": indices, "material": material,
                "extras": extras
            }));
        }
        meshes.push(json!({ "name": o.name, "primitives": primitives }));
        nodes.push(json!({ "name": o.name, "mesh": meshes.len() - 1 }));
        if !coarse.is_empty() {
            meshes.push(json!({ "name": format!("{} (coarse)", o.name), "primitives": coarse }));
            coarse_nodes.push(json!({
                "name": format!("{} (coarse)", o.name), "mesh": meshes.len() - 1,
                "extras": { "restauro_coarse": true }
            }));
        }
    }
    nodes.extend(coarse_nodes);
    while !w.bin.len().is_multiple_of(4) {
        w.bin.push(0);
    }
    let document = json!({
        "asset": {
            "version": "2.0",
            "generator": concat!("restauro ", env!("CARGO_PKG_VERSION")),
            "extras": { "restauro": { "offset_m": offset, "world": "x east, y north, z up" } }
        },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": w.accessors,
        "bufferViews": w.views,
        "buffers": [{ "byteLength": w.bin.len() }],
    });
    Preview { glb: glb(&document, &w.bin), offset_m: offset, triangles, coarse_triangles }
}

/// The GLB container (§4.4): a 12-byte header, the JSON chunk padded with spaces, the binary
/// chunk padded with zeros.
fn glb(document: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = document.to_string().into_bytes();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}
