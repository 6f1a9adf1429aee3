//! The geometry primitives of §6 tessellated: Box (§6.7), Cone (§6.11), Cylinder (§6.14),
//! ElevationGrid (§6.17), Sphere (§6.43); Extrusion (§6.18) is in [`super::extrusion`].
//!
//! Every primitive is centred as its section says and has counter-clockwise, outward-facing
//! triangles (the Box, Cone, Cylinder and Sphere are solids seen from outside, §6.7 ff.);
//! normals are the exact ones of the curved surface at each vertex, and flat on caps and box
//! faces. Their triangle counts are known from the fields alone ([`triangle_bound`]), so the
//! census refuses a hostile size before anything is allocated.

use std::f64::consts::{PI, TAU};

use super::builder::Builder;
use super::faces::{Faces, Local, Rules, triangulate_faces};
use super::math::{V3, normalized};
use super::parser::{Node, Value};

/// Segments around a Cone and a Cylinder: the caps' area is within 0.7 % of the circle's.
pub(super) const SEGMENTS: usize = 32;
/// Rings of latitude and slices of longitude of a Sphere (its area is within 1 % of 4πr²).
pub(super) const STACKS: usize = 16;
pub(super) const SLICES: usize = 32;

/// The triangles a primitive makes at most, and how that is worked out; `None` for a node
/// that is not a primitive. Reads only counts, so a file's worth of sizes costs nothing.
pub(super) fn triangle_bound(node: &Node) -> Option<(u64, &'static str)> {
    let n = SEGMENTS as u64;
    Some(match node.kind.as_str() {
        "Box" => (12, "a box"),
        "Sphere" => (2 * SLICES as u64 * (STACKS as u64 - 1), "its tessellation"),
        "Cone" => (n + n - 2, "its tessellation"),
        "Cylinder" => (2 * n + 2 * (n - 2), "its tessellation"),
        "ElevationGrid" => {
            let x = first_count(node, "xDimension");
            let z = first_count(node, "zDimension");
            let quads = x.saturating_sub(1).saturating_mul(z.saturating_sub(1));
            (quads.saturating_mul(2), "2 × (xDimension − 1) × (zDimension − 1)")
        }
        "Extrusion" => {
            let spine = list_len(node, "spine", 3, 2);
            let section = list_len(node, "crossSection", 2, 5);
            let sides = spine.saturating_sub(1).saturating_mul(section.saturating_sub(1));
            let caps = 2 * section.saturating_sub(2);
            (sides.saturating_mul(2).saturating_add(caps), "from its spine and crossSection")
        }
        _ => return None,
    })
}

/// The first number of a field as a count (0 when absent, negative or not a number: the
/// builder refuses those with their place).
fn first_count(node: &Node, name: &str) -> u64 {
    match node.field(name).map(|f| &*f.value) {
        Some(Value::Nums(nums, _)) => match nums.first() {
            Some(&n) if n >= 0.0 && n.is_finite() => n as u64,
            _ => 0,
        },
        _ => 0,
    }
}

/// How many values of `arity` numbers a field holds (`default` when absent).
fn list_len(node: &Node, name: &str, arity: usize, default: u64) -> u64 {
    match node.field(name).map(|f| &*f.value) {
        Some(Value::Nums(nums, _)) => (nums.len() / arity) as u64,
        Some(_) => 0,
        None => default,
    }
}

impl Builder<'_> {
    /// A primitive geometry node in its own coordinates.
    pub(super) fn primitive(&self, node: &Node, name: &str) -> crate::Result<Local> {
        match node.kind.as_str() {
            "Box" => {
                let size = self.numbers(node, "size", [2.0; 3])?;
                for s in size {
                    self.check_positive(node, "size", s, "each of its x, y and z sizes")?;
                }
                Ok(box_local(size))
            }
            "Sphere" => Ok(sphere(self.positive(node, "radius", 1.0)?)),
            "Cylinder" => Ok(cylinder(
                self.positive(node, "radius", 1.0)?,
                self.positive(node, "height", 2.0)?,
                [
                    self.boolean(node, "side", true)?,
                    self.boolean(node, "top", true)?,
                    self.boolean(node, "bottom", true)?,
                ],
            )),
            "Cone" => Ok(cone(
                self.positive(node, "bottomRadius", 1.0)?,
                self.positive(node, "height", 2.0)?,
                self.boolean(node, "side", true)?,
                self.boolean(node, "bottom", true)?,
            )),
            "ElevationGrid" => self.elevation_grid(node, name),
            _ => self.extrusion(node, name),
        }
    }

    /// A size field (one number), greater than 0 as §6 requires.
    pub(super) fn positive(&self, node: &Node, name: &str, default: f64) -> crate::Result<f64> {
        let [value] = self.numbers(node, name, [default])?;
        self.check_positive(node, name, value, "it")?;
        Ok(value)
    }

    pub(super) fn check_positive(
        &self,
        node: &Node,
        name: &str,
        value: f64,
        what: &str,
    ) -> crate::Result<()> {
        if value > 0.0 {
            return Ok(());
        }
        Err(self.invalid_field(
            node,
            name,
            format!(
                "{value} is not a size: {what} must be greater than 0 (ISO/IEC 14772-1 §6); give \
                 a positive value, or remove the shape"
            ),
        ))
    }

    /// A whole number ≥ 0 (an SFInt32 count).
    fn count(&self, node: &Node, name: &str) -> crate::Result<usize> {
        let [value] = self.numbers(node, name, [0.0])?;
        if value < 0.0 || value.fract() != 0.0 {
            return Err(self.invalid_field(
                node,
                name,
                format!("{value} is not a count; give a whole number of 0 or more"),
            ));
        }
        Ok(value as usize)
    }

    /// §6.17: a grid of `xDimension` × `zDimension` heights in the XZ plane, height along +Y;
    /// point (i, j) is at (xSpacing·i, height[i + j·xDimension], zSpacing·j).
    fn elevation_grid(&self, node: &Node, name: &str) -> crate::Result<Local> {
        let (nx, nz) = (self.count(node, "xDimension")?, self.count(node, "zDimension")?);
        let dx = self.positive(node, "xSpacing", 1.0)?;
        let dz = self.positive(node, "zSpacing", 1.0)?;
        let heights = self.finite_list(node, "height")?.unwrap_or(&[]);
        // The census has bounded nx·nz − nx − nz by the triangle limit, so this cannot
        // overflow for any grid that has quads; the heights are the file's own numbers.
        let expected = nx.saturating_mul(nz);
        if heights.len() != expected {
            return Err(self.invalid_field(
                node,
                "height",
                format!(
                    "{} heights for a grid of xDimension {nx} × zDimension {nz} = {expected} \
                     points; give one height per point (row after row of x)",
                    heights.len()
                ),
            ));
        }
        self.check_points(node, heights.len() as u64)?;
        let rules = Rules {
            convex: true,
            crease: self.numbers(node, "creaseAngle", [0.0])?[0],
            solid: self.boolean(node, "solid", true)?,
        };
        let ccw = self.boolean(node, "ccw", true)?;
        let (points, faces) = grid(nx, nz, dx, dz, heights, ccw);
        triangulate_faces(&points, &faces, rules, self.max_triangles)
            .ok_or_else(|| self.too_many_triangles(name))
    }
}

/// The points and quads of an ElevationGrid. With `ccw`, the quads turn counter-clockwise
/// seen from +Y, so the normal of a flat grid is +Y (§6.17); without, they turn the other way.
pub(super) fn grid(
    nx: usize,
    nz: usize,
    dx: f64,
    dz: f64,
    heights: &[f64],
    ccw: bool,
) -> (Vec<V3>, Faces) {
    let mut points = Vec::with_capacity(heights.len());
    for j in 0..nz {
        for i in 0..nx {
            points.push([dx * i as f64, heights[i + j * nx], dz * j as f64]);
        }
    }
    let mut faces = Faces::default();
    let at = |i: usize, j: usize| (i + j * nx) as u32;
    for j in 0..nz.saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            // (i, j) → (i, j+1) → (i+1, j+1): +Z then +X, which turns about +Y.
            let quad = [at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)];
            if ccw {
                faces.push(quad);
            } else {
                faces.push(quad.into_iter().rev());
            }
        }
    }
    (points, faces)
}

/// §6.7: a box of `size`, centred on the origin, faces flat.
pub(super) fn box_local(size: V3) -> Local {
    let h = size.map(|s| s / 2.0);
    let points: Vec<V3> = (0..8)
        .map(|k: usize| {
            // Corners in the order (−,−,−), (+,−,−), (+,+,−), (−,+,−), then the same at +z.
            let x = if matches!(k % 4, 1 | 2) { h[0] } else { -h[0] };
            let y = if matches!(k % 4, 2 | 3) { h[1] } else { -h[1] };
            let z = if k >= 4 { h[2] } else { -h[2] };
            [x, y, z]
        })
        .collect();
    let mut faces = Faces::default();
    // Each face counter-clockwise seen from outside: −z, +z, −y, +y, −x, +x.
    for face in [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [3, 7, 6, 2], [0, 4, 7, 3], [1, 2, 6, 5]]
    {
        faces.push(face);
    }
    let rules = Rules { convex: true, crease: 0.0, solid: true };
    triangulate_faces(&points, &faces, rules, u64::MAX).unwrap_or_default()
}

/// The point at angle `phi` around +Y, at `radius` and height `y`: φ = 0 is +Z, and φ grows
/// towards +X, counter-clockwise seen from +Y.
fn around(radius: f64, phi: f64, y: f64) -> V3 {
    [radius * phi.sin(), y, radius * phi.cos()]
}

fn angle(j: usize, n: usize) -> f64 {
    TAU * (j % n) as f64 / n as f64
}

/// §6.43: a sphere of `radius` centred on the origin, its normals the radii.
pub(super) fn sphere(radius: f64) -> Local {
    let mut local = Local::default();
    let (s, l) = (STACKS, SLICES);
    let top = local.vertex([0.0, radius, 0.0], [0.0, 1.0, 0.0]);
    for i in 1..s {
        let theta = PI * i as f64 / s as f64;
        for j in 0..l {
            let unit = around(theta.sin(), angle(j, l), theta.cos());
            local.vertex(unit.map(|c| c * radius), unit);
        }
    }
    let bottom = local.vertex([0.0, -radius, 0.0], [0.0, -1.0, 0.0]);
    let at = |i: usize, j: usize| (1 + (i - 1) * l + j % l) as u32;
    // Going down a meridian (θ) then east (φ) turns counter-clockwise seen from outside.
    for j in 0..l {
        local.triangles.push([top, at(1, j), at(1, j + 1)]);
        for i in 1..s - 1 {
            local.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            local.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
        local.triangles.push([at(s - 1, j), bottom, at(s - 1, j + 1)]);
    }
    local
}

/// A disc of `SEGMENTS` corners at height `y`, facing +Y (`up`) or −Y.
fn cap(local: &mut Local, radius: f64, y: f64, up: bool) {
    let normal = [0.0, if up { 1.0 } else { -1.0 }, 0.0];
    let first = local.vertices.len() as u32;
    for j in 0..SEGMENTS {
        local.vertex(around(radius, angle(j, SEGMENTS), y), normal);
    }
    for k in 1..SEGMENTS as u32 - 1 {
        let (b, c) = (first + k, first + k + 1);
        // Increasing φ turns counter-clockwise seen from +Y.
        local.triangles.push(if up { [first, b, c] } else { [first, c, b] });
    }
}

/// §6.14: a cylinder about the Y axis, centred on the origin; `[side, top, bottom]` say which
/// parts exist.
pub(super) fn cylinder(radius: f64, height: f64, [side, top, bottom]: [bool; 3]) -> Local {
    let mut local = Local::default();
    let h = height / 2.0;
    if side {
        for j in 0..SEGMENTS {
            let phi = angle(j, SEGMENTS);
            local.vertex(around(radius, phi, -h), around(1.0, phi, 0.0));
            local.vertex(around(radius, phi, h), around(1.0, phi, 0.0));
        }
        for j in 0..SEGMENTS {
            let (b0, t0) = (2 * j as u32, 2 * j as u32 + 1);
            let (b1, t1) = (2 * ((j + 1) % SEGMENTS) as u32, 2 * ((j + 1) % SEGMENTS) as u32 + 1);
            local.triangles.push([b0, b1, t1]);
            local.triangles.push([b0, t1, t0]);
        }
    }
    if top {
        cap(&mut local, radius, h, true);
    }
    if bottom {
        cap(&mut local, radius, -h, false);
    }
    local
}

/// §6.11: a cone about the Y axis, its apex at +height/2 and its base at −height/2.
pub(super) fn cone(radius: f64, height: f64, side: bool, bottom: bool) -> Local {
    let mut local = Local::default();
    let h = height / 2.0;
    if side {
        // The outward normal of the side at angle φ: (h·sin φ, r, h·cos φ), normalised.
        let normal = |phi: f64| {
            normalized([height * phi.sin(), radius, height * phi.cos()]).unwrap_or([0.0, 1.0, 0.0])
        };
        for j in 0..SEGMENTS {
            let (phi0, phi1) = (angle(j, SEGMENTS), angle(j + 1, SEGMENTS));
            let a = local.vertex(around(radius, phi0, -h), normal(phi0));
            let b = local.vertex(around(radius, phi1, -h), normal(phi1));
            let mid = TAU * (j as f64 + 0.5) / SEGMENTS as f64;
            let apex = local.vertex([0.0, h, 0.0], normal(mid));
            local.triangles.push([a, b, apex]);
        }
    }
    if bottom {
        cap(&mut local, radius, -h, false);
    }
    local
}
