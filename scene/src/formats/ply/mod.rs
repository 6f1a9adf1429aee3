//! Stanford PLY meshes, ASCII and binary: the `vertex` element's x, y, z (and nx, ny, nz) and
//! the `face` element's `vertex_indices` (or `vertex_index`) lists. Polygons are split into
//! fans. PLY has no materials, so the whole mesh is one part, named after the file. A scan's
//! vertex colours (`red`, `green`, `blue`) are read as sRGB codes, full scale the type's
//! largest value (255 for `uchar`) or 1 for floating point, and decoded to linear.
//!
//! Binary files (what scanners export, and the big ones) are decoded straight into columns
//! ([`crate::formats::ply::binary`]); ASCII files are read with ply-rs, whose element maps cost several
//! hundred bytes a vertex. Both are checked first by [`ply_layout`].

mod binary;
mod layout;

use crate::error::{Result, SceneError};
use crate::guard;
use crate::limits::Limits;
use crate::mesh::{Group, Mesh, unit_or_zero};
use layout::{Encoding, Header};
use ply_rs::parser::Parser;
use ply_rs::ply::{DefaultElement, Property};
use std::path::Path;

/// What a mesh takes from a PLY body, however it was read.
#[derive(Default)]
pub(crate) struct Columns {
    /// Each vertex's x, y, z.
    pub(crate) positions: Vec<[f64; 3]>,
    /// Each vertex's nx, ny, nz, when the vertices have all three.
    pub(crate) normals: Option<Vec<[f64; 3]>>,
    /// Each vertex's red, green, blue over their full scale (0..1 in a sound file), when the
    /// vertices have all three.
    pub(crate) colours: Option<Vec<[f64; 3]>>,
    /// Every face's vertex indices one after another, and where each face's start (one more
    /// entry than there are faces).
    pub(crate) indices: Vec<i64>,
    pub(crate) starts: Vec<usize>,
}

/// The vertex coordinate the vertices lack, or the face list the faces lack: the header says,
/// for every element alike.
fn missing(header: &Header) -> Option<(String, String)> {
    let find = |name: &str| header.elements.iter().find(|e| e.name == name);
    let vertex = find("vertex")?;
    for k in ["x", "y", "z"] {
        if vertex.scalar(k).is_none() && vertex.count > 0 {
            return Some(("vertex 0".into(), format!("no numeric `{k}` property")));
        }
    }
    let face = find("face")?;
    let list = face.face_list().is_some();
    (!list && face.count > 0).then(|| ("face 0".into(), "no `vertex_indices` list".into()))
}

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

fn extend_list(p: &Property, out: &mut Vec<i64>) -> Option<()> {
    match p {
        Property::ListChar(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        Property::ListUChar(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        Property::ListShort(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        Property::ListUShort(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        Property::ListInt(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        Property::ListUInt(v) => out.extend(v.iter().map(|&x| i64::from(x))),
        _ => return None,
    }
    Some(())
}

/// Read PLY bytes. `path` names the file in messages and, by its stem, the mesh's one part.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh> {
    parse_limited(bytes, path, &Limits::default())
}

/// [`parse`] within `limits` (faces, vertices of one polygon).
pub fn parse_limited(bytes: &[u8], path: &Path, limits: &Limits) -> Result<Mesh> {
    // Everything ply-rs would refuse, panic on or loop over is refused first, in words; the
    // binary decoder relies on the same checks.
    let header = layout::read_header(bytes, path)?;
    layout::check_body(&header, bytes, path, limits)?;
    for (name, need) in [
        ("vertex", "a PLY mesh needs vertices with x, y, z"),
        ("face", "restauro needs faces, not a point cloud"),
    ] {
        if !header.elements.iter().any(|e| e.name == name) {
            return Err(SceneError::invalid(
                path,
                "header",
                format!("no `{name}` element; {need}"),
            ));
        }
    }
    if let Some((place, problem)) = missing(&header) {
        return Err(SceneError::invalid(path, place, problem));
    }
    let columns = match header.encoding {
        Encoding::Ascii => ascii_columns(bytes, path, &header)?,
        Encoding::BigEndian | Encoding::LittleEndian => {
            crate::formats::ply::binary::decode(&header, bytes)
        }
    };
    mesh_of(columns, path)
}

/// The columns of an ASCII file, read with ply-rs.
fn ascii_columns(bytes: &[u8], path: &Path, header: &Header) -> Result<Columns> {
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
    let empty = Vec::new();
    let vertices = ply.payload.get("vertex").unwrap_or(&empty);
    let faces = ply.payload.get("face").unwrap_or(&empty);
    let mut c = Columns::default();
    let mut normals = Vec::with_capacity(vertices.len());
    let colour = header.elements.iter().find(|e| e.name == "vertex").and_then(|e| e.colour());
    let mut colours = Vec::with_capacity(if colour.is_some() { vertices.len() } else { 0 });
    for v in vertices {
        let get = |k: &str| v.get(k).and_then(number);
        // `missing` made sure every vertex has them.
        c.positions.push(["x", "y", "z"].map(|k| get(k).unwrap_or(f64::NAN)));
        normals.push(["nx", "ny", "nz"].map(get));
        if let Some((_, names, full)) = colour {
            colours.push(names.map(|k| get(k).unwrap_or(f64::NAN) / full));
        }
    }
    if normals.iter().all(|n| n.iter().all(Option::is_some)) {
        c.normals = Some(normals.iter().map(|n| n.map(|x| x.unwrap_or(0.0))).collect());
    }
    c.colours = colour.map(|_| colours);
    c.starts.push(0);
    for f in faces {
        let list = f.get("vertex_indices").or_else(|| f.get("vertex_index"));
        list.and_then(|l| extend_list(l, &mut c.indices));
        c.starts.push(c.indices.len());
    }
    Ok(c)
}

/// The mesh of the columns: each polygon a fan of triangles, its indices checked.
fn mesh_of(c: Columns, path: &Path) -> Result<Mesh> {
    let mut mesh = Mesh {
        positions: Vec::with_capacity(c.positions.len()),
        // nx, ny, nz (the names scanners write, as the Stanford format's examples do).
        normals: c.normals.map(|n| n.iter().map(|v| unit_or_zero(v.map(|x| x as f32))).collect()),
        ..Mesh::default()
    };
    for &p in &c.positions {
        mesh.push_position(p);
    }
    if let Some(colours) = &c.colours {
        mesh.colours = Some(linear_colours(colours, path)?);
    }
    mesh.drop_flat_normals();
    // One part, named as an OBJ's part without groups: not after the file, whose name a
    // bundle replaces by its hash.
    let group = mesh.group_index(Group::named("default"));
    let n = mesh.positions.len() as i64;
    mesh.triangles.reserve(c.indices.len().saturating_sub(2 * c.starts.len()));
    for (i, w) in c.starts.windows(2).enumerate() {
        let indices = &c.indices[w[0]..w[1]];
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
        }
    }
    mesh.triangle_group = vec![group; mesh.triangles.len()];
    Ok(mesh)
}

/// The vertices' colours (over full scale) decoded from sRGB to linear; a colour outside its
/// type's range (a float beyond 0..1, a negative or a NaN) is refused, by vertex.
fn linear_colours(colours: &[[f64; 3]], path: &Path) -> Result<Vec<[f32; 3]>> {
    use restauro_spectral::rgb_space::Transfer;
    if let Some((i, rgb)) =
        colours.iter().enumerate().find(|(_, rgb)| !rgb.iter().all(|c| (0.0..=1.0).contains(c)))
    {
        return Err(SceneError::invalid(
            path,
            format!("vertex {i}"),
            format!(
                "colour {rgb:?} over full scale is outside 0 to 1: vertex colours are 0 to 255 \
                 (uchar), 0 to 65535 (ushort) or 0 to 1 (float); write them in one of these"
            ),
        ));
    }
    Ok(colours.iter().map(|rgb| rgb.map(|c| Transfer::Srgb.decode(c) as f32)).collect())
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

    /// The binary decoder reads what ply-rs reads from the same mesh written as ASCII, in both
    /// byte orders, skipping the properties it does not need (a colour, a face's flags).
    #[test]
    fn binary_files_read_as_their_ascii_twin() {
        let vertices: [([f32; 3], [f64; 3], u8); 4] = [
            ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 10),
            ([2.0, 0.0, 0.5], [0.0, 0.6, 0.8], 20),
            ([2.0, 3.0, 0.0], [0.0, 0.0, 2.0], 30),
            ([0.0, 3.0, 1.0], [1.0, 0.0, 0.0], 40),
        ];
        let faces: [&[i32]; 2] = [&[0, 1, 2, 3], &[3, 2, 1]];
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                 property float z\nproperty uchar red\nproperty double nx\nproperty double ny\n\
                 property double nz\nelement face 2\nproperty uchar flags\n\
                 property list uchar int vertex_indices\nend_header\n"
            )
        };
        let mut ascii = header("ascii");
        for (p, n, r) in vertices {
            ascii += &format!("{} {} {} {r} {} {} {}\n", p[0], p[1], p[2], n[0], n[1], n[2]);
        }
        for f in faces {
            let list: Vec<String> = f.iter().map(i32::to_string).collect();
            ascii += &format!("7 {} {}\n", f.len(), list.join(" "));
        }
        let binary = |big: bool| {
            let order = if big { "binary_big_endian" } else { "binary_little_endian" };
            let mut b = header(order).into_bytes();
            let put = |bytes: &mut [u8], b: &mut Vec<u8>| {
                if big {
                    bytes.reverse();
                }
                b.extend_from_slice(bytes);
            };
            for (p, n, r) in vertices {
                for c in p {
                    put(&mut c.to_le_bytes(), &mut b);
                }
                b.push(r);
                for c in n {
                    put(&mut c.to_le_bytes(), &mut b);
                }
            }
            for f in faces {
                b.extend_from_slice(&[7, f.len() as u8]);
                for &i in f {
                    put(&mut i.to_le_bytes(), &mut b);
                }
            }
            b
        };
        let twin = parse(ascii.as_bytes(), Path::new("a.ply")).unwrap();
        assert_eq!(twin.triangles, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
        assert_eq!(twin.normals.as_ref().unwrap()[2], [0.0, 0.0, 1.0]);
        for big in [false, true] {
            let mesh = parse(&binary(big), Path::new("b.ply")).unwrap();
            assert_eq!(mesh.positions, twin.positions, "big-endian: {big}");
            assert_eq!(mesh.normals, twin.normals, "big-endian: {big}");
            assert_eq!(mesh.triangles, twin.triangles, "big-endian: {big}");
        }
    }

    /// A scan's vertex colours: 8-bit sRGB codes (ASCII, or binary in either type the
    /// Stanford scans and MeshLab write) and floats over 0..1, decoded to linear with
    /// IEC 61966-2-1's function (a code of 128 is 0.2158605 linear, 255 is 1, 0 is 0).
    #[test]
    fn vertex_colours_are_read_as_srgb() {
        let header = |kind: &str, prefix: &str, format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty {kind} {prefix}red\nproperty {kind} {prefix}green\n\
                 property {kind} {prefix}blue\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n"
            )
        };
        let expected = [[1.0, 0.0, 0.215_860_5], [0.0; 3], [0.215_860_5; 3]];
        let close = |m: &Mesh| {
            let c = m.colours.as_ref().expect("colours");
            c.iter().flatten().zip(expected.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-6)
        };
        let ascii = header("uchar", "", "ascii")
            + "0 0 0 255 0 128\n1 0 0 0 0 0\n0 1 0 128 128 128\n3 0 1 2\n";
        assert!(close(&parse(ascii.as_bytes(), Path::new("c.ply")).unwrap()));
        let floats = header("float", "diffuse_", "ascii")
            + "0 0 0 1 0 0.50196078\n1 0 0 0 0 0\n0 1 0 0.50196078 0.50196078 0.50196078\n3 0 1 2\n";
        assert!(close(&parse(floats.as_bytes(), Path::new("f.ply")).unwrap()));
        let mut binary = header("uchar", "", "binary_little_endian").into_bytes();
        for (p, c) in [
            ([0.0f32, 0.0, 0.0], [255u8, 0, 128]),
            ([1.0, 0.0, 0.0], [0; 3]),
            ([0.0, 1.0, 0.0], [128; 3]),
        ] {
            p.iter().for_each(|v| binary.extend_from_slice(&v.to_le_bytes()));
            binary.extend_from_slice(&c);
        }
        binary.push(3);
        [0i32, 1, 2].iter().for_each(|i| binary.extend_from_slice(&i.to_le_bytes()));
        assert!(close(&parse(&binary, Path::new("b.ply")).unwrap()));
        // Two channels of three are no colour.
        let partial = ascii
            .replace("property uchar blue\n", "")
            .replace(" 128\n1", "\n1")
            .replace("0 0 0\n0 1", "0 0\n0 1")
            .replace("128 128 128", "128 128");
        assert_eq!(parse(partial.as_bytes(), Path::new("p.ply")).unwrap().colours, None);
        let bright = floats.replace("0 0 0 1 0 0.50196078", "0 0 0 1.5 0 0.5");
        let err = parse(bright.as_bytes(), Path::new("bright.ply")).unwrap_err().to_string();
        assert!(err.starts_with("bright.ply: vertex 0: colour [1.5, 0.0, 0.5]"), "{err}");
        assert!(err.contains("0 to 255 (uchar)"), "{err}");
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
