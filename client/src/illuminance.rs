//! `restauro illuminance`: the scene's calculation grids computed as a render is (through a
//! cluster, or in-process: the same plan and tiles, so the same bits), then read back from the
//! grids' EXR and written as a lighting designer reads them:
//!
//! * `illuminance.json` (schema `restauro.illuminance/1`): per grid its name, its points
//!   (`position`, `normal`, `lux`, `direct_lux`, `indirect_lux`) and `min_lux`, `mean_lux`,
//!   `max_lux` and `uniformity` (U₀ = E_min/E_mean, EN 12464-1), and for a rectangle its
//!   `divisions` and `cell_area_m2`;
//! * `<grid>.csv`: the same points, one per row;
//! * `<grid>.png`: the illuminance in false colour with isolines and a lux scale (a rectangle's
//!   cells with `u` to the right and `v` up; a list of points as a strip in its order).
//!
//! The reading and the files are `restauro_image::illuminance`'s, which the studio uses too.

use crate::cli::{IlluminanceArgs, RenderArgs};
use anyhow::{Context, Result};
use restauro_assets::load_scene;
pub use restauro_image::illuminance::{
    Document, GridResult, PointResult, SCHEMA, Written, grid_results, write_documents,
};
use restauro_image::image_files::{MAX_PIXELS, read_exr};
use restauro_scene::load::Limits;
use std::fmt::Write as _;

pub fn run(args: &IlluminanceArgs) -> Result<String> {
    let render = RenderArgs {
        scene: args.scene.clone(),
        out: args.out.clone(),
        variant: args.variant.clone(),
        variants: Vec::new(),
        integrator: args.integrator,
        spp: args.spp,
        noise: None,
        width: None,
        height: None,
        spectral: false,
        tile: None,
        exposure: "auto".into(),
        retinex_paths: restauro_scene::job::RetinexOptions::default().paths,
        retinex_seed: 0,
        run: args.run.clone(),
        grids: true,
    };
    if let Some(sequence) = args.sun.sequence() {
        return crate::illuminance_day::run(args, &render, &sequence);
    }
    let computed = crate::render::run(&render)?;
    let stem = crate::render::job_spec(&render, 0)?.name.file_stem();
    let exr = args.out.join(format!("{stem}.exr"));
    let limits: Limits = (&args.run.limits).into();
    let scene = load_scene(&args.scene, &limits)?;
    let image = read_exr(&exr, MAX_PIXELS).with_context(|| format!("reading {}", exr.display()))?;
    let document = Document {
        schema: SCHEMA.into(),
        scene: args.scene.display().to_string(),
        variant: args.variant.clone(),
        grids: grid_results(&scene, &image, &exr)?,
    };
    let json = serde_json::to_string_pretty(&document)? + "\n";
    let mut text = computed;
    let written = write_documents(&args.out, &document, &json)?;
    for (grid, files) in document.grids.iter().zip(written.per_grid) {
        let _ = writeln!(
            text,
            "{}: {} points, min {:.4} lx, mean {:.4} lx, max {:.4} lx, uniformity {:.3}",
            grid.name,
            grid.points.len(),
            grid.min_lux,
            grid.mean_lux,
            grid.max_lux,
            grid.uniformity,
        );
        for f in files {
            let _ = writeln!(text, "wrote {}", f.display());
        }
    }
    let _ = writeln!(text, "wrote {}", written.json.display());
    Ok(if args.json { json } else { text })
}
