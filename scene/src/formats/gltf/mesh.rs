//! glTF 2.0 meshes (`.glb`, or `.gltf` with its buffers embedded as base64 `data:` URIs or in
//! separate files beside it), read with the gltf crate: the triangles of every mesh instance in
//! the default scene, with each node's transform applied down the hierarchy (glTF 2.0 §5.25,
//! column-major matrices). Parts are named by the primitive's material name (or
//! `material<index>`, or `default`).
//!
//! A `.gltf`'s separate buffers (`model.bin`, by a relative URI, percent-decoded as glTF 2.0
//! §3.3 has it) are read from the scene's folder, never outside it. A bundle carries each file
//! by its hash, so when a scene is bundled its `.gltf` gets its buffers embedded
//! ([`embed_buffers`]): one self-contained file, the same triangles. glTF is Y-up; the scene
//! loader turns it Z-up.

use crate::error::{Result, SceneError};
use crate::formats::vrml::Viewpoint;
use crate::guard;
use crate::limits::Limits;
use crate::mesh::{Group, Mesh, unit_or_zero};
use base64::Engine;
use glam::{DMat3, DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::path::Path;

/// Reads a file that a glTF names by a relative URI (already percent-decoded), from the
/// scene's folder.
pub type External<'a> = &'a dyn Fn(&str) -> Result<Vec<u8>>;

/// The path a glTF's buffer URI names, relative to the glTF's own folder: a relative URI,
/// percent-decoded; anything else (a scheme, an absolute path) is refused.
pub(crate) fn external_path(uri: &str, path: &Path, index: usize) -> Result<String> {
    let decoded = percent_encoding::percent_decode_str(uri).decode_utf8_lossy().into_owned();
    if decoded.contains("://") || decoded.starts_with('/') || decoded.contains(':') {
        return Err(SceneError::invalid(
            path,
            format!("buffer {index}"),
            format!(
                "refers to `{uri}`, which is not a file beside the model; keep the buffer in \
                 the scene's folder and refer to it by a relative path"
            ),
        ));
    }
    Ok(decoded)
}

fn buffers(doc: &gltf::Gltf, path: &Path, external: External<'_>) -> Result<Vec<Vec<u8>>> {
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
                    None if doc.blob.is_some() => Err(SceneError::invalid(
                        path,
                        format!("buffer {}", b.index()),
                        format!(
                            "refers to the separate file `{uri}`; a .glb keeps its buffers in \
                             its binary chunk: export it again, or as .gltf with its .bin"
                        ),
                    )),
                    None => external(&external_path(uri, path, b.index())?),
                }
            }
        })
        .collect()
}

/// Check an accessor before the gltf crate reads it: the gltf crate (1.4) trusts the file
/// here — an index accessor of floats reaches an `unreachable!()`, a byte stride shorter than an
/// element fails an assertion, and a count of 0 underflows. So: the component type and shape
/// must be one of `allowed`, the values must lie in a buffer view that lies in its buffer, with
/// a stride that holds an element. `Ok(false)` for an accessor of no elements (nothing to read).
fn check_accessor(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    path: &Path,
    role: &str,
    allowed: &[(DataType, Dimensions)],
    expected: &str,
) -> Result<bool> {
    let place = format!("accessor {} ({role})", accessor.index());
    let refuse = |problem: String| Err(SceneError::invalid(path, &place, problem));
    let shape = (accessor.data_type(), accessor.dimensions());
    if !allowed.contains(&shape) {
        return refuse(format!(
            "holds {:?} of {:?}, but {role} must be {expected}; re-export the model",
            shape.1, shape.0
        ));
    }
    if accessor.sparse().is_some() {
        return refuse(
            "is a sparse accessor, which restauro does not read; re-export the model without \
             sparse accessors"
                .into(),
        );
    }
    if accessor.count() == 0 {
        return Ok(false);
    }
    let Some(view) = accessor.view() else {
        return refuse(
            "has no buffer view (all its values would be zero); re-export the model with its \
             data"
                .into(),
        );
    };
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer_len) {
        return refuse(format!(
            "its buffer view {} (bytes {} to {}) runs past the end of buffer {}, which holds \
             {buffer_len} bytes; the file is truncated or damaged",
            view.index(),
            view.offset(),
            view.offset().saturating_add(view.length()),
            view.buffer().index()
        ));
    }
    let size = accessor.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return refuse(format!(
            "its buffer view {} has a byte stride of {stride}, less than the {size} bytes of one \
             element, so elements would overlap; fix the stride (or re-export the model)",
            view.index()
        ));
    }
    let end = stride
        .checked_mul(accessor.count() - 1)
        .and_then(|b| b.checked_add(size))
        .and_then(|b| b.checked_add(accessor.offset()));
    if end.is_none_or(|end| end > view.length()) {
        return refuse(format!(
            "{} elements of {size} bytes every {stride} from byte {} do not fit in buffer view \
             {} of {} bytes; the counts or offsets are wrong",
            accessor.count(),
            accessor.offset(),
            view.index(),
            view.length()
        ));
    }
    Ok(true)
}

/// The running totals of an import, against the limits.
struct Totals<'a> {
    limits: &'a Limits,
    instances: u64,
    /// The perspective cameras met, as viewpoints.
    cameras: Vec<Viewpoint>,
    /// Reads a file beside the model (buffers, images).
    external: External<'a>,
    /// The materials' photos decoded so far.
    images: crate::formats::gltf::texture::Decoded,
}

/// A node's perspective camera as a viewpoint in the file's coordinates: glTF cameras look
/// along their local −Z with +Y up (glTF 2.0 §3.10), as VRML's do, and `yfov` is the vertical
/// field of view in radians. The node's scale is dropped (a camera has none).
fn camera_viewpoint(node: &gltf::Node, world: DMat4) -> Option<Viewpoint> {
    let camera = node.camera()?;
    let gltf::camera::Projection::Perspective(p) = camera.projection() else { return None };
    let (_, rotation, translation) = world.to_scale_rotation_translation();
    let (axis, angle) = rotation.to_axis_angle();
    let name = camera
        .name()
        .or(node.name())
        .map_or_else(|| format!("camera {}", camera.index()), str::to_owned);
    let finite = translation.is_finite() && axis.is_finite() && angle.is_finite();
    (finite && p.yfov().is_finite() && p.yfov() > 0.0).then(|| Viewpoint {
        position: translation.to_array(),
        orientation: (axis.as_vec3().to_array(), angle as f32),
        field_of_view: p.yfov(),
        description: name,
    })
}

/// Where a primitive is read: the file's buffers, the node's world transform, and its place
/// for messages.
struct PrimitiveAt<'r> {
    buffers: &'r [Vec<u8>],
    path: &'r Path,
    world: DMat4,
    /// `mesh <name> primitive <p>`.
    place: String,
}

impl PrimitiveAt<'_> {
    fn invalid(&self, problem: impl Into<String>) -> SceneError {
        SceneError::invalid(self.path, self.place.clone(), problem.into())
    }
}

/// A primitive's POSITION and index accessors, checked and worth drawing.
struct Geometry {
    /// The POSITION count.
    vertices: u64,
    /// The index count, if the primitive has an index accessor.
    indices: Option<u64>,
}

/// A primitive's optional attributes (checked) and its material's photo.
struct Attributes {
    has_normals: bool,
    has_texcoords: bool,
    has_colours: bool,
    photo: Option<crate::formats::gltf::texture::Photo>,
}

/// The values of a primitive, read from its buffers and transformed to the world.
struct PrimitiveData {
    positions: Vec<[f64; 3]>,
    indices: Vec<u32>,
    normals: Option<Vec<[f32; 3]>>,
    texcoords: Option<Vec<[f32; 2]>>,
    colours: Option<Vec<[f32; 3]>>,
}

/// The depth of the hierarchy and the number of node instances, against the limits.
fn count_instance(path: &Path, depth: usize, totals: &mut Totals) -> Result<()> {
    if depth > 256 {
        return Err(SceneError::invalid(path, "node hierarchy", "nested more than 256 deep"));
    }
    // Nodes may be listed as children more than once (the specification forbids it, the crate
    // does not check), so a small file can stand for an exponential number of instances.
    totals.instances += 1;
    if totals.instances > totals.limits.max_instances {
        return Err(SceneError::Limit {
            path: path.to_owned(),
            what: "the number of node instances (counting nodes listed more than once)".into(),
            value: totals.instances,
            limit: totals.limits.max_instances,
            fix: "list each node once, or raise the limit with --max-instances".into(),
        });
    }
    Ok(())
}

/// The mode, the POSITION accessor and the indices of a primitive; `None` when it has no
/// vertices or no triangles, so nothing to draw.
fn check_geometry(prim: &gltf::Primitive, at: &PrimitiveAt) -> Result<Option<Geometry>> {
    if prim.mode() != Mode::Triangles {
        return Err(at.invalid(format!(
            "primitive mode {:?}; only triangle lists are read (re-export with triangles)",
            prim.mode()
        )));
    }
    let Some(position_accessor) = prim.get(&gltf::Semantic::Positions) else {
        return Err(
            at.invalid("no POSITION attribute; a triangle primitive needs its vertex positions")
        );
    };
    let has_positions = check_accessor(
        &position_accessor,
        at.buffers,
        at.path,
        "POSITION",
        &[(DataType::F32, Dimensions::Vec3)],
        "VEC3 of float (componentType 5126)",
    )?;
    let index_accessor = prim.indices();
    let has_indices = match &index_accessor {
        Some(a) => check_accessor(
            a,
            at.buffers,
            at.path,
            "indices",
            &[
                (DataType::U8, Dimensions::Scalar),
                (DataType::U16, Dimensions::Scalar),
                (DataType::U32, Dimensions::Scalar),
            ],
            "SCALAR of unsigned byte, short or int (componentType 5121, 5123 or 5125)",
        )?,
        None => false,
    };
    if !has_positions || (index_accessor.is_some() && !has_indices) {
        return Ok(None); // no vertices or no triangles: nothing to draw
    }
    Ok(Some(Geometry {
        vertices: position_accessor.count() as u64,
        indices: index_accessor.map(|a| a.count() as u64),
    }))
}

/// The triangles and vertices the primitive adds, against the limits.
fn check_counts(mesh: &Mesh, limits: &Limits, geometry: &Geometry, at: &PrimitiveAt) -> Result<()> {
    let count = geometry.vertices;
    let new_triangles = match geometry.indices {
        Some(n) => n / 3,
        None => count / 3,
    };
    let triangles = mesh.triangles.len() as u64 + new_triangles;
    if triangles > limits.max_triangles {
        return Err(SceneError::Limit {
            path: at.path.to_owned(),
            what: format!("the number of triangles (counting node instances) at {}", at.place),
            value: triangles,
            limit: limits.max_triangles,
            fix: "simplify the model, or raise the limit with --max-triangles".into(),
        });
    }
    // Vertices no triangle could use are not worth memory: at most three per triangle.
    let vertices = mesh.positions.len() as u64 + count;
    let max_vertices = limits.max_triangles.saturating_mul(3).min(u64::from(u32::MAX));
    if vertices > max_vertices {
        return Err(SceneError::Limit {
            path: at.path.to_owned(),
            what: format!("the number of vertices (counting node instances) at {}", at.place),
            value: vertices,
            limit: max_vertices,
            fix: "simplify the model, or raise the triangle limit (three vertices each) \
                  with --max-triangles"
                .into(),
        });
    }
    Ok(())
}

/// The NORMAL, TEXCOORD_n and COLOR_0 accessors, and the material's photo (whose set decides
/// which TEXCOORD_n).
fn check_attributes(
    prim: &gltf::Primitive,
    material: &gltf::Material,
    at: &PrimitiveAt,
    totals: &mut Totals,
) -> Result<Attributes> {
    // Whether the primitive has a readable `semantic` accessor (checked).
    let has = |semantic: gltf::Semantic, allowed: &[(DataType, Dimensions)], expected| {
        let role = semantic.to_string();
        prim.get(&semantic).map_or(Ok(false), |a| {
            check_accessor(&a, at.buffers, at.path, &role, allowed, expected)
        })
    };
    let vec3 = [(DataType::F32, Dimensions::Vec3)];
    let has_normals = has(gltf::Semantic::Normals, &vec3, "VEC3 of float (componentType 5126)")?;
    let photo = crate::formats::gltf::texture::base_colour_photo(
        material,
        at.buffers,
        at.path,
        (totals.external, totals.limits.max_pixels),
        &mut totals.images,
    )?;
    let set = photo.as_ref().map_or(0, |p| p.set);
    let uv = [DataType::F32, DataType::U8, DataType::U16].map(|t| (t, Dimensions::Vec2));
    let has_texcoords = has(
        gltf::Semantic::TexCoords(set),
        &uv,
        "VEC2 of float, or of normalized unsigned byte or short",
    )?;
    // Vertex colours (glTF 2.0 §3.7.2.1: linear, multiplying the base colour), as a
    // scanner's photogrammetry export carries them when it bakes no photo.
    let colour = [DataType::F32, DataType::U8, DataType::U16]
        .map(|t| [(t, Dimensions::Vec3), (t, Dimensions::Vec4)]);
    let has_colours = has(
        gltf::Semantic::Colors(0),
        colour.as_flattened(),
        "VEC3 or VEC4 of float, or of normalized unsigned byte or short",
    )?;
    Ok(Attributes { has_normals, has_texcoords, has_colours, photo })
}

/// The values of the checked accessors, positions and normals in world coordinates; the
/// indices are checked against the vertices.
fn read_primitive(
    prim: &gltf::Primitive,
    attributes: &Attributes,
    indexed: bool,
    at: &PrimitiveAt,
) -> Result<PrimitiveData> {
    let world = at.world;
    let buffers = at.buffers;
    let (has_normals, has_texcoords, has_colours) =
        (attributes.has_normals, attributes.has_texcoords, attributes.has_colours);
    let photo = attributes.photo.as_ref();
    let set = photo.map_or(0, |p| p.set);
    // Normals go through the inverse transpose, so a non-uniform scale keeps them normal.
    let normal_matrix = DMat3::from_mat4(world).inverse().transpose();
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let read = guard::catch(|| {
        let positions: Option<Vec<[f64; 3]>> = reader.read_positions().map(|ps| {
            ps.map(|p| world.transform_point3(DVec3::from_array(p.map(f64::from))).to_array())
                .collect()
        });
        let indices: Option<Vec<u32>> = reader.read_indices().map(|i| i.into_u32().collect());
        let normals: Option<Vec<[f32; 3]>> =
            reader.read_normals().filter(|_| has_normals).map(|ns| {
                ns.map(|n| {
                    let n = normal_matrix * DVec3::from_array(n.map(f64::from));
                    unit_or_zero(n.as_vec3().to_array())
                })
                .collect()
            });
        let transform = photo.and_then(|p| p.transform);
        let texcoords: Option<Vec<[f32; 2]>> = reader
            .read_tex_coords(set)
            .filter(|_| has_texcoords)
            .map(|t| t.into_f32().map(|uv| transform.map_or(uv, |x| x.apply(uv))).collect());
        let colours: Option<Vec<[f32; 3]>> =
            reader.read_colors(0).filter(|_| has_colours).map(|c| c.into_rgb_f32().collect());
        (positions, indices, normals, texcoords, colours)
    })
    .map_err(|_| at.invalid(guard::gave_up("glTF")))?;
    let (Some(positions), indices, normals, texcoords, colours) = read else {
        return Err(
            at.invalid("the POSITION values cannot be read from their buffer; the file is damaged")
        );
    };
    let indices = check_indices(indices, indexed, positions.len() as u32, at)?;
    Ok(PrimitiveData { positions, indices, normals, texcoords, colours })
}

/// The indices as read (all vertices in order without an index accessor): whole triangles, of
/// vertices the primitive has.
fn check_indices(
    indices: Option<Vec<u32>>,
    indexed: bool,
    count: u32,
    at: &PrimitiveAt,
) -> Result<Vec<u32>> {
    let indices: Vec<u32> = match (indices, indexed) {
        (Some(i), _) => i,
        (None, false) => (0..count).collect(),
        (None, true) => {
            return Err(
                at.invalid("the indices cannot be read from their buffer; the file is damaged")
            );
        }
    };
    if !indices.len().is_multiple_of(3) {
        return Err(at.invalid("the index count is not a multiple of 3"));
    }
    if let Some(bad) = indices.iter().find(|&&i| i >= count) {
        return Err(at.invalid(format!(
            "vertex index {bad} is out of range: the primitive has {count} vertices"
        )));
    }
    Ok(indices)
}

/// The part a primitive's triangles go to: its material's name, colour, sidedness and photo.
fn material_group(
    mesh: &mut Mesh,
    material: &gltf::Material,
    photo: Option<crate::formats::gltf::texture::Photo>,
) -> u32 {
    let name = match (material.name(), material.index()) {
        (Some(n), _) => n.to_owned(),
        (None, Some(i)) => format!("material{i}"),
        (None, None) => "default".to_owned(),
    };
    let [r, g, b, _] = material.pbr_metallic_roughness().base_color_factor();
    mesh.group_index(Group {
        name,
        colour: Some([r, g, b]),
        double_sided: material.double_sided(),
        photo: photo.map(|p| p.texture),
    })
}

/// The primitive's vertices, their shading normals, texture coordinates and colours, and its
/// triangles in `group`, added to the mesh.
fn append_primitive(
    mesh: &mut Mesh,
    data: PrimitiveData,
    group: u32,
    at: &PrimitiveAt,
) -> Result<()> {
    let PrimitiveData { positions, indices, normals, texcoords, colours } = data;
    // A mirroring transform (negative determinant) turns the winding around.
    let flip = at.world.determinant() < 0.0;
    let base = mesh.positions.len() as u32;
    let shading = mesh.normals.get_or_insert_with(Vec::new);
    match normals {
        Some(n) if n.len() == positions.len() => shading.extend(n),
        // Without NORMAL the primitive is flat, as glTF 2.0 §3.7.2.1 says.
        _ => shading.resize(base as usize + positions.len(), [0.0; 3]),
    }
    let uv = mesh.texcoords.get_or_insert_with(Vec::new);
    match texcoords {
        Some(t) if t.len() == positions.len() => uv.extend(t),
        _ => uv.resize(base as usize + positions.len(), [f32::NAN; 2]),
    }
    if let Some(bad) =
        colours.iter().flatten().position(|c| !c.iter().all(|v| (0.0..=1.0).contains(v)))
    {
        return Err(at.invalid(format!(
            "COLOR_0 of vertex {bad} is outside 0 to 1; vertex colours are linear \
             values from 0 to 1"
        )));
    }
    let vertex_colours = mesh.colours.get_or_insert_with(Vec::new);
    match colours {
        Some(c) if c.len() == positions.len() => vertex_colours.extend(c),
        _ => vertex_colours.resize(base as usize + positions.len(), [f32::NAN; 3]),
    }
    for p in positions {
        mesh.push_position(p);
    }
    for t in indices.chunks_exact(3) {
        let tri = if flip { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] };
        mesh.triangles.push(tri.map(|i| base + i));
        mesh.triangle_group.push(group);
    }
    Ok(())
}

/// One triangle primitive of a node's mesh, checked, read and added to the mesh.
fn add_primitive(
    prim: &gltf::Primitive,
    at: &PrimitiveAt,
    mesh: &mut Mesh,
    totals: &mut Totals,
) -> Result<()> {
    let Some(geometry) = check_geometry(prim, at)? else {
        return Ok(());
    };
    check_counts(mesh, totals.limits, &geometry, at)?;
    let material = prim.material();
    let mut attributes = check_attributes(prim, &material, at, totals)?;
    let data = read_primitive(prim, &attributes, geometry.indices.is_some(), at)?;
    let group = material_group(mesh, &material, attributes.photo.take());
    append_primitive(mesh, data, group, at)
}

fn add_node(
    node: gltf::Node,
    parent: DMat4,
    buffers: &[Vec<u8>],
    mesh: &mut Mesh,
    path: &Path,
    depth: usize,
    totals: &mut Totals,
) -> Result<()> {
    count_instance(path, depth, totals)?;
    // The chain of transforms in 64 bits: a survey's offset often sits in a node's translation.
    let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
    let world = parent * local;
    totals.cameras.extend(camera_viewpoint(&node, world));
    if let Some(m) = node.mesh() {
        for (p, prim) in m.primitives().enumerate() {
            let place = format!(
                "mesh {} primitive {p}",
                m.name().map_or(m.index().to_string(), str::to_owned)
            );
            let at = PrimitiveAt { buffers, path, world, place };
            add_primitive(&prim, &at, mesh, totals)?;
        }
    }
    for child in node.children() {
        add_node(child, world, buffers, mesh, path, depth + 1, totals)?;
    }
    Ok(())
}

/// Read glTF bytes (JSON or GLB) that need no other file. `path` names the file in messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let no_folder = |uri: &str| {
        Err(SceneError::invalid(
            path,
            "buffers",
            format!("refers to the separate file `{uri}`, and there is no folder to read it from"),
        ))
    };
    parse_limited(bytes, path, &Limits::default(), &no_folder)
}

/// A GLB container's framing (glTF 2.0 §4.4), checked before the gltf crate splits it: it
/// subtracts the 12-byte header from the stated length without checking that the length holds
/// it (an overflow, a panic in builds with overflow checks).
fn check_glb(bytes: &[u8], path: &Path) -> Result<()> {
    let word =
        |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let refuse = |place: &str, problem: String| Err(SceneError::invalid(path, place, problem));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return refuse(
            "GLB header",
            "the file ends inside the 12-byte GLB header; it is truncated".into(),
        );
    };
    if version != 2 {
        return refuse(
            "GLB header",
            format!("GLB version {version}; restauro reads glTF 2.0 (version 2)"),
        );
    }
    if length < 12 || length as usize > bytes.len() {
        return refuse(
            "GLB header",
            format!(
                "the header gives a length of {length} bytes but the file has {}; it is truncated \
                 or damaged",
                bytes.len()
            ),
        );
    }
    let mut at = 12usize;
    let mut chunk = 0;
    while at < length as usize {
        let (Some(chunk_length), Some(_)) = (word(at), word(at + 4)) else {
            return refuse(
                &format!("GLB chunk {chunk} (byte {at})"),
                "the file ends inside a chunk header; it is truncated".into(),
            );
        };
        let end = (at + 8).checked_add(chunk_length as usize);
        if end.is_none_or(|end| end > length as usize) {
            return refuse(
                &format!("GLB chunk {chunk} (byte {at})"),
                format!(
                    "a chunk of {chunk_length} bytes runs past the end of the file ({length} bytes); \
                     it is truncated or damaged"
                ),
            );
        }
        at = end.unwrap_or(usize::MAX);
        chunk += 1;
    }
    Ok(())
}

/// Checks the gltf crate's validation takes for granted: its hook for a primitive's POSITION
/// accessor indexes the accessors before the index itself is validated (a panic on an index out
/// of range).
fn check_references(doc: &gltf::json::Root, path: &Path) -> Result<()> {
    let accessors = doc.accessors.len();
    for (m, mesh) in doc.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let place = || format!("meshes[{m}].primitives[{p}]");
            for (semantic, index) in &primitive.attributes {
                if index.value() >= accessors {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "an attribute".into(),
                    };
                    return Err(SceneError::invalid(
                        path,
                        format!("{}.attributes.{name}", place()),
                        format!(
                            "refers to accessor {}, but the file has {accessors} accessors; the file \
                             is damaged, re-export it",
                            index.value()
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// [`parse`] within `limits` (node instances, triangles); `external` reads the buffers a
/// `.gltf` keeps in separate files.
pub fn parse_limited(
    bytes: &[u8],
    path: &Path,
    limits: &Limits,
    external: External<'_>,
) -> Result<Mesh> {
    Ok(parse_with_cameras(bytes, path, limits, external)?.0)
}

/// [`parse_limited`], with the file's perspective cameras (in the default scene, in node order)
/// as viewpoints the scene's camera can use.
pub fn parse_with_cameras(
    bytes: &[u8],
    path: &Path,
    limits: &Limits,
    external: External<'_>,
) -> Result<(Mesh, Vec<Viewpoint>)> {
    if bytes.starts_with(b"glTF") {
        check_glb(bytes, path)?;
    }
    let gave_up = || SceneError::invalid(path, "glTF", guard::gave_up("glTF"));
    let not_gltf = |e: gltf::Error| {
        SceneError::invalid(path, "glTF", format!("{e}; the file is not valid glTF 2.0"))
    };
    let unchecked = guard::catch(|| gltf::Gltf::from_slice_without_validation(bytes))
        .map_err(|_| gave_up())?
        .map_err(not_gltf)?;
    check_references(unchecked.document.as_json(), path)?;
    let gltf::Gltf { document, blob } = unchecked;
    let document = guard::catch(|| gltf::Document::from_json(document.into_json()))
        .map_err(|_| gave_up())?
        .map_err(not_gltf)?;
    let doc = gltf::Gltf { document, blob };
    let buffers = buffers(&doc, path, external)?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::invalid(path, "scenes", "the file has no scene"))?;
    let mut mesh = Mesh::default();
    let mut totals =
        Totals { limits, instances: 0, cameras: Vec::new(), external, images: Default::default() };
    for node in scene.nodes() {
        add_node(node, DMat4::IDENTITY, &buffers, &mut mesh, path, 0, &mut totals)?;
    }
    mesh.drop_flat_normals();
    Ok((mesh, totals.cameras))
}

/// A `.gltf` with the buffers and images it keeps in separate files embedded as base64 `data:`
/// URIs, so that it is one file (for a bundle); a model with none (or a `.glb`) is returned as
/// it is.
pub fn embed_buffers(bytes: &[u8], path: &Path, external: External<'_>) -> Result<Vec<u8>> {
    if bytes.starts_with(b"glTF") {
        return Ok(bytes.to_vec());
    }
    let not_json = |e: serde_json::Error| {
        SceneError::invalid(path, "glTF", format!("{e}; the file is not valid glTF 2.0 JSON"))
    };
    let mut json: serde_json::Value = serde_json::from_slice(bytes).map_err(not_json)?;
    let mut changed = false;
    // Buffers, and the images of the materials' photos.
    for key in ["buffers", "images"] {
        let Some(items) = json.get_mut(key).and_then(|b| b.as_array_mut()) else { continue };
        for (index, item) in items.iter_mut().enumerate() {
            let Some(uri) = item.get("uri").and_then(|u| u.as_str()) else { continue };
            if uri.starts_with("data:") {
                continue;
            }
            let data = external(&external_path(uri, path, index)?)?;
            let media = match key {
                "buffers" => "application/octet-stream",
                _ if data.starts_with(&[0xff, 0xd8, 0xff]) => "image/jpeg",
                _ => "image/png",
            };
            let encoded = base64::engine::general_purpose::STANDARD.encode(&data);
            item["uri"] = format!("data:{media};base64,{encoded}").into();
            changed = true;
        }
    }
    Ok(if changed { serde_json::to_vec(&json).map_err(not_json)? } else { bytes.to_vec() })
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

    /// A glTF of one triangle drawn twice: by `node` (a node of mesh 0, whose primitive has
    /// vertex attribute `attribute`, VEC3 of float, of `values`), and by a node of mesh 1,
    /// whose primitive has none.
    fn triangle_with(attribute: &str, values: [[f32; 3]; 3], node: &str) -> String {
        let mut bin = Vec::new();
        let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        for c in positions.iter().chain(&values).flatten() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
        for i in [0u16, 1, 2] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let data = base64::engine::general_purpose::STANDARD.encode(&bin);
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
            "nodes":[{node},{{"mesh":1}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"{attribute}":2}},"indices":1}}]}},
                      {{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}},
                         {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},
                           {{"buffer":0,"byteOffset":72,"byteLength":6}}],
            "buffers":[{{"byteLength":78,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#
        )
    }

    /// NORMAL goes through the inverse transpose of the node's transform (a non-uniform scale
    /// tilts it) and is scaled to unit length; a primitive without NORMAL is flat (zeros).
    #[test]
    fn normals_are_read_and_carried_through_the_transform() {
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let normals = [[0.0, 0.0, 1.0], [0.0, h, h], [1.0, 0.0, 0.0]];
        let gltf = triangle_with("NORMAL", normals, r#"{"mesh":0,"scale":[1,2,1]}"#);
        let mesh = parse(gltf.as_bytes(), Path::new("n.gltf")).unwrap();
        let normals = mesh.normals.expect("normals");
        // (0, ½√2, ½√2) through diag(1, ½, 1): (0, 1, 2)/√5.
        let expect = [[0.0, 0.0, 1.0], [0.0, 0.4472136, 0.8944272], [1.0, 0.0, 0.0], [0.0; 3]];
        for (k, e) in expect.iter().enumerate() {
            for c in 0..3 {
                assert!((normals[k][c] - e[c]).abs() < 1e-6, "vertex {k}: {:?}", normals[k]);
            }
        }
        assert_eq!(&normals[3..], &[[0.0; 3]; 3]);
    }

    /// COLOR_0 (linear floats here) becomes the vertices' colours as they are; a primitive
    /// without it has none (NaN); a colour beyond 1 is refused, naming the vertex.
    #[test]
    fn color_0_is_read_and_checked() {
        let gltf = |red: f32| {
            let colours = [[0.25, 0.5, 0.75], [red, 0.0, 0.0], [1.0, 1.0, 1.0]];
            triangle_with("COLOR_0", colours, r#"{"mesh":0}"#)
        };
        let mesh = parse(gltf(0.5).as_bytes(), Path::new("c.gltf")).unwrap();
        let colours = mesh.colours.expect("colours");
        assert_eq!(&colours[..3], &[[0.25, 0.5, 0.75], [0.5, 0.0, 0.0], [1.0, 1.0, 1.0]]);
        assert!(colours[3..].iter().flatten().all(|c| c.is_nan()));
        let err = parse(gltf(1.5).as_bytes(), Path::new("c.gltf")).unwrap_err().to_string();
        assert!(
            err.contains("c.gltf: mesh 0 primitive 0: COLOR_0 of vertex 1 is outside 0 to 1"),
            "{err}"
        );
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
                double_sided: true,
                photo: None,
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
    fn external_buffers_are_read_and_embedded() {
        let embedded = two_instances();
        let (head, rest) = embedded.split_once("data:application/octet-stream;base64,").unwrap();
        let (data, tail) = rest.split_once('"').unwrap();
        let bin = base64::engine::general_purpose::STANDARD.decode(data).unwrap();
        // The same model with its buffer in `mesh data.bin` beside it (a percent-encoded URI).
        let separate = format!("{head}mesh%20data.bin\"{tail}");
        let files = |uri: &str| -> Result<Vec<u8>> {
            assert_eq!(uri, "mesh data.bin");
            Ok(bin.clone())
        };
        let path = Path::new("s.gltf");
        let limits = Limits::default();
        let from_files = parse_limited(separate.as_bytes(), path, &limits, &files).unwrap();
        let reference = parse(embedded.as_bytes(), path).unwrap();
        assert_eq!(from_files.positions, reference.positions);
        // Embedded for a bundle: one file, the same triangles.
        let one = embed_buffers(separate.as_bytes(), path, &files).unwrap();
        assert_eq!(parse(&one, path).unwrap().positions, reference.positions);
        assert_eq!(embed_buffers(embedded.as_bytes(), path, &files).unwrap(), embedded.as_bytes());
        // Without a folder, or outside it, a separate file is refused.
        let err = parse(separate.as_bytes(), path).unwrap_err().to_string();
        assert!(err.contains("mesh data.bin"), "{err}");
        for uri in ["https://example.org/m.bin", "/etc/m.bin", "C:%5Cm.bin"] {
            let far = format!("{head}{uri}\"{tail}");
            let err = parse_limited(far.as_bytes(), path, &limits, &files).unwrap_err();
            assert!(err.to_string().contains("not a file beside the model"), "{uri}: {err}");
        }
    }

    #[test]
    fn bad_json_is_refused() {
        let err = parse(b"{not json", Path::new("j.gltf")).unwrap_err().to_string();
        assert!(err.starts_with("j.gltf: glTF: "), "{err}");
    }
}
