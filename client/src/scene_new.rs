//! `restauro scene new --mesh FILE [--site LAT,LON] [--out DIR]`: a starter scene for the
//! user's own model, that renders at once and says in comments what to change.
//!
//! The mesh is read as any scene reads it (every format, the same checks); the scene lists its
//! parts, each bound to a placeholder stone, frames it with a camera from the side on which it
//! is widest (a facade is seen from the front), and lights it with the sun of a summer afternoon
//! at the site (or from the south-south-west at 45° without one) and a clear sky.

use crate::cli::SceneNewArgs;
use anyhow::{Context, Result, bail};
use restauro_assets::load_scene;
use restauro_scene::load::Limits;
use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

/// The placeholder every part starts with: a measured travertine.
const PLACEHOLDER: &str = "travertine_tufa_solid__eco_ward73";
/// The camera's vertical field of view, and its image.
const FOV_DEG: f64 = 40.0;
const IMAGE: (u32, u32) = (1280, 720);

/// A TOML string.
fn quoted(text: &str) -> String {
    toml::Value::String(text.to_owned()).to_string()
}

/// `LAT,LON` in degrees.
fn parse_site(text: &str) -> Result<(f64, f64)> {
    let bad = || {
        anyhow::anyhow!(
            "--site `{text}`: give latitude and longitude in degrees, e.g. 45.737,7.323 \
             (north and east positive)"
        )
    };
    let (lat, lon) = text.split_once(',').ok_or_else(bad)?;
    let (lat, lon): (f64, f64) =
        (lat.trim().parse().map_err(|_| bad())?, lon.trim().parse().map_err(|_| bad())?);
    if !(lat.is_finite() && lon.is_finite() && lat.abs() <= 90.0 && lon.abs() <= 180.0) {
        bail!("--site `{text}`: latitude must be within ±90° and longitude within ±180°");
    }
    Ok((lat, lon))
}

/// Where the mesh goes in the scene's folder, and the reference the scene uses: the mesh stays
/// where it is when the scene is written beside it; otherwise it is copied into `meshes/`.
fn place_mesh(mesh: &Path, out: &Path) -> Result<String> {
    let file = mesh.file_name().context("--mesh names no file")?.to_string_lossy().into_owned();
    let folder = mesh.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let same = |a: &Path, b: &Path| a.canonicalize().ok() == b.canonicalize().ok();
    if same(folder, out) {
        return Ok(file);
    }
    if mesh.extension().is_some_and(|e| e.eq_ignore_ascii_case("gltf")) {
        bail!(
            "{}: a .gltf may keep its buffers in files beside it; write the scene beside the \
             model (leave out --out), or save the model as .glb",
            mesh.display()
        );
    }
    let is_wrl = mesh.extension().is_some_and(|e| e.eq_ignore_ascii_case("wrl"));
    if is_wrl && std::fs::read_to_string(mesh).is_ok_and(|text| text.contains("Inline")) {
        bail!(
            "{}: the world inlines other files, which are found beside it; write the scene \
             beside the model (leave out --out)",
            mesh.display()
        );
    }
    let target = out.join("meshes").join(&file);
    std::fs::create_dir_all(out.join("meshes"))
        .with_context(|| format!("creating {}", out.join("meshes").display()))?;
    std::fs::copy(mesh, &target)
        .with_context(|| format!("copying {} to {}", mesh.display(), target.display()))?;
    // An OBJ's material library and its photos go with it, where it names them.
    let is_obj = mesh.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    let text =
        if is_obj { std::fs::read_to_string(mesh).unwrap_or_default() } else { String::new() };
    for companion in restauro_scene::formats::obj::library::companions(&text, folder) {
        let inside = Path::new(&companion).components().all(|c| matches!(c, Component::Normal(_)));
        if !inside {
            continue;
        }
        let (from, to) = (folder.join(&companion), out.join("meshes").join(&companion));
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        std::fs::copy(&from, &to)
            .with_context(|| format!("copying {} to {}", from.display(), to.display()))?;
    }
    Ok(format!("meshes/{file}"))
}

/// What the starter scene needs to know of the mesh.
struct Survey {
    parts: Vec<String>,
    /// Its bounds in the scene's world (Z up).
    bounds: [[f64; 3]; 2],
    /// An OBJ or PLY that looks Y-up is read with `up_axis = "y"` (see `restauro_scene::upright`).
    y_up: bool,
}

/// The mesh read as a scene reads it; an OBJ or PLY that lies on its back is read again Y-up.
fn survey(dir: &Path, reference: &str) -> Result<Survey> {
    let (parts, bounds, on_its_back) = read_mesh(dir, reference, false)?;
    if !on_its_back {
        return Ok(Survey { parts, bounds, y_up: false });
    }
    let (parts, bounds, _) = read_mesh(dir, reference, true)?;
    Ok(Survey { parts, bounds, y_up: true })
}

/// The parts and world bounds of the mesh, and whether it probably lies on its back.
fn read_mesh(
    dir: &Path,
    reference: &str,
    y_up: bool,
) -> Result<(Vec<String>, [[f64; 3]; 2], bool)> {
    let probe = format!(
        "format = 1\n[camera]\nposition = [0.0, -10.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n\
         width = 16\nheight = 9\n[spectra]\nstone = {}\n[materials.stone]\nmodel = \"lambert\"\n\
         reflectance = \"stone\"\n[[objects]]\nname = \"model\"\nmesh = {}\nmaterial = \"stone\"\n\
         {}[[lights]]\nkind = \"sun\"\nilluminance_lux = 1.0\nspectrum = \"stone\"\n\
         azimuth_deg = 0.0\nelevation_deg = 45.0\n",
        quoted(PLACEHOLDER),
        quoted(reference),
        if y_up { "up_axis = \"y\"\n" } else { "" }
    );
    let path = dir.join(format!(".restauro-scene-new-{}.toml", std::process::id()));
    std::fs::write(&path, probe).with_context(|| format!("writing {}", path.display()))?;
    let loaded = load_scene(&path, &Limits::default());
    let _ = std::fs::remove_file(&path);
    let loaded = loaded?;
    let mesh = &loaded.objects[0].mesh;
    let Some(b) = mesh.bounds() else {
        bail!("{reference}: the mesh has no triangles, so there is nothing to frame");
    };
    let parts = mesh.groups.iter().map(|g| g.name.clone()).collect();
    let on_its_back = loaded.notes.iter().any(|n| n.contains("probably lies on its back"));
    Ok((parts, [b.min.map(f64::from), b.max.map(f64::from)], on_its_back))
}

/// A camera that frames `bounds` from the side on which they are widest, at eye level with the
/// model's middle, far enough that the whole box is in view.
fn camera(bounds: [[f64; 3]; 2]) -> ([f64; 3], [f64; 3]) {
    let [min, max] = bounds;
    let centre: [f64; 3] = std::array::from_fn(|k| 0.5 * (min[k] + max[k]));
    let size: [f64; 3] = std::array::from_fn(|k| max[k] - min[k]);
    // Widest along X: seen from the south (−Y), looking north; otherwise from the west.
    let (across, depth, from) = if size[0] >= size[1] {
        (size[0], size[1], [0.0, -1.0])
    } else {
        (size[1], size[0], [-1.0, 0.0])
    };
    let aspect = f64::from(IMAGE.0) / f64::from(IMAGE.1);
    let half_fov = (FOV_DEG / 2.0).to_radians();
    // The nearest distance at which both the height and the width fit, with a margin.
    let fit = (size[2] / 2.0).max(across / 2.0 / aspect) / half_fov.tan();
    let distance = 1.15 * fit + depth / 2.0;
    let position = [centre[0] + from[0] * distance, centre[1] + from[1] * distance, centre[2]];
    (position, centre)
}

/// For a model far from zero (a survey in UTM), the whole metres of its centre: the scene's
/// `origin`.
fn survey_origin(bounds: [[f64; 3]; 2]) -> Option<[f64; 3]> {
    let far = bounds.iter().flatten().any(|c| c.abs() > restauro_scene::mesh::ANCHOR_BEYOND_M);
    far.then(|| std::array::from_fn(|k| (0.5 * (bounds[0][k] + bounds[1][k])).round()))
}

fn vector(v: [f64; 3]) -> String {
    format!("[{:.3}, {:.3}, {:.3}]", v[0], v[1], v[2])
}

/// The sun's table: by the site and a summer afternoon, or by direction.
fn sun(site: Option<(f64, f64)>) -> String {
    match site {
        Some((lat, lon)) => {
            // The site's standard time, near enough from its longitude (15° an hour); change
            // `datetime` to the hour and date to be shown, with the site's own offset.
            let hours = (lon / 15.0).round() as i32;
            let sign = if hours < 0 { '-' } else { '+' };
            format!(
                "# The sun by NREL's SPA at the site on a summer afternoon: change the date and hour\n\
                 # (and the offset to the site's own), or give azimuth_deg and elevation_deg instead.\n\
                 kind = \"sun\"\npreset = \"sun\"\nspectrum = \"sunlight\"\n\
                 site = {{ latitude_deg = {lat}, longitude_deg = {lon}, height_m = 0.0, datetime = \
                 \"2026-07-15T15:30:00{sign}{:02}:00\" }}\n",
                hours.abs()
            )
        }
        None => "# The sun from the south-south-west, 45° up (give --site LAT,LON, or a `site`\n\
                 # table, for the sun of a place, date and hour).\n\
                 kind = \"sun\"\nilluminance_lux = 100000.0\nspectrum = \"sunlight\"\n\
                 azimuth_deg = 200.0\nelevation_deg = 45.0\n"
            .to_owned(),
    }
}

/// The starter scene's text.
fn scene_text(mesh: &str, survey: &Survey, site: Option<(f64, f64)>) -> String {
    let Survey { parts, bounds, y_up } = survey;
    let bounds = *bounds;
    let (position, target) = camera(bounds);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# A starter scene for {mesh}, written by `restauro scene new`. Check it with\n\
         # `restauro scene check`, render it with `restauro render`; docs/scene-format.md has\n\
         # every field. World: +X east, +Y north, +Z up, metres.\nformat = 1\n"
    );
    if let Some(origin) = survey_origin(bounds) {
        let _ = writeln!(
            s,
            "# The model is in survey coordinates: positions are moved by -origin before they\n\
             # become 32-bit numbers, so millimetres survive. Everything below stays in the\n\
             # survey's coordinates.\norigin = {}\n",
            vector(origin)
        );
    }
    let _ = writeln!(
        s,
        "[camera]\n# Framing the model ({} × {} × {} m) from its wider side; move it where a person\n\
         # would stand (eyes at about 1.7 m above the ground).\nposition = {}\ntarget = {}\n\
         vertical_fov_deg = {FOV_DEG}\nwidth = {}\nheight = {}\n",
        fmt_m(bounds[1][0] - bounds[0][0]),
        fmt_m(bounds[1][1] - bounds[0][1]),
        fmt_m(bounds[1][2] - bounds[0][2]),
        vector(position),
        vector(target),
        IMAGE.0,
        IMAGE.1
    );
    let _ = writeln!(
        s,
        "[render]\n# path: with the light between surfaces; whitted: the paper's direct light only.\n\
         integrator = \"path\"\nsamples_per_pixel = 16\nmax_depth = 4\nseed = 1\n"
    );
    let _ = writeln!(
        s,
        "[spectra]\n# A placeholder for every part: replace it with the measured reflectance of each\n\
         # stone (`restauro color --list` lists the shipped ones; a CSV file of your own works too).\n\
         stone = {}\nsunlight = {{ illuminant = \"D55\" }}\nskylight = {{ illuminant = \"daylight:12000\" }}\n",
        quoted(PLACEHOLDER)
    );
    let _ = writeln!(
        s,
        "[materials.stone]\n# lambert (matte) or cook-torrance (with roughness and ior, for polished stone).\n\
         model = \"lambert\"\nreflectance = \"stone\"\n"
    );
    // A part's name as a TOML key: bare when it can be, quoted otherwise.
    let key = |p: &str| {
        let bare =
            !p.is_empty() && p.bytes().all(|b| b.is_ascii_alphanumeric() || b"_-".contains(&b));
        if bare { p.to_owned() } else { quoted(p) }
    };
    let bindings: Vec<String> = parts.iter().map(|p| format!("{} = \"stone\"", key(p))).collect();
    let up = if *y_up {
        "# The model looked as if it lay on its back read Z-up, so it is read Y-up, as it was\n\
         # probably exported; delete this line if it now stands on its side.\nup_axis = \"y\"\n"
    } else {
        ""
    };
    let _ = writeln!(
        s,
        "[[objects]]\n# Each part of the mesh ({} in all) bound to a material: give each its own.\n\
         name = \"model\"\nmesh = {}\n{up}materials = {{ {} }}\n",
        parts.len(),
        quoted(mesh),
        bindings.join(", ")
    );
    let _ = writeln!(s, "[[lights]]\n{}", sun(site));
    let _ = writeln!(
        s,
        "[[lights]]\n# A clear sky: 15 000 lux of diffuse light on the horizontal (preset \"overcast\"\n\
         # for a cloudy day, with model = \"cie-overcast\").\nkind = \"sky\"\npreset = \"clear\"\n\
         spectrum = \"skylight\""
    );
    s
}

fn fmt_m(v: f64) -> String {
    format!("{v:.1}")
}

pub fn run(args: &SceneNewArgs) -> Result<String> {
    let site = args.site.as_deref().map(parse_site).transpose()?;
    if !args.mesh.is_file() {
        bail!(
            "--mesh {}: no such file; give the path of your model (.obj, .gltf, .glb, .ply or .wrl)",
            args.mesh.display()
        );
    }
    let out: PathBuf = match &args.out {
        Some(out) => out.clone(),
        None => args
            .mesh
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_owned(),
    };
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let stem = args.mesh.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let scene_path = out.join(format!("{stem}.toml"));
    if scene_path.exists() && !args.force {
        bail!("{} exists; choose another --out, or --force to write over it", scene_path.display());
    }
    let reference = place_mesh(&args.mesh, &out)?;
    let survey = survey(&out, &reference)?;
    let text = scene_text(&reference, &survey, site);
    let parts = &survey.parts;
    std::fs::write(&scene_path, &text)
        .with_context(|| format!("writing {}", scene_path.display()))?;
    // What was written is checked as any scene is.
    load_scene(&scene_path, &Limits::default())?;
    let mut s =
        format!("wrote {} for {} ({} parts: ", scene_path.display(), reference, parts.len());
    s.push_str(&parts.join(", "));
    let _ = writeln!(s, ")");
    if survey.y_up {
        let _ = writeln!(
            s,
            "note: {reference} looked Y-up (lying on its back read Z-up), so the scene reads it \
             with up_axis = \"y\""
        );
    }
    let _ = writeln!(
        s,
        "next: edit the spectra and materials, then `restauro render {}`",
        scene_path.display()
    );
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A survey in UTM gets an origin at its centre's whole metres; a model near zero none.
    #[test]
    fn a_survey_far_from_zero_gets_an_origin() {
        let utm = [[5_000_000.2, 4_000_000.0, 10.0], [5_000_040.2, 4_000_002.0, 30.0]];
        assert_eq!(survey_origin(utm), Some([5_000_020.0, 4_000_001.0, 20.0]));
        assert_eq!(survey_origin([[-20.0, 0.0, 0.0], [20.0, 2.0, 20.0]]), None);
    }

    #[test]
    fn a_facade_is_framed_from_the_front() {
        // 40 m wide (X), 2 m deep, 20 m high: seen from the south, centred, all in view.
        let (position, target) = camera([[-20.0, 0.0, 0.0], [20.0, 2.0, 20.0]]);
        assert_eq!(target, [0.0, 1.0, 10.0]);
        assert!(position[1] < -20.0 && position[0] == 0.0 && position[2] == 10.0, "{position:?}");
        // The whole width fits the horizontal field of view.
        let half_h = (FOV_DEG / 2.0).to_radians().tan() * 1280.0 / 720.0;
        assert!(20.0 / (1.0 - position[1]) < half_h);
        // A deep, narrow model is seen from the west.
        let (position, _) = camera([[0.0, 0.0, 0.0], [2.0, 30.0, 5.0]]);
        assert!(position[0] < 0.0 && position[1] == 15.0, "{position:?}");
    }

    #[test]
    fn sites_are_checked() {
        assert_eq!(parse_site("45.737, 7.323").unwrap(), (45.737, 7.323));
        for bad in ["45", "north,east", "95,7", "45,200"] {
            assert!(parse_site(bad).is_err(), "{bad}");
        }
    }
}
