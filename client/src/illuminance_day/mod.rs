//! `restauro illuminance --sun-from … --to … --every …` (or `--dates … --at …`): the scene's
//! calculation grids through a day, or at one hour on several dates, as one sequence job on a
//! cluster; each frame's grids are read back as `restauro illuminance` reads one, and written
//! per grid as
//!
//! * `<grid>-day.csv`: a row per point (`index,x_m,y_m,z_m`, then its illuminance in lux at each
//!   frame, the column named by the frame's label);
//! * `<grid>-day.png`: the least, mean and most illuminance over the grid at each frame.

mod chart;

use crate::cli::{IlluminanceArgs, RenderArgs};
use crate::sequence::{Rendered, render_sequence};
use anyhow::{Context, Result};
use restauro_assets::load_scene;
use restauro_image::illuminance::{GridResult, grid_results};
use restauro_image::image_files::{MAX_PIXELS, PngPixels, read_exr, write_png};
use restauro_scene::load::Limits;
use restauro_scene::sequence::Sequence;
use restauro_spectral::rgb_space::RgbSpace;
use std::fmt::Write as _;
use std::path::PathBuf;

/// The grids at each frame of `sequence`; `render` is the grids' render (`grids: true`).
pub fn run(args: &IlluminanceArgs, render: &RenderArgs, sequence: &Sequence) -> Result<String> {
    let Rendered { spec, cluster, status, .. } = render_sequence(render, sequence, "the grids")?;
    let limits: Limits = (&args.run.limits).into();
    let scene = load_scene(&args.scene, &limits)?;
    let stem = spec.name.file_stem();
    // Each frame's grids, frame by frame.
    let mut at_frames: Vec<Vec<GridResult>> = Vec::with_capacity(spec.frames.len());
    for index in 0..spec.frames.len() {
        let exr = render.out.join(format!("{stem}-{index:04}.exr"));
        let image =
            read_exr(&exr, MAX_PIXELS).with_context(|| format!("reading {}", exr.display()))?;
        at_frames.push(grid_results(&scene, &image, &exr)?);
    }
    let labels: Vec<String> = spec.frames.iter().map(|f| f.label.clone()).collect();
    let mut text = String::new();
    let _ = writeln!(
        text,
        "computed the grids of {} at {} times through {} (job {})",
        render.scene.display(),
        labels.len(),
        cluster.description(render),
        status.id
    );
    let grids = at_frames.first().map_or(0, Vec::len);
    for g in 0..grids {
        let name = at_frames[0][g].name.clone();
        for path in write_grid(render, &name, &labels, &at_frames, g)? {
            let _ = writeln!(text, "wrote {}", path.display());
        }
    }
    Ok(text)
}

/// Writes grid `g`'s table and chart through the frames; their paths.
fn write_grid(
    render: &RenderArgs,
    name: &str,
    labels: &[String],
    at_frames: &[Vec<GridResult>],
    g: usize,
) -> Result<[PathBuf; 2]> {
    let csv = render.out.join(format!("{name}-day.csv"));
    std::fs::write(&csv, table(labels, at_frames, g))
        .with_context(|| format!("writing {}", csv.display()))?;
    let of = |f: fn(&GridResult) -> f64| at_frames.iter().map(|grids| f(&grids[g])).collect();
    let series = [
        chart::Series { name: "most", colour: [240, 190, 60], lux: of(|r| r.max_lux) },
        chart::Series { name: "mean", colour: [235, 235, 235], lux: of(|r| r.mean_lux) },
        chart::Series { name: "least", colour: [90, 160, 240], lux: of(|r| r.min_lux) },
    ];
    let title = format!("{name}: illuminance (lx)");
    let picture = chart::chart(&title, labels, &series);
    let png = render.out.join(format!("{name}-day.png"));
    let pixels = PngPixels::Eight(picture.data);
    write_png(&png, picture.width as usize, picture.height as usize, &pixels, RgbSpace::Srgb)?;
    Ok([csv, png])
}

/// A row per point of grid `g`: its index and position, then its illuminance at each frame.
fn table(labels: &[String], at_frames: &[Vec<GridResult>], g: usize) -> String {
    let mut s = String::from("index,x_m,y_m,z_m");
    for label in labels {
        let _ = write!(s, ",lux {label}");
    }
    s.push('\n');
    let Some(first) = at_frames.first() else { return s };
    for (i, p) in first[g].points.iter().enumerate() {
        let [x, y, z] = p.position;
        let _ = write!(s, "{i},{x},{y},{z}");
        for grids in at_frames {
            let _ = write!(s, ",{}", grids[g].points[i].lux);
        }
        s.push('\n');
    }
    s
}
