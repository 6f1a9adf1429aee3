//! The `[[objects]]` table: each object's name and transform checked, its mesh imported (OBJ,
//! PLY, glTF, VRML) and checked as its file holds it, placed in the world and checked there, and
//! its parts bound to the scene's materials; then the level-of-detail pass hides the parts that
//! detailed objects replace. The scene's triangles are counted as the meshes arrive, so that a
//! scene over the limit is refused before the rest of it is read.

use super::{Ctx, Limits, MAX_COORDINATE_M, finite3, placeable, unknown};
use crate::assets::{extension, utf8_text};
use crate::error::{Result, SceneError};
use crate::formats::gltf::mesh as gltf_mesh;
use crate::formats::{obj, ply, vrml};
use crate::mesh::Mesh;
use crate::scene_file::{self, UpAxis};
use crate::upright;
use glam::{DMat3, DMat4, DVec3};
use std::collections::{BTreeMap, BTreeSet};

/// An object's mesh in world coordinates and what each of its parts is made of.
#[derive(Clone, Debug)]
pub struct LoadedObject {
    pub name: String,
    pub mesh: Mesh,
    /// For each mesh group, the scene material.
    pub group_materials: Vec<String>,
    /// For each mesh group, whether another object replaces it (level of detail).
    pub hidden_groups: Vec<bool>,
}

/// Each object's viewpoints (a VRML world's, a glTF file's cameras) and its placement, for the
/// camera to look through.
pub(super) type Viewpoints = BTreeMap<String, (Vec<vrml::Viewpoint>, DMat4)>;

/// Every object, in the file's order, then the parts that others replace.
pub(super) fn load_objects(
    ctx: &mut Ctx,
    limits: &Limits,
) -> Result<(Vec<LoadedObject>, Viewpoints)> {
    let file = ctx.file;
    let mut objects: Vec<LoadedObject> = Vec::new();
    let mut viewpoints: Viewpoints = BTreeMap::new();
    let mut names = BTreeSet::new();
    let mut triangles: u64 = 0;
    for (i, o) in file.objects.iter().enumerate() {
        let place = format!("objects[{i}] ({})", o.name);
        if !names.insert(o.name.clone()) {
            return Err(ctx.invalid(
                &place,
                format!("the name `{}` is used by two objects; names must be unique", o.name),
            ));
        }
        check_transform(ctx, &place, &o.transform)?;
        let (mut mesh, vps, file_up) = import_object(ctx, o, &place, limits)?;
        triangles += mesh.triangles.len() as u64;
        if triangles > limits.max_triangles {
            return Err(ctx.limit(
                "the number of triangles",
                triangles,
                limits.max_triangles,
                "simplify the meshes, or raise the limit with --max-triangles",
            ));
        }
        let matrix = object_matrix(o, file_up);
        transform_mesh(&mut mesh, matrix);
        check_placed(ctx, &mesh, &place, &o.mesh)?;
        viewpoints.insert(o.name.clone(), (vps, matrix));
        let group_materials = bind_materials(ctx, o, &place, &mesh)?;
        let hidden_groups = vec![false; mesh.groups.len()];
        objects.push(LoadedObject { name: o.name.clone(), mesh, group_materials, hidden_groups });
    }
    replace_parts(ctx, &mut objects)?;
    Ok((objects, viewpoints))
}

/// An object's transform: every number finite, and a scale not 0.
fn check_transform(ctx: &Ctx, place: &str, t: &scene_file::Transform) -> Result<()> {
    let bad_vec =
        t.translate.is_some_and(|v| !finite3(v)) || t.rotate_deg.is_some_and(|v| !finite3(v));
    let bad_scale = match &t.scale {
        Some(scene_file::Scale::Uniform(s)) => !(s.is_finite() && *s != 0.0),
        Some(scene_file::Scale::PerAxis(s)) => !s.iter().all(|v| v.is_finite() && *v != 0.0),
        None => false,
    };
    if bad_vec || bad_scale {
        return Err(ctx.invalid(
            format!("{place}.transform"),
            "every number must be finite, and a scale not 0",
        ));
    }
    Ok(())
}

/// The object's mesh imported and checked as its file holds it (see [`check_mesh`]), with the
/// file's notes; a part's photo without texture coordinates is dropped, and said; a mesh read
/// Z-up that looks Y-up is noted. Also returns the file's viewpoints and its up axis.
fn import_object(
    ctx: &mut Ctx,
    o: &scene_file::Object,
    place: &str,
    limits: &Limits,
) -> Result<(Mesh, Vec<vrml::Viewpoint>, UpAxis)> {
    let (mut mesh, vps, file_up, file_notes) =
        import_mesh(ctx, &o.mesh, &format!("{place}.mesh"), limits)?;
    // The notes name the mesh file and its line; the object says which use of it.
    ctx.notes.extend(file_notes.into_iter().map(|n| format!("object `{}`: {n}", o.name)));
    check_mesh(ctx, &mut mesh, place, &o.mesh)?;
    for g in 0..mesh.groups.len() {
        if mesh.groups[g].photo.is_some() && !mesh.group_has_texcoords(g as u32) {
            mesh.groups[g].photo = None;
            ctx.notes.push(format!(
                "object `{}`: part `{}` has a photo in `{}` but no texture coordinates for it; it is shown without",
                o.name, mesh.groups[g].name, o.mesh
            ));
        }
    }
    if o.up_axis.is_none() && file_up == UpAxis::Z {
        note_if_on_its_back(ctx, &mesh, place, &o.mesh);
    }
    Ok((mesh, vps, file_up))
}

/// Bind each part to a scene material: every key of the object's `materials` a part of its
/// mesh, every part a material the scene defines, a white patch the part's photo holds, and
/// texture coordinates wherever the material has a texture.
fn bind_materials(
    ctx: &Ctx,
    o: &scene_file::Object,
    place: &str,
    mesh: &Mesh,
) -> Result<Vec<String>> {
    let file = ctx.file;
    for key in o.materials.keys() {
        if !mesh.groups.iter().any(|g| &g.name == key) {
            return Err(ctx.invalid(
                format!("{place}.materials"),
                unknown("mesh part", key, mesh.groups.iter().map(|g| g.name.as_str()))
                    .replace("the scene defines", &format!("`{}` has", o.mesh)),
            ));
        }
    }
    let mut group_materials = Vec::new();
    for g in &mesh.groups {
        let material = o.materials.get(&g.name).or(o.material.as_ref()).ok_or_else(|| {
            ctx.invalid(
                place,
                format!(
                    "part `{}` of `{}` has no material: bind it in `materials` or give `material`",
                    g.name, o.mesh
                ),
            )
        })?;
        if !file.materials.contains_key(material) {
            return Err(ctx.invalid(
                place,
                unknown("material", material, file.materials.keys().map(String::as_str)),
            ));
        }
        let m = &file.materials[material];
        if let (Some(photo), None, Some(patch)) = (&g.photo, &m.texture, m.white_patch) {
            photo.check_patch(patch).map_err(|problem| {
                ctx.invalid(
                    format!("materials.{material}.white_patch"),
                    format!("in the photo of part `{}` of `{}`: {problem}", g.name, o.mesh),
                )
            })?;
        }
        let textured = ["base", "degraded", "cleaned"].iter().any(|st| m.texture_of(st).is_some());
        let group = group_materials.len() as u32;
        if textured && !mesh.group_has_texcoords(group) {
            return Err(ctx.invalid(
                place,
                format!(
                    "part `{}` of `{}` has no texture coordinates (OBJ `vt`, glTF TEXCOORD_0), \
                     but its material `{material}` has a texture; export the model with its \
                     texture coordinates, or take the texture off the material",
                    g.name, o.mesh
                ),
            ));
        }
        group_materials.push(material.clone());
    }
    Ok(group_materials)
}

/// Level of detail: hide the parts that detailed objects replace.
fn replace_parts(ctx: &Ctx, objects: &mut [LoadedObject]) -> Result<()> {
    let file = ctx.file;
    for (i, o) in file.objects.iter().enumerate() {
        let Some(rep) = &o.replaces else { continue };
        let place = format!("objects[{i}] ({}).replaces", o.name);
        if rep.object == o.name {
            return Err(ctx.invalid(&place, "an object cannot replace itself"));
        }
        let target = objects.iter_mut().find(|t| t.name == rep.object).ok_or_else(|| {
            SceneError::invalid(
                &ctx.path,
                &place,
                unknown("object", &rep.object, file.objects.iter().map(|o| o.name.as_str())),
            )
        })?;
        for g in &rep.groups {
            let k = target.mesh.groups.iter().position(|x| &x.name == g).ok_or_else(|| {
                SceneError::invalid(
                    &ctx.path,
                    &place,
                    unknown("mesh part", g, target.mesh.groups.iter().map(|x| x.name.as_str())),
                )
            })?;
            target.hidden_groups[k] = true;
        }
    }
    Ok(())
}

/// Import a mesh by its reference's extension; also returns VRML viewpoints and the file's
/// own notes (what a VRML world holds but does not draw). Messages about the mesh's content
/// name the mesh file by its path.
fn import_mesh(
    ctx: &Ctx,
    reference: &str,
    place: &str,
    limits: &Limits,
) -> Result<(Mesh, Vec<vrml::Viewpoint>, UpAxis, Vec<String>)> {
    let bytes = ctx.assets.read(reference, place)?;
    let name = ctx.assets.display_path(reference);
    Ok(match extension(reference).as_str() {
        "obj" => {
            let text = utf8_text(bytes, &name)?;
            let mut mesh = obj::parse_limited(&text, &name, limits)?;
            let notes = crate::formats::obj::library::apply(
                &mut mesh,
                &text,
                reference,
                ctx.assets,
                place,
                limits.max_pixels,
            )?;
            (mesh, Vec::new(), UpAxis::Z, notes)
        }
        "ply" => (ply::parse_limited(&bytes, &name, limits)?, Vec::new(), UpAxis::Z, Vec::new()),
        "gltf" | "glb" => {
            // A buffer that cannot be read is the model's problem: the message names the model.
            let beside = |uri: &str| {
                let invalid = |e: String| SceneError::invalid(&name, format!("buffer `{uri}`"), e);
                let file =
                    crate::assets::sibling(reference, uri).map_err(|e| invalid(e.to_string()))?;
                ctx.assets.read(&file, place).map_err(|e| invalid(e.to_string()))
            };
            let (mesh, cameras) = gltf_mesh::parse_with_cameras(&bytes, &name, limits, &beside)?;
            (mesh, cameras, UpAxis::Y, Vec::new())
        }
        "wrl" => {
            let text = utf8_text(bytes, &name)?;
            let inlines = crate::formats::vrml::inlines_from_assets(ctx.assets, place);
            let scene = vrml::parse_with_inlines(&text, &name, reference, limits, &inlines)?;
            (scene.mesh, scene.viewpoints, UpAxis::Y, scene.notes)
        }
        other => {
            return Err(ctx.invalid(
                place,
                format!("`{reference}`: `.{other}` is not a mesh format restauro reads; use .obj, .gltf, .glb, .ply or .wrl"),
            ));
        }
    })
}

/// The object's placement: the file's up axis turned to +Z, then scale, rotation (X, Y, Z)
/// and translation.
fn object_matrix(object: &scene_file::Object, file_up: UpAxis) -> DMat4 {
    let up = match object.up_axis.unwrap_or(file_up) {
        // Y-up to Z-up: +Y becomes +Z, +Z becomes −Y (a +90° turn about X).
        UpAxis::Y => DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2),
        UpAxis::Z => DMat4::IDENTITY,
    };
    let t = &object.transform;
    let scale = match &t.scale {
        Some(scene_file::Scale::Uniform(s)) => DVec3::splat(*s),
        Some(scene_file::Scale::PerAxis(s)) => DVec3::from_array(*s),
        None => DVec3::ONE,
    };
    let r = t.rotate_deg.unwrap_or([0.0; 3]).map(f64::to_radians);
    let rotation =
        DMat4::from_rotation_z(r[2]) * DMat4::from_rotation_y(r[1]) * DMat4::from_rotation_x(r[0]);
    DMat4::from_translation(DVec3::from_array(t.translate.unwrap_or([0.0; 3])))
        * rotation
        * DMat4::from_scale(scale)
        * up
}

/// A note when a mesh read as Z-up looks as if it were written Y-up (see [`upright`]).
fn note_if_on_its_back(ctx: &mut Ctx, mesh: &Mesh, place: &str, reference: &str) {
    if let Some(e) = upright::y_up_evidence(mesh) {
        ctx.notes.push(format!(
            "{place}: `{reference}` probably lies on its back: read Z-up, as OBJ and PLY are by \
             default, its surfaces face +Y overall ({:.0}° from +Y, where a survey's open \
             underside leaves them facing up). If it was exported Y-up, add `up_axis = \"y\"` \
             to the object; `up_axis = \"z\"` says it is right as it is and ends this note",
            e.angle_to_y_deg
        ));
    }
}

/// Check the imported mesh: finite vertices, valid indices, something to render; degenerate
/// triangles (zero area, common in scans) are dropped and counted.
fn check_mesh(ctx: &mut Ctx, mesh: &mut Mesh, place: &str, reference: &str) -> Result<()> {
    if let Some(i) = mesh.positions.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(ctx.invalid(
            place,
            format!("`{reference}`: vertex {i} is {:?}, not a finite position", mesh.positions[i]),
        ));
    }
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(ctx.invalid(
            place,
            format!("`{reference}`: triangle {t} refers to a vertex beyond the {n} there are"),
        ));
    }
    let before = mesh.triangles.len();
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| DVec3::from_array(mesh.positions[i as usize].map(f64::from)));
            (b - a).cross(c - a).length_squared() > 0.0
        })
        .collect();
    let mut k = keep.iter();
    mesh.triangles.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    mesh.triangle_group.retain(|_| *k.next().unwrap_or(&true));
    let mut k = keep.iter();
    mesh.levels.of_triangle.retain(|_| *k.next().unwrap_or(&true));
    let dropped = before - mesh.triangles.len();
    if mesh.triangles.is_empty() {
        return Err(ctx.invalid(
            place,
            format!("`{reference}` has no triangles with an area; nothing to render"),
        ));
    }
    if dropped > 0 {
        ctx.notes.push(format!(
            "{place}: {dropped} degenerate (zero-area) triangles of `{reference}` dropped"
        ));
    }
    Ok(())
}

/// Every vertex of a placed mesh within [`MAX_COORDINATE_M`]: a huge scale or translation
/// must be refused here, by `scene check`, not by the tracer's BVH builder.
fn check_placed(ctx: &Ctx, mesh: &Mesh, place: &str, reference: &str) -> Result<()> {
    match mesh.positions.iter().position(|p| !p.iter().all(|&x| placeable(f64::from(x)))) {
        None => Ok(()),
        Some(i) => Err(ctx.invalid(
            format!("{place}.transform"),
            format!(
                "vertex {i} of `{reference}` lands at {:?} m once placed, beyond ±{MAX_COORDINATE_M:e} m; \
                 check the transform's scale and translate (and the file's units)",
                mesh.positions[i]
            ),
        )),
    }
}

/// Place the mesh: its file coordinates (anchor and all, in 64 bits) through `m`, which
/// includes the scene's `origin`; the placed mesh has no anchor.
fn transform_mesh(mesh: &mut Mesh, m: DMat4) {
    let anchor = DVec3::from_array(mesh.anchor_m);
    for p in &mut mesh.positions {
        let in_file = anchor + DVec3::from_array(p.map(f64::from));
        *p = m.transform_point3(in_file).as_vec3().to_array();
    }
    mesh.anchor_m = [0.0; 3];
    mesh.levels.transform(m);
    let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
    if let Some(normals) = &mut mesh.normals {
        for n in normals.iter_mut() {
            *n = (normal_matrix * DVec3::from_array(n.map(f64::from)))
                .normalize_or_zero()
                .as_vec3()
                .to_array();
        }
    }
    // A mirroring placement turns the winding around; keep front faces counter-clockwise.
    if m.determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
}
