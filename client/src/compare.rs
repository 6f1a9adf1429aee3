//! `restauro compare A.exr B.exr --out DIR`: how two restoration hypotheses differ, pixel by
//! pixel, as a person would judge the difference of two colours — CIEDE2000 (CIE 142-2001) in
//! CIELAB relative to one reference white for both images.
//!
//! It writes into DIR:
//! * `delta-e.png` — the ΔE00 map (viridis, light sources in grey) with its colour scale and
//!   statistics;
//! * `side-by-side.png` — A and B as the display shows them, with one exposure (the white);
//! * `split.png` — one image, A on the left and B on the right of a line down the middle;
//! * `compare.json` (schema `restauro.compare/1`) — the files, the white, and the statistics:
//!   mean, median, 95th percentile and maximum ΔE00, and the share of the pixels above the
//!   threshold.
//!
//! The white: `--white` takes the display's exposure syntax. `auto` (the default) is the
//! reference white the display would choose for A (so the map measures what the PNGs show);
//! `absolute:<cd/m²>` a luminance (for a render, E_h/π of a perfect white horizontal surface
//! is the natural one); `relative` Y = 1, for images after the Retinex. Either image's light
//! sources (its `emitter` channel: the sky) are left out.

use crate::cli::CompareArgs;
use anyhow::{Context, Result, bail};
use restauro_demo::picture::{map_picture, picture};
use restauro_demo::sheet::{Grid, INK, Rgb8, beside_colour_bar, colour_bar};
use restauro_image::delta_e::{DeltaEMap, DeltaEStats, delta_e_map, scale_max, white_luminance};
use restauro_image::image_files::{MAX_PIXELS, PngPixels, XyzImage, read_exr, write_png};
use restauro_spectral::appearance::d65_white;
use restauro_spectral::display::Exposure;
use restauro_spectral::rgb_space::RgbSpace;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

fn write(dir: &Path, name: &str, image: &Rgb8) -> Result<()> {
    let path = dir.join(name);
    let pixels = PngPixels::Eight(image.data.clone());
    write_png(&path, image.width as usize, image.height as usize, &pixels, RgbSpace::Srgb)
        .with_context(|| format!("writing {}", path.display()))
}

#[derive(Serialize)]
struct Summary<'a> {
    schema: &'static str,
    a: String,
    b: String,
    width: usize,
    height: usize,
    /// The reference white's luminance in the images' units (cd/m² for a render, 1 relative).
    white_luminance: f64,
    white: &'a str,
    delta_e00: &'a DeltaEStats,
    files: Vec<&'static str>,
}

/// The files [`compare_images`] writes, in the order it lists them.
const FILES: [&str; 4] = ["delta-e.png", "side-by-side.png", "split.png", "compare.json"];

/// Compares two images already read; writes the files into `out` and returns the summary text.
pub fn compare_images(
    (a, a_name): (&XyzImage, &str),
    (b, b_name): (&XyzImage, &str),
    (white, white_text): (Exposure, &str),
    threshold: f64,
    out: &Path,
) -> Result<String> {
    check_comparable((a, a_name), (b, b_name), threshold)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let luminance = white_luminance(a, white);
    let map = delta_e_map(a, b, d65_white().scale(luminance), threshold);
    let s = &map.stats;
    let caption = format!(
        "mean {:.2}, median {:.2}, 95th percentile {:.2}, max {:.1}; {:.1} % above {}",
        s.mean,
        s.median,
        s.p95,
        s.max,
        100.0 * s.share_above_threshold,
        s.threshold
    );
    let cell = (a.width as u32).clamp(240, 960);
    let footer = format!(
        "CIELAB relative to a D65 white of luminance {luminance:.4} ({white_text}); light \
         sources in grey."
    );
    let names = format!("A: {a_name}; B: {b_name}");
    write(
        out,
        "delta-e.png",
        &delta_e_sheet(&map, (a.width, a.height), cell, names, &caption, footer),
    )?;

    // One exposure for both: the white.
    let exposure = Exposure::Absolute { white_cd_m2: luminance };
    let (pa, pb) = (picture(a, exposure), picture(b, exposure));
    let side = Grid {
        title: "A and B, one exposure",
        column_labels: vec![format!("A: {a_name}"), format!("B: {b_name}")],
        row_labels: vec![String::new()],
        cells: vec![vec![Some(pa.resized_to_width(cell)), Some(pb.resized_to_width(cell))]],
        captions: Vec::new(),
        cell_width: cell,
        footer: Vec::new(),
    }
    .render();
    write(out, "side-by-side.png", &side)?;
    write(out, "split.png", &split(&pa, &pb))?;

    let summary = Summary {
        schema: "restauro.compare/1",
        a: a_name.to_owned(),
        b: b_name.to_owned(),
        width: a.width,
        height: a.height,
        white_luminance: luminance,
        white: white_text,
        delta_e00: s,
        files: FILES.to_vec(),
    };
    let json = out.join("compare.json");
    std::fs::write(&json, serde_json::to_string_pretty(&summary)? + "\n")
        .with_context(|| format!("writing {}", json.display()))?;
    let mut text = format!("ΔE00 between {a_name} and {b_name}: {caption}\n");
    for f in FILES {
        let _ = writeln!(text, "wrote {}", out.join(f).display());
    }
    Ok(text)
}

/// The images are compared pixel by pixel, so they must be of one size; the threshold is a ΔE00.
fn check_comparable(
    (a, a_name): (&XyzImage, &str),
    (b, b_name): (&XyzImage, &str),
    threshold: f64,
) -> Result<()> {
    if (a.width, a.height) != (b.width, b.height) {
        bail!(
            "{a_name} is {}×{} and {b_name} {}×{}: compare images of one size (render both \
             with the same --width and --height)",
            a.width,
            a.height,
            b.width,
            b.height
        );
    }
    if !(threshold.is_finite() && threshold >= 0.0) {
        bail!(
            "--threshold {threshold}: use a ΔE00 of 0 or more (2 is about a just noticeable difference)"
        );
    }
    Ok(())
}

/// `delta-e.png`: the map, `cell` pixels wide, with its statistics and its colour scale.
fn delta_e_sheet(
    map: &DeltaEMap,
    (width, height): (usize, usize),
    cell: u32,
    names: String,
    caption: &str,
    footer: String,
) -> Rgb8 {
    let top = scale_max(&map.values);
    let grid = Grid {
        title: "CIEDE2000 between A and B, pixel by pixel",
        column_labels: vec![names],
        row_labels: vec!["ΔE00".into()],
        cells: vec![vec![Some(map_picture(map, width, height, top).resized_to_width(cell))]],
        captions: vec![vec![caption.to_owned()]],
        cell_width: cell,
        footer: vec![footer],
    }
    .render();
    let cell_h = (f64::from(cell) * height as f64 / width as f64).round() as u32;
    let bar = colour_bar(top, 6, 0, "ΔE00", cell_h);
    beside_colour_bar(&grid, &bar)
}

/// `split.png`: A on the left and B on the right of a line down the middle.
fn split(pa: &Rgb8, pb: &Rgb8) -> Rgb8 {
    let mut split = pa.clone();
    let half = split.width / 2;
    for y in 0..split.height {
        for x in half..split.width {
            split.put(x, y, pb.get(x, y));
        }
        split.put(half, y, INK);
    }
    split
}

pub fn run(args: &CompareArgs) -> Result<String> {
    let white: Exposure = args.white.parse().map_err(|e| anyhow::anyhow!("--white: {e}"))?;
    let a = read_exr(&args.a, MAX_PIXELS)?;
    let b = read_exr(&args.b, MAX_PIXELS)?;
    let (an, bn) = (args.a.display().to_string(), args.b.display().to_string());
    compare_images((&a, &an), (&b, &bn), (white, &args.white), args.threshold, &args.out)
}
