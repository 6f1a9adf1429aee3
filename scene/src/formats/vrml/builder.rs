//! Walking the node tree: transforms, shapes and their geometry appended to the mesh, and
//! notes for what is not drawn.

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use super::census::{TRIANGLES_FIX, depth_limit, instances_limit};
use super::faces::Local;
use super::math::*;
use super::notes::Notes;
use super::parser::{Field, Node, Value};
use super::{MAX_DEPTH, Viewpoint};
use crate::error::SceneError;
use crate::limits::Limits;
use crate::mesh::{Group, Mesh};

/// Turns the parsed nodes into the mesh, instance by instance.
pub(super) struct Builder<'s> {
    /// The file being walked: the world's, or an `Inline`d file's while its nodes are walked.
    pub path: Rc<Path>,
    /// Where `Inline`d files come from; without it, an Inline is noted and not drawn.
    pub inline: Option<&'s super::InlineFn<'s>>,
    /// The references of the files being walked, the world's first (an Inline's url is
    /// relative to the file it is in).
    pub files: Vec<String>,
    /// Inlined files parsed, by (the file inlining, the url).
    pub inlined: HashMap<(String, String), Rc<super::inline::InlinedFile>>,
    pub limits: Limits,
    pub mesh: Mesh,
    pub viewpoints: Vec<Viewpoint>,
    pub notes: Notes,
    instances: u64,
    pub max_triangles: u64,
    max_instances: u64,
    pub max_polygon_vertices: u64,
    /// The triangulation of each geometry node walked, by node address (the nodes live as
    /// long as the builder).
    cache: HashMap<usize, Rc<Local>>,
    /// The (LOD, level) chain the walk is inside.
    lod_path: Vec<(u32, u32)>,
}

/// A field's place and name, for messages: "12:5: `translation` of Transform `arch`".
pub(super) fn place(field: &Field, node: &Node) -> String {
    format!("{}:{}: `{}` of {}", field.pos.line, field.pos.column, field.name, of(node))
}

/// A node as messages name it: "Transform `arch`" or "Box at 3:10".
pub(super) fn of(node: &Node) -> String {
    match &node.def {
        Some(name) => format!("{} `{name}`", node.kind),
        None => format!("{} at {}:{}", node.kind, node.pos.line, node.pos.column),
    }
}

/// Grouping nodes whose `children` are drawn (§6.2, §6.6, §6.8, §6.21, §6.52).
const GROUPS: [&str; 5] = ["Transform", "Group", "Anchor", "Billboard", "Collision"];
/// Geometry that is tessellated (§6.7, §6.11, §6.14, §6.17, §6.18, §6.43) or triangulated
/// (§6.23).
const GEOMETRY: [&str; 7] =
    ["IndexedFaceSet", "Box", "Sphere", "Cone", "Cylinder", "ElevationGrid", "Extrusion"];

impl<'s> Builder<'s> {
    /// A builder of the world at `path`, whose reference in the scene is `reference`.
    pub fn new(
        path: &Path,
        reference: &str,
        limits: &Limits,
        inline: Option<&'s super::InlineFn<'s>>,
    ) -> Builder<'s> {
        Builder {
            path: Rc::from(path),
            inline,
            files: vec![reference.to_owned()],
            inlined: HashMap::new(),
            limits: *limits,
            mesh: Mesh { normals: Some(Vec::new()), ..Mesh::default() },
            viewpoints: Vec::new(),
            notes: Notes::default(),
            instances: 0,
            max_triangles: limits.max_triangles,
            max_instances: limits.max_instances,
            max_polygon_vertices: limits.max_polygon_vertices,
            cache: HashMap::new(),
            lod_path: Vec::new(),
        }
    }
}

impl Builder<'_> {
    /// The numbers of a field, each finite in f32 range; `None` when the field is absent.
    pub fn finite_list<'n>(&self, node: &'n Node, name: &str) -> crate::Result<Option<&'n [f64]>> {
        let Some(field) = node.field(name) else { return Ok(None) };
        let nums: &[f64] = match &*field.value {
            Value::Nums(nums, _) => nums,
            _ => &[],
        };
        if let Some(&n) = nums.iter().find(|n| !fits_f32(**n)) {
            return Err(SceneError::invalid(
                &*self.path,
                place(field, node),
                format!(
                    "{n} is not a finite number restauro can hold (32-bit float); fix the value"
                ),
            ));
        }
        Ok(Some(nums))
    }

    /// A field of exactly `N` finite numbers (f32 range), or `default` when absent.
    pub fn numbers<const N: usize>(
        &self,
        node: &Node,
        name: &str,
        default: [f64; N],
    ) -> crate::Result<[f64; N]> {
        let Some(nums) = self.finite_list(node, name)? else { return Ok(default) };
        match <[f64; N]>::try_from(nums) {
            Ok(out) => Ok(out),
            Err(_) => Err(self.invalid_field(
                node,
                name,
                format!(
                    "expected {N} number{}, found {}",
                    if N == 1 { "" } else { "s" },
                    nums.len()
                ),
            )),
        }
    }

    /// An error about field `name` of `node`, by its place.
    pub fn invalid_field(&self, node: &Node, name: &str, problem: impl Into<String>) -> SceneError {
        let at = match node.field(name) {
            Some(field) => place(field, node),
            None => format!("`{name}` of {}", of(node)),
        };
        SceneError::invalid(&*self.path, at, problem)
    }

    /// A `TRUE`/`FALSE` field, or `default` when absent.
    pub fn boolean(&self, node: &Node, name: &str, default: bool) -> crate::Result<bool> {
        let Some(field) = node.field(name) else { return Ok(default) };
        match &*field.value {
            Value::Word(w) if w == "TRUE" => Ok(true),
            Value::Word(w) if w == "FALSE" => Ok(false),
            _ => {
                Err(SceneError::invalid(&*self.path, place(field, node), "expected TRUE or FALSE"))
            }
        }
    }

    /// One node instance under the matrix `m`; `name` is the nearest `DEF` name of an
    /// enclosing group, which names the shapes below it.
    pub fn walk(
        &mut self,
        node: &Node,
        m: &Mat,
        name: Option<&str>,
        depth: usize,
    ) -> crate::Result<()> {
        if depth > MAX_DEPTH {
            return Err(depth_limit(&self.path, node.pos, depth));
        }
        // The census has counted these already; this is the backstop.
        self.instances += 1;
        if self.instances > self.max_instances {
            return Err(instances_limit(&self.path, self.instances, self.max_instances));
        }
        let group_name = node.def.as_deref().or(name);
        match node.kind.as_str() {
            "Transform" => {
                let local = self.transform(node)?;
                let m = mul(m, &local);
                self.walk_all(node.nodes("children"), &m, group_name, depth)
            }
            kind if GROUPS.contains(&kind) => {
                self.walk_all(node.nodes("children"), m, group_name, depth)
            }
            "Switch" => {
                let [which] = self.numbers(node, "whichChoice", [-1.0])?;
                let choices = node.nodes("choice");
                match (which >= 0.0).then(|| choices.get(which as usize)).flatten() {
                    Some(child) => self.walk(child, m, group_name, depth + 1),
                    None => Ok(()),
                }
            }
            "LOD" => self.lod(node, m, group_name, depth),
            "Shape" => self.shape(node, m, group_name),
            "Viewpoint" => self.viewpoint(node, m),
            "Inline" if self.inline.is_some() => self.inline(node, m, group_name, depth),
            _ => {
                self.notes.child(node);
                Ok(())
            }
        }
    }

    /// §6.26: every level is kept, each triangle marked with the level it is in; the render
    /// chooses ([`crate::lod`]).
    fn lod(&mut self, node: &Node, m: &Mat, name: Option<&str>, depth: usize) -> crate::Result<()> {
        let levels = node.nodes("level");
        if levels.is_empty() {
            return Ok(());
        }
        let center = self.numbers(node, "center", [0.0; 3])?;
        let ranges = self.finite_list(node, "range")?.unwrap_or(&[]).to_vec();
        if ranges.iter().any(|r| *r < 0.0) || ranges.windows(2).any(|w| w[1] < w[0]) {
            return Err(self.invalid_field(
                node,
                "range",
                "the ranges must be 0 or more and in ascending order (VRML97 §6.26)",
            ));
        }
        let scale = det3(&linear(m)).abs().cbrt();
        let lods = &mut self.mesh.levels;
        if lods.lods.is_empty() {
            // Triangles met before the first LOD lie in none.
            lods.of_triangle = vec![lods.path_index(&[]); self.mesh.triangles.len()];
        }
        let id = lods.lods.len() as u32;
        lods.lods.push(crate::lod::Lod {
            center_m: apply_point(m, center),
            units_per_m: if scale > 0.0 { 1.0 / scale } else { 1.0 },
            ranges,
            levels: levels.len() as u32,
        });
        for (i, child) in levels.iter().enumerate() {
            self.lod_path.push((id, i as u32));
            let walked = self.walk(child, m, name, depth + 1);
            self.lod_path.pop();
            walked?;
        }
        Ok(())
    }

    pub(super) fn walk_all(
        &mut self,
        nodes: &[Rc<Node>],
        m: &Mat,
        name: Option<&str>,
        depth: usize,
    ) -> crate::Result<()> {
        for child in nodes {
            self.walk(child, m, name, depth + 1)?;
        }
        Ok(())
    }

    /// §6.52: `T · C · R · SR · S · SR⁻¹ · C⁻¹`.
    fn transform(&self, node: &Node) -> crate::Result<Mat> {
        let t = self.numbers(node, "translation", [0.0; 3])?;
        let [rx, ry, rz, ra] = self.numbers(node, "rotation", [0.0, 0.0, 1.0, 0.0])?;
        let s = self.numbers(node, "scale", [1.0; 3])?;
        let [sx, sy, sz, sa] = self.numbers(node, "scaleOrientation", [0.0, 0.0, 1.0, 0.0])?;
        let c = self.numbers(node, "center", [0.0; 3])?;
        let mut m = translation(t);
        for factor in [
            translation(c),
            rotation([rx, ry, rz], ra),
            rotation([sx, sy, sz], sa),
            scaling(s),
            rotation([sx, sy, sz], -sa),
            translation(c.map(|x| -x)),
        ] {
            m = mul(&m, &factor);
        }
        Ok(m)
    }

    /// §6.53, carried to the root: position by the matrix, orientation by its rotation part.
    fn viewpoint(&mut self, node: &Node, m: &Mat) -> crate::Result<()> {
        let position = self.numbers(node, "position", [0.0, 0.0, 10.0])?;
        let [x, y, z, a] = self.numbers(node, "orientation", [0.0, 0.0, 1.0, 0.0])?;
        let [fov] = self.numbers(node, "fieldOfView", [std::f64::consts::FRAC_PI_4])?; // §6.53: 0.785398
        let description = match node.field("description").map(|f| &*f.value) {
            Some(Value::Strs(s, _)) => s.first().cloned().unwrap_or_default(),
            _ => String::new(),
        };
        let world = rotation_part(&linear(m));
        let local = linear(&rotation([x, y, z], a));
        let combined: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| world[i][k] * local[k][j]).sum())
        });
        let (axis, angle) = axis_angle(&combined);
        let p = apply_point(m, position);
        if !p.iter().all(|&c| fits_f32(c)) {
            return Err(SceneError::invalid(
                &*self.path,
                format!("{}:{}: Viewpoint", node.pos.line, node.pos.column),
                "its position is not finite once transformed; fix the enclosing Transforms",
            ));
        }
        self.viewpoints.push(Viewpoint {
            position: p,
            orientation: (axis.map(|c| c as f32), angle as f32),
            field_of_view: fov as f32,
            description,
        });
        Ok(())
    }

    /// §6.41: a Shape's appearance names and colours its group; its geometry is drawn if it
    /// is a face set or a primitive, and noted otherwise.
    fn shape(&mut self, node: &Node, m: &Mat, name: Option<&str>) -> crate::Result<()> {
        let name = match name {
            Some(name) => name.to_string(),
            None => format!("shape{}", node.ordinal),
        };
        let appearance = node.first_node("appearance").filter(|a| a.kind == "Appearance");
        if let Some(texture) = appearance.and_then(|a| a.first_node("texture")) {
            self.notes.texture(texture);
        }
        let material =
            appearance.and_then(|a| a.first_node("material")).filter(|m| m.kind == "Material");
        let colour = match material {
            Some(material) if material.field("diffuseColor").is_some() => {
                Some(self.numbers(material, "diffuseColor", [0.8; 3])?.map(|c| c as f32))
            }
            _ => None,
        };
        let Some(geometry) = node.first_node("geometry") else { return Ok(()) };
        if !GEOMETRY.contains(&geometry.kind.as_str()) || geometry.external.is_some() {
            self.notes.geometry(geometry);
            return Ok(());
        }
        let local = self.local(geometry, &name)?;
        self.append(&local, geometry, m, &name, colour)
    }

    /// A geometry node in its own coordinates, worked out once however many times it is
    /// `USE`d.
    fn local(&mut self, node: &Rc<Node>, name: &str) -> crate::Result<Rc<Local>> {
        let key = Rc::as_ptr(node) as usize;
        if let Some(local) = self.cache.get(&key) {
            return Ok(local.clone());
        }
        let local = Rc::new(match node.kind.as_str() {
            "IndexedFaceSet" => self.face_set(node, name)?,
            _ => self.primitive(node, name)?,
        });
        self.cache.insert(key, local.clone());
        Ok(local)
    }

    /// The error for a geometry whose triangles alone pass the limit.
    pub fn too_many_triangles(&self, name: &str) -> SceneError {
        SceneError::Limit {
            path: self.path.to_path_buf(),
            what: format!("the number of triangles of shape `{name}`"),
            value: self.max_triangles + 1,
            limit: self.max_triangles,
            fix: TRIANGLES_FIX.to_string(),
        }
    }

    /// Refuses a geometry of more than 2^32 points (possible only with raised limits): the
    /// mesh indexes its vertices with 32 bits.
    pub fn check_points(&self, node: &Node, points: u64) -> crate::Result<()> {
        if points <= u32::MAX as u64 {
            return Ok(());
        }
        Err(SceneError::Limit {
            path: self.path.to_path_buf(),
            what: format!("the number of points of {}", of(node)),
            value: points,
            limit: u32::MAX as u64,
            fix: "split the geometry into several shapes".to_string(),
        })
    }

    /// `local` placed by `m` and appended to the mesh in the group `name`.
    fn append(
        &mut self,
        local: &Local,
        node: &Node,
        m: &Mat,
        name: &str,
        colour: Option<[f32; 3]>,
    ) -> crate::Result<()> {
        let group = self.mesh.group_index(Group {
            name: name.to_string(),
            colour,
            double_sided: local.double_sided,
            photo: None,
        });
        if let Some(g) = self.mesh.groups.get_mut(group as usize) {
            g.double_sided |= local.double_sided;
            if g.colour.is_none() {
                g.colour = colour;
            }
        }
        let linear_m = linear(m);
        let det = det3(&linear_m);
        if det == 0.0 || !det.is_finite() {
            return Ok(()); // a zero scale flattens the whole shape to nothing
        }
        let total = self.mesh.triangles.len() as u64 + local.triangles.len() as u64;
        if total > self.max_triangles {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!("the number of triangles (counting USE copies) with shape `{name}`"),
                value: total,
                limit: self.max_triangles,
                fix: TRIANGLES_FIX.to_string(),
            });
        }
        let end = self.mesh.positions.len() as u64 + local.vertices.len() as u64;
        if end > u32::MAX as u64 {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: "the number of vertices".to_string(),
                value: end,
                limit: u32::MAX as u64,
                fix: "simplify the model or split it into several files".to_string(),
            });
        }
        let base = self.mesh.positions.len() as u32;
        // Normals go through the inverse transpose; the cofactor matrix is that times det,
        // and the sign keeps them pointing out of the front.
        let normal_m = cofactor(&linear_m).map(|row| row.map(|x| x * det.signum()));
        self.mesh.positions.reserve(local.vertices.len());
        for &(p, n) in &local.vertices {
            let p = apply_point(m, p);
            if !p.iter().all(|&c| fits_f32(c)) {
                return Err(SceneError::invalid(
                    &*self.path,
                    format!(
                        "{}:{}: {} of shape `{name}`",
                        node.pos.line, node.pos.column, node.kind
                    ),
                    "a point is not finite once transformed; fix the enclosing Transforms' values",
                ));
            }
            let n = normalized(apply_linear(&normal_m, n)).unwrap_or(n);
            self.mesh.push_position(p);
            if let Some(normals) = &mut self.mesh.normals {
                normals.push(n.map(|c| c as f32));
            }
        }
        let path = if self.mesh.levels.lods.is_empty() {
            None
        } else {
            Some(self.mesh.levels.path_index(&self.lod_path))
        };
        if let Some(path) = path {
            let n = local.triangles.len();
            self.mesh.levels.of_triangle.extend(std::iter::repeat_n(path, n));
        }
        for &[a, b, c] in &local.triangles {
            // A mirror (negative determinant) turns counter-clockwise faces clockwise.
            let tri = if det < 0.0 { [a, c, b] } else { [a, b, c] };
            self.mesh.triangles.push(tri.map(|v| v + base));
            self.mesh.triangle_group.push(group);
        }
        Ok(())
    }
}
