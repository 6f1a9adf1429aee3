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
//! A part that shows detail over its spectrum (its photo, or its scan's vertex colours; see
//! `restauro_render::texture`) carries it here as well, so that the view shows the lichen and
//! the crust where the snapshot will: the base state's photo, at most [`PREVIEW_TEXELS`] on a
//! side, as the primitive's `baseColorTexture`, or the colours as `COLOR_0`; in grey for
//! `detail = "luminance"`. The primitive's `extras.detail_mean` is the linear mean of what it
//! carries, by which the viewer divides the part's colour, so that the view too shows the
//! detail relative to the measured spectrum.
//!
//! A model of more than twice [`vertex_clustering::TARGET_TRIANGLES`] triangles carries a
//! coarser copy for drawing while the view moves: one more node per object, marked
//! `extras.restauro_coarse`, whose primitives index the same vertices (see
//! [`vertex_clustering`]).

use crate::vertex_clustering;
use restauro_scene::load::{LoadedObject, LoadedScene};
use restauro_scene::scene_file::{Detail, Material};
use restauro_scene::texture::{Texture, luminance};
use restauro_spectral::rgb_space::Transfer;
use serde_json::{Value, json};
use std::collections::BTreeMap;

/// The most texels a photo has on a side in the preview: enough for a screen's view of a
/// facade, small enough for the page to load quickly.
pub const PREVIEW_TEXELS: u32 = 1024;

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
    images: Vec<Value>,
}

impl Writer {
    /// Appends `bytes` as a buffer view (4-byte aligned, §3.6.2.4) for vertex data (`target`
    /// 34962), indices (34963) or an image (none); its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut view = json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.views.push(view);
        self.views.len() - 1
    }

    /// Appends a PNG image; its index (which is also its texture's: one texture per image).
    fn image(&mut self, png: &[u8]) -> usize {
        let view = self.view(png, None);
        self.images.push(json!({ "bufferView": view, "mimeType": "image/png" }));
        self.images.len() - 1
    }

    fn vec2s(&mut self, data: &[[f32; 2]]) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34962));
        self.accessor(json!({
            "bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC2"
        }))
    }

    fn accessor(&mut self, value: Value) -> usize {
        self.accessors.push(value);
        self.accessors.len() - 1
    }

    fn vec3s(&mut self, data: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(34962));
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
        let view = self.view(&bytes, Some(34963));
        self.accessor(json!({
            "bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR"
        }))
    }
}

/// The scene as GLB; `colour` gives each scene material's linear-sRGB base colour (0–1).
pub fn scene_glb(scene: &LoadedScene, colour: impl Fn(&str) -> [f32; 3]) -> Preview {
    let names: Vec<&String> = scene.file.materials.keys().collect();
    let mut glb = Glb {
        scene,
        offset: centre(scene),
        materials: base_materials(scene, &names, colour),
        names,
        cell_m: vertex_clustering::cell_size_m(scene, vertex_clustering::TARGET_TRIANGLES),
        w: Writer::default(),
        details: Details::default(),
        meshes: Vec::new(),
        nodes: Vec::new(),
        coarse_nodes: Vec::new(),
        triangles: 0,
        coarse_triangles: 0,
    };
    for o in &scene.objects {
        glb.object(o);
    }
    glb.finish()
}

/// One glTF material per scene material, in the order of `names`: its colour, no metal, its
/// roughness, double-sided.
fn base_materials(
    scene: &LoadedScene,
    names: &[&String],
    colour: impl Fn(&str) -> [f32; 3],
) -> Vec<Value> {
    names
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
        .collect()
}

/// The GLB being written: the binary chunk, and the document's materials, meshes and nodes as
/// the objects are added.
struct Glb<'a> {
    scene: &'a LoadedScene,
    /// World coordinates of the GLB's origin (see the module doc).
    offset: [f64; 3],
    /// The scene's materials, in the order of the first glTF materials.
    names: Vec<&'a String>,
    materials: Vec<Value>,
    /// The cell of the vertex clustering, when the model gets a coarse copy.
    cell_m: Option<f64>,
    w: Writer,
    details: Details,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    coarse_nodes: Vec<Value>,
    triangles: usize,
    coarse_triangles: usize,
}

/// What one object writes once for all its parts: its positions and normals (accessors), its
/// vertices' cluster representatives, and which parts are coloured per vertex.
struct ObjectData {
    position: usize,
    normal: Option<usize>,
    representative: Option<Vec<u32>>,
    coloured: Vec<bool>,
    carried: Carried,
}

impl Glb<'_> {
    /// Adds object `o`: one node and mesh of its visible parts, and one of their coarse copy.
    fn object(&mut self, o: &LoadedObject) {
        let positions: Vec<[f32; 3]> =
            o.mesh.positions.iter().map(|&p| to_gltf(p, self.offset)).collect();
        let w = &mut self.w;
        let position = w.vec3s(&positions, true);
        // glTF normals must be unit vectors: a mesh with flat parts (zero normals) goes
        // without, and the viewer shades it flat, as it does a mesh that has none.
        let normal =
            o.mesh.normals.as_ref().filter(|n| n.iter().all(|v| *v != [0.0; 3])).map(|n| {
                let turned: Vec<[f32; 3]> = n.iter().map(|v| [v[0], v[2], -v[1]]).collect();
                w.vec3s(&turned, false)
            });
        let mut data = ObjectData {
            position,
            normal,
            representative: self
                .cell_m
                .map(|c| vertex_clustering::representatives(&o.mesh.positions, c)),
            coloured: o.mesh.coloured_groups(),
            carried: Carried::default(),
        };
        let (mut primitives, mut coarse) = (Vec::new(), Vec::new());
        // The levels of detail the scene's camera shows, as a render does.
        let shown = o.mesh.levels.shown(&self.scene.viewer());
        for g in 0..o.mesh.groups.len() {
            if o.hidden_groups[g] {
                continue;
            }
            let tris = part_triangles(o, g, shown.as_deref());
            if tris.is_empty() {
                continue;
            }
            let (primitive, coarse_primitive) = self.part(o, g, &tris, &mut data);
            primitives.push(primitive);
            coarse.extend(coarse_primitive);
        }
        self.meshes.push(json!({ "name": o.name, "primitives": primitives }));
        self.nodes.push(json!({ "name": o.name, "mesh": self.meshes.len() - 1 }));
        if !coarse.is_empty() {
            let name = format!("{} (coarse)", o.name);
            self.meshes.push(json!({ "name": name, "primitives": coarse }));
            self.coarse_nodes.push(json!({
                "name": name, "mesh": self.meshes.len() - 1,
                "extras": { "restauro_coarse": true }
            }));
        }
    }

    /// The primitive of part `g` of object `o`, whose triangles are `tris` (vertex indices),
    /// and of its coarse copy when it has one left.
    fn part(
        &mut self,
        o: &LoadedObject,
        g: usize,
        tris: &[u32],
        data: &mut ObjectData,
    ) -> (Value, Option<Value>) {
        let scene = self.scene;
        let group = &o.mesh.groups[g];
        self.triangles += tris.len() / 3;
        let indices = self.w.indices(tris);
        let mut material = self.names.iter().position(|n| **n == o.group_materials[g]);
        let mut attributes = json!({ "POSITION": data.position });
        if let Some(normal) = data.normal {
            attributes["NORMAL"] = json!(normal);
        }
        let mut extras =
            json!({ "object": o.name, "part": group.name, "material": o.group_materials[g] });
        let m = &scene.file.materials[&o.group_materials[g]];
        let part = Part { scene, object: &o.name, material: m, group, coloured: data.coloured[g] };
        let ours = (&mut self.w, &mut self.materials, &mut self.details, &mut data.carried);
        if let Some(mean) = part.carry(ours, &o.mesh, tris, &mut attributes, &mut material) {
            extras["detail_mean"] = json!(mean);
        }
        let coarse = data.representative.as_ref().and_then(|r| {
            let fewer = vertex_clustering::coarse_indices(tris, r);
            if fewer.is_empty() {
                return None;
            }
            self.coarse_triangles += fewer.len() / 3;
            let indices = self.w.indices(&fewer);
            Some(json!({
                "attributes": attributes.clone(), "indices": indices, "material": material,
                "extras": extras.clone()
            }))
        });
        let primitive = json!({
            "attributes": attributes, "indices": indices, "material": material, "extras": extras
        });
        (primitive, coarse)
    }

    /// The document around what was written, and the GLB of both.
    fn finish(self) -> Preview {
        let Glb { offset, mut nodes, coarse_nodes, meshes, materials, mut w, .. } = self;
        let (triangles, coarse_triangles) = (self.triangles, self.coarse_triangles);
        nodes.extend(coarse_nodes);
        while !w.bin.len().is_multiple_of(4) {
            w.bin.push(0);
        }
        let mut document = json!({
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
        // glTF's arrays, when present, hold at least one item (§5: `minItems` 1).
        if !w.images.is_empty() {
            let textures: Vec<Value> =
                (0..w.images.len()).map(|i| json!({ "source": i })).collect();
            document["textures"] = json!(textures);
            document["images"] = json!(w.images);
        }
        Preview { glb: glb(&document, &w.bin), offset_m: offset, triangles, coarse_triangles }
    }
}

/// The vertex indices of the triangles of part `g` of `o` that the levels of detail show
/// (`shown`, per triangle; `None`: all).
fn part_triangles(o: &LoadedObject, g: usize, shown: Option<&[bool]>) -> Vec<u32> {
    o.mesh
        .triangles
        .iter()
        .zip(&o.mesh.triangle_group)
        .enumerate()
        .filter(|(k, (_, tg))| **tg as usize == g && shown.is_none_or(|s| s[*k]))
        .flat_map(|(_, (t, _))| *t)
        .collect()
}

/// The photos written so far, each once per key and grey or not: its texture and linear
/// mean; and the materials made for parts with a photo, by scene material and texture.
#[derive(Default)]
struct Details {
    photos: BTreeMap<(String, bool), (usize, [f32; 3])>,
    materials: BTreeMap<(usize, usize), usize>,
}

/// What one object has written once for its parts: texture coordinates, and its vertex
/// colours in colour and in grey.
#[derive(Default)]
struct Carried {
    texcoords: Option<usize>,
    colours: [Option<usize>; 2],
}

/// A part of an object, and what it shows over its spectrum.
struct Part<'a> {
    scene: &'a LoadedScene,
    object: &'a str,
    material: &'a Material,
    group: &'a restauro_scene::mesh::Group,
    /// Whether every vertex of the part has a colour.
    coloured: bool,
}

impl Part<'_> {
    /// Writes what the part shows over its spectrum (its base state's photo, else its vertex
    /// colours) into its primitive's `attributes` and `material`; the linear mean of it, by
    /// which the viewer divides the part's colour. `tris`: the part's vertex indices.
    fn carry(
        &self,
        (w, materials, details, carried): (
            &mut Writer,
            &mut Vec<Value>,
            &mut Details,
            &mut Carried,
        ),
        mesh: &restauro_scene::mesh::Mesh,
        tris: &[u32],
        attributes: &mut Value,
        material: &mut Option<usize>,
    ) -> Option<[f32; 3]> {
        let m = self.material;
        let grey = match m.detail.unwrap_or_default() {
            Detail::None => return None,
            Detail::Luminance => true,
            Detail::Chromatic => false,
        };
        let photo = match &m.texture {
            Some(reference) => Some((reference.clone(), self.scene.textures.get(reference)?)),
            None => self
                .group
                .photo
                .as_ref()
                .map(|p| (format!("{}#{}", self.object, self.group.name), p)),
        };
        if let Some((key, texture)) = photo {
            let (image, mean) = *details.photos.entry((key, grey)).or_insert_with(|| {
                let balanced = m.white_patch.map(|p| texture.white_balanced(p));
                let (png, mean) = preview_png(balanced.as_ref().unwrap_or(texture), grey);
                (w.image(&png), mean)
            });
            let uv = mesh.texcoords.as_ref()?;
            let texcoords = *carried.texcoords.get_or_insert_with(|| {
                w.vec2s(
                    &uv.iter()
                        .map(|t| t.map(|c| if c.is_finite() { c } else { 0.0 }))
                        .collect::<Vec<_>>(),
                )
            });
            attributes["TEXCOORD_0"] = json!(texcoords);
            let base = (*material)?;
            let made = *details.materials.entry((base, image)).or_insert_with(|| {
                let mut textured = materials[base].clone();
                textured["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": image });
                materials.push(textured);
                materials.len() - 1
            });
            *material = Some(made);
            return Some(mean);
        }
        let colours = mesh.colours.as_ref().filter(|_| self.coloured)?;
        let shade = |c: [f32; 3]| if grey { [luminance(c); 3] } else { c };
        let accessor = *carried.colours[usize::from(grey)].get_or_insert_with(|| {
            let finite = |c: &[f32; 3]| if c[0].is_finite() { shade(*c) } else { [0.0; 3] };
            w.vec3s(&colours.iter().map(finite).collect::<Vec<_>>(), false)
        });
        attributes["COLOR_0"] = json!(accessor);
        let mut sum = [0.0f64; 3];
        for &i in tris {
            let c = shade(colours[i as usize]);
            (0..3).for_each(|k| sum[k] += f64::from(c[k]));
        }
        Some(sum.map(|c| (c / tris.len() as f64) as f32))
    }
}

/// A photo as the preview's PNG (8-bit sRGB): box-filtered to at most [`PREVIEW_TEXELS`] on a
/// side, in grey (its luminance) when `grey`; and its linear mean.
fn preview_png(texture: &Texture, grey: bool) -> (Vec<u8>, [f32; 3]) {
    // sRGB decoding by table: a big photo has tens of millions of texels.
    let decode: Vec<f32> =
        (0..=u16::MAX).map(|c| Transfer::Srgb.decode(f64::from(c) / 65535.0) as f32).collect();
    let k = texture.width.max(texture.height).div_ceil(PREVIEW_TEXELS).max(1);
    let (width, height) = (texture.width.div_ceil(k), texture.height.div_ceil(k));
    let mut linear = Vec::with_capacity(width as usize * height as usize);
    for row in 0..height {
        for col in 0..width {
            let (mut sum, mut n) = ([0.0f32; 3], 0.0f32);
            for y in row * k..((row + 1) * k).min(texture.height) {
                for x in col * k..((col + 1) * k).min(texture.width) {
                    let t = texture.texels[(y * texture.width + x) as usize];
                    (0..3).for_each(|c| sum[c] += decode[usize::from(t[c])]);
                    n += 1.0;
                }
            }
            let c = sum.map(|v| v / n);
            linear.push(if grey { [luminance(c); 3] } else { c });
        }
    }
    let mut mean = [0.0f64; 3];
    linear.iter().for_each(|c| (0..3).for_each(|k| mean[k] += f64::from(c[k])));
    let mean = mean.map(|v| (v / linear.len() as f64) as f32);
    let bytes: Vec<u8> = linear
        .iter()
        .flatten()
        .map(|&v| (Transfer::Srgb.encode(f64::from(v)) * 255.0).round().clamp(0.0, 255.0) as u8)
        .collect();
    let mut png = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // Writing to memory cannot fail but for sizes the image's own checks keep out.
        if let Ok(mut writer) = encoder.write_header() {
            let _ = writer.write_image_data(&bytes);
        }
    }
    (png, mean)
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
