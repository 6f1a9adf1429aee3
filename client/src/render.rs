//! `restauro render`: a scene rendered in this process (the cluster will route the same work
//! through its workers), written as OpenEXR (absolute XYZ, RGB preview, optionally the spectral
//! layers) and PNG.

use crate::cli::{DisplayTarget, IntegratorArg, RenderArgs};
use crate::retinex::parse_exposure;
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use restauro_coordinator::image_files::{
    PngPixels, XyzImage, write_png, write_spectral_exr, write_xyz_exr,
};
use restauro_scene::load::{Limits, load_scene};
use restauro_scene::scene_file::Integrator;
use restauro_spectral::display::{DisplayParams, encode, to_u8};
use restauro_spectral::grid::{BANDS, wavelength_nm};
use restauro_spectral::rgb_space::RgbSpace;
use restauro_worker::prepared::{PreparedScene, Settings};
use restauro_worker::tile::{Rect, render_tile};
use std::fmt::Write as _;
use std::time::Instant;

pub fn run(args: &RenderArgs) -> Result<String> {
    let limits: Limits = (&args.limits).into();
    let mut scene = load_scene(&args.scene, &limits)?;
    if let Some(w) = args.width {
        scene.camera.width = w;
    }
    if let Some(h) = args.height {
        scene.camera.height = h;
    }
    let (w, h) = (scene.camera.width, scene.camera.height);
    let pixels = u64::from(w) * u64::from(h);
    if w == 0 || h == 0 || pixels > limits.max_pixels {
        bail!(
            "--width/--height give {w}×{h} pixels; use at least 1×1 and at most {} pixels (--max-pixels)",
            limits.max_pixels
        );
    }
    let exposure = parse_exposure(&args.exposure)?;
    let r = &scene.file.render;
    let settings = Settings {
        integrator: match args.integrator {
            Some(IntegratorArg::Whitted) => Integrator::Whitted,
            Some(IntegratorArg::Path) => Integrator::Path,
            None => r.integrator,
        },
        samples_per_pixel: args.spp.unwrap_or(r.samples_per_pixel),
        max_depth: r.max_depth,
        seed: r.seed,
    };
    if settings.samples_per_pixel == 0 || settings.samples_per_pixel > limits.max_samples_per_pixel
    {
        bail!(
            "--spp {}: use 1 to {} samples per pixel (--max-spp)",
            settings.samples_per_pixel,
            limits.max_samples_per_pixel
        );
    }
    if args.tile == 0 {
        bail!("--tile 0: a tile needs at least one pixel");
    }
    let started = Instant::now();
    let prepared = PreparedScene::new(&scene, args.variant.as_deref(), settings)?;
    let prepare_s = started.elapsed().as_secs_f64();

    let tiles: Vec<Rect> = (0..h)
        .step_by(args.tile as usize)
        .flat_map(|y| {
            (0..w).step_by(args.tile as usize).map(move |x| Rect {
                x,
                y,
                width: args.tile.min(w - x),
                height: args.tile.min(h - y),
            })
        })
        .collect();
    let bar = ProgressBar::with_draw_target(Some(tiles.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "render {bar:40} {pos}/{len} tiles, {elapsed} elapsed, eta {eta}",
        )
        .context("progress template")?,
    );
    let mut xyz = vec![[0.0f32; 3]; (w * h) as usize];
    let mut spectral: Vec<Vec<f32>> =
        if args.spectral { vec![vec![0.0; (w * h) as usize]; BANDS] } else { Vec::new() };
    let render_started = Instant::now();
    for rect in tiles {
        let tile = render_tile(&prepared, rect, args.spectral);
        for (i, p) in tile.xyz.iter().enumerate() {
            let (x, y) = (rect.x + i as u32 % rect.width, rect.y + i as u32 / rect.width);
            let at = (y * w + x) as usize;
            xyz[at] = *p;
            if let Some(s) = &tile.spectral {
                for (band, plane) in spectral.iter_mut().enumerate() {
                    plane[at] = s[i][band];
                }
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let render_s = render_started.elapsed().as_secs_f64();

    let stem = args.scene.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
    let name = match &args.variant {
        Some(v) => format!("{stem}-{v}"),
        None => stem.to_owned(),
    };
    let exr = args.out.join(format!("{name}.exr"));
    let png = args.out.join(format!("{name}.png"));
    let image = XyzImage { width: w as usize, height: h as usize, pixels: xyz, emitter: None };
    let integrator = format!("{:?}", settings.integrator).to_lowercase();
    let info = format!(
        "scene={} variant={} integrator={integrator} spp={} max_depth={} seed={}",
        args.scene.display(),
        args.variant.as_deref().unwrap_or("base"),
        settings.samples_per_pixel,
        settings.max_depth,
        settings.seed
    );
    let attrs = [
        ("restauroRender", info.as_str()),
        ("restauroXyzUnits", "absolute: Y in cd/m2 (K_m = 683 lm/W)"),
    ];
    if args.spectral {
        let bands = spectral.into_iter().enumerate().map(|(i, v)| (wavelength_nm(i), v)).collect();
        write_spectral_exr(&exr, &image, bands, &attrs)?;
    } else {
        write_xyz_exr(&exr, &image, &attrs)?;
    }
    let target = DisplayTarget { display_space: RgbSpace::Srgb, bits: 8 };
    let encoded = encode(&image.pixels, &DisplayParams { space: target.display_space, exposure });
    write_png(&png, image.width, image.height, &PngPixels::Eight(to_u8(&encoded)), RgbSpace::Srgb)?;

    let mean_y =
        image.pixels.iter().map(|p| f64::from(p[1])).sum::<f64>() / image.pixels.len() as f64;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "rendered {} ({w}×{h}, {integrator}, {} spp, {} triangles) in {render_s:.2} s after {prepare_s:.2} s of preparation; mean luminance {mean_y:.2} cd/m²",
        args.scene.display(),
        settings.samples_per_pixel,
        prepared.triangle_count()
    );
    let _ = writeln!(s, "wrote {}", exr.display());
    let _ = writeln!(s, "wrote {}", png.display());
    Ok(s)
}
