//! A survey-sized model made on the spot: a relief of `nx × ny` quads (two triangles each) over
//! 50 m × 25 m, 2 m high, as binary PLY, in a scene of one stone under the sun. The studio's
//! tests of big models (the coarse copy drawn while moving, and the speed measurement) open it.

use crate::{Coordinator, Worker, submit};
use std::io::Write;
use std::path::Path;

/// A coordinator serving the studio and one worker, holding the relief of `nx × ny` quads
/// (rendered once, 160 × 90 px, 1 sample per pixel), in `dir`: the coordinator, the page's
/// address and the worker.
pub fn relief_studio(dir: &Path, nx: usize, ny: usize) -> (Coordinator, String, Worker) {
    let scene = dir.join("relief");
    std::fs::create_dir_all(&scene).unwrap();
    relief_scene(&scene, nx, ny);
    let (c, page) = Coordinator::with_studio(dir);
    let worker = Worker::start(dir, &c.url, "local-1", &[]);
    let file = scene.join("scene.toml");
    submit(file.to_str().unwrap(), &["--spp", "1"], &c.url, &dir.join("client.token"));
    (c, page, worker)
}

/// Writes `relief.ply` and `scene.toml` into `dir` (which exists).
pub fn relief_scene(dir: &Path, nx: usize, ny: usize) {
    relief(&dir.join("relief.ply"), nx, ny);
    std::fs::write(
        dir.join("scene.toml"),
        "format = 1\n[camera]\nposition = [0.0, -60.0, 12.0]\ntarget = [0.0, 0.0, 12.0]\n\
         width = 160\nheight = 90\n[spectra]\nstone = \"travertine_tufa_solid__eco_ward73\"\n\
         sun = { illuminant = \"D55\" }\n[materials.stone]\nmodel = \"lambert\"\nreflectance = \"stone\"\n\
         [[objects]]\nname = \"relief\"\nmesh = \"relief.ply\"\nmaterial = \"stone\"\n\
         [[lights]]\nkind = \"sun\"\npreset = \"sun\"\nspectrum = \"sun\"\n",
    )
    .unwrap();
}

/// A binary PLY of a relief `nx × ny` quads (2 triangles each) over 50 m × 25 m, 2 m high.
fn relief(path: &std::path::Path, nx: usize, ny: usize) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let vertices = (nx + 1) * (ny + 1);
    let faces = 2 * nx * ny;
    write!(
        f,
        "ply\nformat binary_little_endian 1.0\nelement vertex {vertices}\nproperty float x\n\
         property float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .unwrap();
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, z) = (50.0 * i as f32 / nx as f32, 25.0 * j as f32 / ny as f32);
            let y = -(2.0 * ((x * 1.3).sin() * (z * 0.7).cos()).abs());
            for v in [x - 25.0, y, z] {
                f.write_all(&v.to_le_bytes()).unwrap();
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
                f.write_all(&[3u8]).unwrap();
                for v in t {
                    f.write_all(&v.to_le_bytes()).unwrap();
                }
            }
        }
    }
}
