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
}

impl Group {
    pub fn named(name: impl Into<String>) -> Self {
        Self { name: name.into(), colour: None, double_sided: false }
    }
}

/// Triangles with counter-clockwise front faces (seen from the front, in a right-handed
/// coordinate system), in metres.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals, when the file gives or implies them (same length as
    /// `positions`).
    pub normals: Option<Vec<[f32; 3]>>,
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, its index in `groups`.
    pub triangle_group: Vec<u32>,
    pub groups: Vec<Group>,
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

    /// Append another mesh, keeping group names unique (parts with the same name merge).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        let remap: Vec<u32> = other.groups.iter().map(|g| self.group_index(g.clone())).collect();
        match (&mut self.normals, &other.normals) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (a @ Some(_), None) => *a = None,
            (None, Some(_)) if self.positions.is_empty() => self.normals = other.normals.clone(),
            _ => {}
        }
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        self.triangle_group.extend(other.triangle_group.iter().map(|&g| remap[g as usize]));
    }
}
