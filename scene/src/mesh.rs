//! A triangle mesh as restauro renders it, whatever file it came from.

/// A named part of a mesh: the mesh file's own material or group name, which a scene binds to
/// one of its materials.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    pub name: String,
    /// A colour the file gives the part (OBJ `Kd`, VRML `Material.diffuseColor`, glTF
    /// `baseColorFactor`), linear 0..1: a fallback when the scene binds no spectrum.
    pub colour: Option<[f32; 3]>,
    /// Whether both sides of the faces are visible (VRML `solid FALSE`, glTF `doubleSided`).
    pub double_sided: bool,
    /// The photo the file lays on the part (glTF `baseColorTexture`): detail over the
    /// spectrum the scene binds it to, unless the scene's material gives its own.
    pub photo: Option<std::sync::Arc<crate::texture::Texture>>,
}

impl Group {
    pub fn named(name: impl Into<String>) -> Self {
        Self { name: name.into(), colour: None, double_sided: false, photo: None }
    }
}

/// Beyond this distance from zero (m), a file's coordinates are stored relative to an
/// [`Mesh::anchor_m`]: a 32-bit float there still resolves 0.06 mm, where at a survey's
/// 5 000 000 m it resolves only 0.5 m.
pub const ANCHOR_BEYOND_M: f64 = 1000.0;

/// Triangles with counter-clockwise front faces (seen from the front, in a right-handed
/// coordinate system), in metres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The point (in the file's own coordinates, m) that `positions` are relative to: zero,
    /// unless the file is georeferenced (its first vertex beyond [`ANCHOR_BEYOND_M`]); then
    /// the whole metres of that vertex. The scene's placement takes it back out in 64-bit
    /// arithmetic, so survey coordinates lose nothing on the way to 32 bits.
    pub anchor_m: [f64; 3],
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals, when the file gives or implies them (same length as
    /// `positions`; unit length, or zero at a vertex that has none, whose triangles are then
    /// shaded flat).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per-vertex texture coordinates when the file gives them (same length as `positions`),
    /// in glTF's convention: (0, 0) the image's top-left corner, v downwards (OBJ's v, which
    /// counts from the bottom, is turned over as it is read). NaN at a vertex that has none.
    pub texcoords: Option<Vec<[f32; 2]>>,
    /// Per-vertex colours when the file gives them (PLY `red`, `green`, `blue`, its sRGB codes
    /// decoded by IEC 61966-2-1; glTF `COLOR_0`), linear sRGB 0..1. Like a photo, detail over
    /// the spectrum the scene binds the part to, never an albedo. NaN at a vertex that has none.
    pub colours: Option<Vec<[f32; 3]>>,
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, its index in `groups`.
    pub triangle_group: Vec<u32>,
    pub groups: Vec<Group>,
    /// Levels of detail (VRML97 `LOD`): every level is kept; a render shows those its camera
    /// calls for.
    pub levels: crate::lod::Levels,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

impl Mesh {
    /// The index of the group called `name`, added if new.
    pub fn group_index(&mut self, group: Group) -> u32 {
        match self.groups.iter().position(|g| g.name == group.name) {
            Some(i) => i as u32,
            None => {
                self.groups.push(group);
                (self.groups.len() - 1) as u32
            }
        }
    }

    /// Add a vertex given in the file's coordinates (m); the first one beyond
    /// [`ANCHOR_BEYOND_M`] in a mesh with no vertices yet sets the anchor.
    pub fn push_position(&mut self, p: [f64; 3]) {
        if self.positions.is_empty() && p.iter().any(|c| c.abs() > ANCHOR_BEYOND_M) {
            self.anchor_m = p.map(|c| if c.is_finite() { c.round() } else { 0.0 });
        }
        self.positions.push(std::array::from_fn(|k| (p[k] - self.anchor_m[k]) as f32));
    }

    /// A vertex in the file's coordinates (m), in 64 bits.
    pub fn position_m(&self, i: usize) -> [f64; 3] {
        let p = self.positions[i];
        std::array::from_fn(|k| self.anchor_m[k] + f64::from(p[k]))
    }

    /// The bounding box of the vertices that triangles use; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<Bounds> {
        let mut iter = self.triangles.iter().flatten().map(|&i| self.positions[i as usize]);
        let first = iter.next()?;
        Some(iter.fold(Bounds { min: first, max: first }, |b, p| Bounds {
            min: std::array::from_fn(|k| b.min[k].min(p[k])),
            max: std::array::from_fn(|k| b.max[k].max(p[k])),
        }))
    }

    /// The number of triangles in each group, by name, sorted by name.
    pub fn triangles_per_group(&self) -> Vec<(String, usize)> {
        let mut counts = vec![0usize; self.groups.len()];
        for &g in &self.triangle_group {
            counts[g as usize] += 1;
        }
        let mut out: Vec<(String, usize)> =
            self.groups.iter().map(|g| g.name.clone()).zip(counts).collect();
        out.sort();
        out
    }

    /// Forget the normals when no vertex has one: the mesh is flat. The same for texture
    /// coordinates.
    pub fn drop_flat_normals(&mut self) {
        if self.normals.as_ref().is_some_and(|n| n.iter().all(|v| *v == [0.0; 3])) {
            self.normals = None;
        }
        if self.texcoords.as_ref().is_some_and(|t| t.iter().all(|uv| uv[0].is_nan())) {
            self.texcoords = None;
        }
        if self.colours.as_ref().is_some_and(|c| c.iter().all(|rgb| rgb[0].is_nan())) {
            self.colours = None;
        }
    }

    /// Whether every vertex of every triangle of group `group` has texture coordinates.
    pub fn group_has_texcoords(&self, group: u32) -> bool {
        let Some(uv) = &self.texcoords else { return false };
        let finite = |i: u32| uv[i as usize].iter().all(|c| c.is_finite());
        self.triangles
            .iter()
            .zip(&self.triangle_group)
            .filter(|(_, g)| **g == group)
            .all(|(t, _)| t.iter().all(|&i| finite(i)))
    }

    /// Per group, whether every vertex of every one of its triangles has a colour (in one pass
    /// over the triangles, however many groups there are).
    pub fn coloured_groups(&self) -> Vec<bool> {
        let mut out = vec![self.colours.is_some(); self.groups.len()];
        let Some(colours) = &self.colours else { return out };
        let coloured = |i: &u32| colours[*i as usize].iter().all(|c| c.is_finite());
        for (t, &g) in self.triangles.iter().zip(&self.triangle_group) {
            if out[g as usize] && !t.iter().all(coloured) {
                out[g as usize] = false;
            }
        }
        out
    }

    /// Append another mesh, keeping group names unique (parts with the same name merge).
    pub fn append(&mut self, other: &Mesh) {
        if self.positions.is_empty() {
            self.anchor_m = other.anchor_m;
        }
        let base = self.positions.len() as u32;
        let remap: Vec<u32> = other.groups.iter().map(|g| self.group_index(g.clone())).collect();
        let (len, more) = (self.positions.len(), other.positions.len());
        // A part without normals keeps its flat faces beside one with them (zero normals); a
        // part without texture coordinates or colours beside one with them: NaN, none.
        extend_attribute(&mut self.normals, &other.normals, (len, more), [0.0; 3]);
        extend_attribute(&mut self.texcoords, &other.texcoords, (len, more), [f32::NAN; 2]);
        extend_attribute(&mut self.colours, &other.colours, (len, more), [f32::NAN; 3]);
        if other.anchor_m == self.anchor_m {
            self.positions.extend_from_slice(&other.positions);
        } else {
            // Moved onto this mesh's anchor in 64 bits.
            let shift: [f64; 3] = std::array::from_fn(|k| other.anchor_m[k] - self.anchor_m[k]);
            self.positions.extend(
                other
                    .positions
                    .iter()
                    .map(|p| std::array::from_fn(|k| (f64::from(p[k]) + shift[k]) as f32)),
            );
        }
        self.append_levels(other);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        self.triangle_group.extend(other.triangle_group.iter().map(|&g| remap[g as usize]));
    }
}

impl Mesh {
    /// `other`'s levels of detail after this mesh's (call before its triangles are added).
    fn append_levels(&mut self, other: &Mesh) {
        if self.levels.lods.is_empty() && other.levels.lods.is_empty() {
            return;
        }
        if self.levels.of_triangle.is_empty() {
            self.levels.of_triangle = vec![self.levels.path_index(&[]); self.triangles.len()];
        }
        let first = self.levels.lods.len() as u32;
        self.levels.lods.extend(other.levels.lods.iter().cloned());
        let remap: Vec<u32> = other
            .levels
            .paths
            .iter()
            .map(|p| {
                let moved: Vec<(u32, u32)> = p.iter().map(|&(l, v)| (l + first, v)).collect();
                self.levels.path_index(&moved)
            })
            .collect();
        let empty = self.levels.path_index(&[]);
        match other.levels.of_triangle.is_empty() {
            true => {
                self.levels.of_triangle.extend(std::iter::repeat_n(empty, other.triangles.len()))
            }
            false => self
                .levels
                .of_triangle
                .extend(other.levels.of_triangle.iter().map(|&p| remap[p as usize])),
        }
    }
}

/// A per-vertex attribute of `len` vertices followed by `more` vertices' `other`, `none` for
/// the vertices of the side without it; still `None` when neither side has it.
fn extend_attribute<T: Copy>(
    mine: &mut Option<Vec<T>>,
    other: &Option<Vec<T>>,
    (len, more): (usize, usize),
    none: T,
) {
    match (mine.as_mut(), other) {
        (Some(a), Some(b)) => a.extend_from_slice(b),
        (Some(a), None) => a.resize(len + more, none),
        (None, Some(b)) => {
            let mut a = vec![none; len];
            a.extend_from_slice(b);
            *mine = Some(a);
        }
        (None, None) => {}
    }
}

/// `v` scaled to unit length, or zero when it has no direction (zero, or not finite): a
/// vertex normal that cannot shade.
pub fn unit_or_zero(v: [f32; 3]) -> [f32; 3] {
    let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if length.is_finite() && length > 1e-12 { v.map(|c| c / length) } else { [0.0; 3] }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(z: f32, normals: Option<[f32; 3]>) -> Mesh {
        let mut m = Mesh {
            positions: vec![[0.0, 0.0, z], [1.0, 0.0, z], [0.0, 1.0, z]],
            normals: normals.map(|n| vec![n; 3]),
            triangles: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        m.triangle_group = vec![m.group_index(Group::named("part"))];
        m
    }

    /// Appending a flat mesh to a smooth one, or the other way, keeps the smooth one's normals
    /// and gives the flat one zeros: neither loses its shading.
    #[test]
    fn smooth_and_flat_parts_keep_their_shading_when_appended() {
        let up = [0.0, 0.0, 1.0];
        let mut a = triangle(0.0, Some(up));
        a.append(&triangle(1.0, None));
        assert_eq!(a.normals, Some(vec![up, up, up, [0.0; 3], [0.0; 3], [0.0; 3]]));
        let mut b = triangle(0.0, None);
        b.append(&triangle(1.0, Some(up)));
        assert_eq!(b.normals, Some(vec![[0.0; 3], [0.0; 3], [0.0; 3], up, up, up]));
        let mut c = triangle(0.0, None);
        c.append(&triangle(1.0, None));
        assert_eq!(c.normals, None);
        assert_eq!(unit_or_zero([0.0, 3.0, 4.0]), [0.0, 0.6, 0.8]);
        assert_eq!(unit_or_zero([f32::NAN, 0.0, 1.0]), [0.0; 3]);
    }
}
