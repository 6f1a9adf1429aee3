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
    let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join("relief.ply")).unwrap());
    restauro_demo::scenes::relief::write_ply(&mut f, nx, ny).unwrap();
    f.flush().unwrap();
    std::fs::write(dir.join("scene.toml"), restauro_demo::scenes::relief::SCENE_TOML).unwrap();
}
