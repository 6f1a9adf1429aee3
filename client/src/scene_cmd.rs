//! `restauro scene aosta | check | bundle`.

use crate::cli::SceneCommand;
use anyhow::Result;
use restauro_assets::bundle_scene;
use restauro_assets::load_scene;
use restauro_demo::scene_files::write_aosta;
use restauro_scene::load::{Limits, LoadedScene};
use std::fmt::Write as _;
use std::path::Path;

/// A summary of a loaded scene: what a restorer checks before rendering.
pub fn summary(path: &Path, scene: &LoadedScene) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}: valid", path.display());
    let c = &scene.camera;
    let _ = writeln!(
        s,
        "  camera {}×{} at {:?} looking at {:?}, vertical field {:.1}°",
        c.width, c.height, c.pose.position, c.pose.target, c.pose.vertical_fov_deg
    );
    let _ =
        writeln!(s, "  {} triangles in {} objects", scene.triangle_count(), scene.objects.len());
    for o in &scene.objects {
        if let Some(b) = o.mesh.bounds() {
            let _ = writeln!(
                s,
                "    {}: {} triangles, bounds {:?} – {:?} m, parts {}",
                o.name,
                o.mesh.triangles.len(),
                b.min,
                b.max,
                parts(scene, &o.mesh, &o.group_materials)
            );
        }
    }
    for l in &scene.lights {
        let _ = writeln!(s, "  {l}");
    }
    let variants: Vec<&str> = scene.file.variants.keys().map(String::as_str).collect();
    let _ = writeln!(
        s,
        "  variants: {}",
        if variants.is_empty() { "none".to_owned() } else { variants.join(", ") }
    );
    for n in &scene.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}

/// An object's parts and their materials, each with what its file lays on it as detail when
/// its material shows that: `facade→stone`, `scan→stone (vertex colours)`.
fn parts(scene: &LoadedScene, mesh: &restauro_scene::mesh::Mesh, materials: &[String]) -> String {
    let coloured = mesh.coloured_groups();
    let part = |(k, (g, m)): (usize, (&restauro_scene::mesh::Group, &String))| {
        let own = if !scene.file.materials[m].shows_file_detail("base") {
            ""
        } else if g.photo.is_some() {
            " (its photo)"
        } else if coloured[k] {
            " (vertex colours)"
        } else {
            ""
        };
        format!("{}→{m}{own}", g.name)
    };
    mesh.groups.iter().zip(materials).enumerate().map(part).collect::<Vec<_>>().join(", ")
}

pub fn run(command: &SceneCommand) -> Result<String> {
    match command {
        SceneCommand::Aosta { out, width, height, seed } => {
            let files = write_aosta(out, *width, *height, *seed)?;
            // Check what was written as any scene is checked.
            let loaded = load_scene(&files.sunny, &Limits::default())?;
            let mut s = summary(&files.sunny, &loaded);
            for other in [&files.overcast, &files.clear, &files.floodlit] {
                load_scene(other, &Limits::default())?;
            }
            for path in [&files.sunny, &files.overcast, &files.clear, &files.floodlit, &files.mesh]
            {
                let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
                let _ = writeln!(s, "wrote {} ({bytes} bytes)", path.display());
            }
            Ok(s)
        }
        SceneCommand::New(args) => crate::scene_new::run(args),
        SceneCommand::Check { scene, limits } => {
            let loaded = load_scene(scene, &limits.into())?;
            Ok(summary(scene, &loaded))
        }
        SceneCommand::Bundle { scene, out, limits } => {
            let bundle = bundle_scene(scene, &limits.into())?;
            bundle.load(&limits.into())?;
            let mut s = String::new();
            let _ = writeln!(s, "bundle {}", bundle.id());
            for (hash, bytes) in &bundle.files {
                let _ = writeln!(s, "  {hash}  {} bytes", bytes.len());
            }
            if let Some(out) = out {
                if !restauro_assets::archive::is_archive(out) {
                    anyhow::bail!(
                        "--out {}: a bundle archive is a .tar file; name it e.g. scene.tar",
                        out.display()
                    );
                }
                restauro_assets::archive::write_archive(&bundle, out)?;
                let bytes = std::fs::metadata(out).map_or(0, |m| m.len());
                let _ = writeln!(
                    s,
                    "wrote {} ({bytes} bytes): `scene check`, `render` and `submit` take it as \
                     they take the scene",
                    out.display()
                );
            }
            Ok(s)
        }
    }
}
