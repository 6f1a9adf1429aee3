//! A survey-sized mesh made on the spot: a relief of `nx × ny` quads (two triangles each) over
//! 50 m × 25 m, standing in the XZ plane and up to 2 m deep, as binary PLY — the format scanners
//! export. The studio's tests of big models and `restauro bench mesh` read it.

use std::io::{self, Write};

/// Writes the relief of `nx × ny` quads as binary little-endian PLY.
pub fn write_ply(out: &mut impl Write, nx: usize, ny: usize) -> io::Result<()> {
    let vertices = (nx + 1) * (ny + 1);
    let faces = 2 * nx * ny;
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n"
    )?;
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, z) = (50.0 * i as f32 / nx as f32, 25.0 * j as f32 / ny as f32);
            let y = -(2.0 * ((x * 1.3).sin() * (z * 0.7).cos()).abs());
            for v in [x - 25.0, y, z] {
                out.write_all(&v.to_le_bytes())?;
            }
        }
    }
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as i32;
    for j in 0..ny {
        for i in 0..nx {
            for t in [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ] {
                out.write_all(&[3u8])?;
                for v in t {
                    out.write_all(&v.to_le_bytes())?;
                }
            }
        }
    }
    Ok(())
}

/// A scene of the relief in one stone under the summer sun, seen from 60 m in front, for a
/// `relief.ply` beside it.
pub const SCENE_TOML: &str = "format = 1\n[camera]\nposition = [0.0, -60.0, 12.0]\n\
    target = [0.0, 0.0, 12.0]\nwidth = 160\nheight = 90\n\
    [spectra]\nstone = \"travertine_tufa_solid__eco_ward73\"\nsun = { illuminant = \"D55\" }\n\
    [materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n\
    [[objects]]\nname = \"relief\"\nmesh = \"relief.ply\"\nmaterial = \"stone\"\n\
    [[lights]]\nkind = \"sun\"\npreset = \"sun\"\nspectrum = \"sun\"\n";

#[cfg(test)]
mod tests {
    #[test]
    fn the_relief_reads_back_with_its_triangles() {
        let mut bytes = Vec::new();
        super::write_ply(&mut bytes, 4, 3).unwrap();
        let mesh = restauro_scene::formats::ply::parse(&bytes, std::path::Path::new("relief.ply"))
            .unwrap();
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (20, 24));
        let b = mesh.bounds().unwrap();
        assert_eq!((b.min[0], b.max[0], b.max[2]), (-25.0, 25.0, 25.0));
    }
}
