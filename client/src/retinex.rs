//! `restauro retinex` and `restauro display`: from an XYZ (or RGB) OpenEXR image to what a
//! person standing there sees, and to a display.

use crate::cli::{DisplayArgs, DisplayTarget, RetinexArgs};
use anyhow::{Context, Result, bail};
use restauro_cluster::progress::Progress;
use restauro_image::image_files::{
    MAX_PIXELS, PngPixels, XyzImage, read_exr, write_png, write_xyz_exr,
};
use restauro_spectral::appearance::ChannelSpace;
use restauro_spectral::display::{DisplayParams, Exposure, encode, to_u8, to_u16};
use restauro_spectral::retinex::{RetinexParams, WhiteReference};
use restauro_spectral::seen::{Adaptation, SeenParams, SeenReport, seen_image};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Images with at least this many pixels get a progress bar.
const PROGRESS_FROM_PIXELS: usize = 1 << 20;

/// `--white area | paper`.
pub fn parse_white(text: &str) -> Result<WhiteReference> {
    match text.to_ascii_lowercase().as_str() {
        "area" => Ok(WhiteReference::Area),
        "paper" => Ok(WhiteReference::Paper),
        _ => bail!("--white `{text}`: use area (the default) or paper"),
    }
}

/// `--light-sources pass | keep`: the mask of the pixels the paths pass over.
pub fn parse_light_sources(text: &str, image: &XyzImage) -> Result<Option<Vec<bool>>> {
    match text.to_ascii_lowercase().as_str() {
        "pass" => Ok(image.emitter.clone()),
        "keep" => Ok(None),
        _ => bail!("--light-sources `{text}`: use pass (the default) or keep"),
    }
}

/// `--frameworks lights | none`: the keys of the frameworks of illumination.
pub fn parse_frameworks(text: &str, image: &XyzImage) -> Result<Option<Vec<u32>>> {
    match text.to_ascii_lowercase().as_str() {
        "lights" => Ok(image.lit_by.clone()),
        "none" => Ok(None),
        _ => bail!("--frameworks `{text}`: use lights (the default) or none"),
    }
}

/// `--exposure auto[:KEY] | absolute:<cd/m²> | relative`.
pub fn parse_exposure(text: &str) -> Result<Exposure> {
    text.parse().map_err(|e| anyhow::anyhow!("--{e}"))
}

fn write_display_png(
    path: &Path,
    width: usize,
    height: usize,
    xyz: &[[f32; 3]],
    target: &DisplayTarget,
    exposure: Exposure,
) -> Result<()> {
    let encoded = encode(xyz, &DisplayParams { space: target.display_space, exposure });
    let pixels = if target.bits == 16 {
        PngPixels::Sixteen(to_u16(&encoded))
    } else {
        PngPixels::Eight(to_u8(&encoded))
    };
    write_png(path, width, height, &pixels, target.display_space)?;
    Ok(())
}

/// `--adaptation auto | light | retinex` for `image`: auto is light when the file carries its
/// adapting white.
pub fn parse_adaptation(text: &str, space: ChannelSpace, image: &XyzImage) -> Result<Adaptation> {
    match text.to_ascii_lowercase().as_str() {
        "light" => Ok(Adaptation::Light),
        "retinex" => Ok(Adaptation::Retinex(space)),
        "auto" if image.white.is_some() => Ok(Adaptation::Light),
        "auto" => Ok(Adaptation::Retinex(space)),
        _ => bail!("--adaptation `{text}`: use auto (the default), light or retinex"),
    }
}

pub fn run(args: &RetinexArgs) -> Result<String> {
    let image = read_exr(&args.input, MAX_PIXELS)?;
    let params = seen_params(args, &image)?;
    let adaptation = parse_adaptation(&args.adaptation, args.space, &image)?;
    let bar = if image.pixels.len() >= PROGRESS_FROM_PIXELS {
        Progress::new("retinex", "paths", Some(0), "retinex {bar:40} {percent}% paths, eta {eta}")?
    } else {
        Progress::hidden()
    };
    let started = Instant::now();
    let (out, report) = seen_image(
        &image.pixels,
        image.white.as_deref(),
        (image.width, image.height),
        &params,
        adaptation,
        &|done, total| {
            bar.set_length(total);
            bar.set_position(done);
        },
    )
    .with_context(|| format!("{}", args.input.display()))?;
    bar.finish_and_clear();
    let seconds = started.elapsed().as_secs_f64();

    write_display_png(
        &args.out,
        image.width,
        image.height,
        &out,
        &args.display,
        Exposure::Relative,
    )?;
    let mut text = seen_summary(args, &image, adaptation, &report, seconds);
    let _ = writeln!(text, "wrote {}", args.out.display());
    if let Some(exr) = &args.exr {
        let settings = report.settings(&params);
        let result = XyzImage {
            width: image.width,
            height: image.height,
            pixels: out,
            emitter: image.emitter,
            lit_by: image.lit_by,
            white: None,
        };
        write_xyz_exr(
            exr,
            &result,
            &[
                ("restauroRetinex", settings.as_str()),
                ("restauroXyzScale", "relative: Y = 1 is the reference white, D65"),
            ],
        )?;
        let _ = writeln!(text, "wrote {}", exr.display());
    }
    Ok(text)
}

/// The seen image's parameters from the command line, checked in the order of its options.
fn seen_params(args: &RetinexArgs, image: &XyzImage) -> Result<SeenParams> {
    Ok(SeenParams {
        retinex: RetinexParams {
            paths: args.paths,
            reach: args.reach,
            length: args.length,
            threshold: args.threshold,
            seed: args.seed,
            white: parse_white(&args.white)?,
            emitters: parse_light_sources(&args.light_sources, image)?,
            frameworks: parse_frameworks(&args.frameworks, image)?,
            framework_weight: args.framework_weight,
            ..RetinexParams::default()
        },
        plane_weight: args.plane_weight,
        mesopic: !args.no_mesopic,
        history: None,
    })
}

/// What the seen image took: its paths and frameworks, and the light it adapted to (or a note
/// that the file carried none).
fn seen_summary(
    args: &RetinexArgs,
    image: &XyzImage,
    adaptation: Adaptation,
    report: &SeenReport,
    seconds: f64,
) -> String {
    let mut text = String::new();
    let stats = &report.retinex;
    let _ = writeln!(
        text,
        "seen image of {} ({}×{}) in {seconds:.2} s, adapted to the {}: {} samples per pixel at \
         least ({} at most), paths of {} steps, {} framework{} of illumination",
        args.input.display(),
        image.width,
        image.height,
        match adaptation {
            Adaptation::Light => "light the render measured".to_owned(),
            Adaptation::Retinex(space) => format!("Retinex's whites in {space}"),
        },
        stats.min_samples,
        stats.max_samples,
        stats.length,
        stats.frameworks,
        if stats.frameworks == 1 { "" } else { "s" },
    );
    if let Some(light) = &report.light {
        let _ = writeln!(
            text,
            "white level {:.4} cd/m² at x, y = {:.4}, {:.4}; degree of adaptation {:.2}–{:.2}; \
             mesopic coefficient {:.2}–{:.2}",
            light.white_level_cd_m2,
            light.white_xy.0,
            light.white_xy.1,
            light.degree[0],
            light.degree[2],
            light.mesopic[0],
            light.mesopic[2],
        );
    } else if args.adaptation == "auto" {
        let _ = writeln!(
            text,
            "note: {} carries no adapting white (a render from restauro does): adapted by the \
             Retinex alone",
            args.input.display()
        );
    }
    text
}

/// `restauro display --false-colour luminance`: the luminance map with its isolines and legend.
fn false_colour(args: &DisplayArgs, image: &XyzImage) -> Result<String> {
    use restauro_image::false_colour::{FalseColour, LEGEND_PX, Range, Unit, picture};
    let range = match &args.range {
        Some(text) => {
            let (min, max) = text
                .split_once(':')
                .and_then(|(a, b)| {
                    Some((a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?))
                })
                .ok_or_else(|| {
                    anyhow::anyhow!("--range `{text}`: give MIN:MAX in cd/m², e.g. 1:1000")
                })?;
            Range::new(min, max, args.scale).map_err(|e| anyhow::anyhow!("--range: {e}"))?
        }
        None => Range::auto(&image.pixels, args.scale),
    };
    let fc = FalseColour { scale: args.scale, range, bands: args.bands, unit: Unit::default() };
    let rgb = picture(&image.pixels, image.width, &fc);
    let height = image.height + LEGEND_PX;
    write_png(
        &args.out,
        image.width,
        height,
        &PngPixels::Eight(rgb),
        restauro_spectral::rgb_space::RgbSpace::Srgb,
    )
    .with_context(|| format!("writing {}", args.out.display()))?;
    Ok(format!(
        "wrote {}: luminance in false colour, {} scale from {} to {} cd/m², {} bands\n",
        args.out.display(),
        args.scale,
        range.min,
        range.max,
        args.bands
    ))
}

pub fn run_display(args: &DisplayArgs) -> Result<String> {
    let exposure = parse_exposure(&args.exposure)?;
    let image = read_exr(&args.input, MAX_PIXELS)?;
    if args.false_colour.is_some() {
        return false_colour(args, &image);
    }
    write_display_png(
        &args.out,
        image.width,
        image.height,
        &image.pixels,
        &args.display,
        exposure,
    )?;
    Ok(format!("wrote {}\n", args.out.display()))
}
