//! The demo's scenes as folders on disk, each written atomically: what `restauro scene aosta`,
//! the demo and the benchmarks render.

use restauro_image::atomic_file;
use std::io;
use std::path::{Path, PathBuf};

/// The files of a generated Aosta scene.
pub struct AostaFiles {
    /// `aosta.toml`: a summer afternoon.
    pub sunny: PathBuf,
    /// `aosta-overcast.toml`: an overcast day.
    pub overcast: PathBuf,
    /// `aosta-clear.toml`: the afternoon's sun under the CIE standard clear sky.
    pub clear: PathBuf,
    /// `aosta-floodlit.toml`: a night under floodlights, with a calculation grid.
    pub floodlit: PathBuf,
    /// `meshes/facade.obj`, which all of them use.
    pub mesh: PathBuf,
}

/// Writes the procedural Aosta facade scene into `out`: `aosta.toml` (a summer afternoon),
/// `aosta-overcast.toml` (an overcast day) and `meshes/facade.obj`.
pub fn write_aosta(out: &Path, width: u32, height: u32, seed: u64) -> io::Result<AostaFiles> {
    let generated = crate::scenes::aosta::generate(width, height, seed);
    let files = AostaFiles {
        sunny: out.join("aosta.toml"),
        overcast: out.join("aosta-overcast.toml"),
        clear: out.join("aosta-clear.toml"),
        floodlit: out.join("aosta-floodlit.toml"),
        mesh: out.join("meshes/facade.obj"),
    };
    let photometry = crate::scenes::aosta::PHOTOMETRY
        .map(|(name, text)| (out.join("photometry").join(name), text.to_owned()));
    let texts = [
        (files.mesh.clone(), generated.facade_obj),
        (files.sunny.clone(), generated.scene_toml),
        (files.overcast.clone(), generated.overcast_toml),
        (files.clear.clone(), generated.clear_toml),
        (files.floodlit.clone(), generated.floodlit_toml),
    ];
    for (path, text) in texts.iter().chain(&photometry) {
        atomic_file::write(path, text.as_bytes()).map_err(|e| {
            io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))
        })?;
    }
    Ok(files)
}
