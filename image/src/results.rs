//! A finished render's files: the absolute XYZ image (OpenEXR, with the spectral layers when
//! kept) and its display PNG, and the seen image — the image as an adapted observer sees it,
//! adapted to the light the render measured with the paper's Retinex paths for lightness
//! (`restauro_spectral::seen`; paper §2.5) — as a relative-XYZ EXR and a PNG. Every file is written under a
//! temporary name and renamed, so a reader never sees half of one.

use crate::error::ImageError;
use crate::framebuffer::Framebuffer;
use crate::image_files::{
    PngPixels, XyzImage, write_png, write_render_exr, write_spectral_exr, write_xyz_exr,
};
use restauro_spectral::appearance::ChannelSpace;
use restauro_spectral::display::{DisplayParams, Exposure, encode, to_u8};
use restauro_spectral::grid::wavelength_nm;
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::rgb_space::RgbSpace;
use restauro_spectral::seen::{Adaptation, EyeHistory, EyeState, SeenParams, seen_image};
use std::path::Path;
use std::time::Instant;

/// What to write, beyond the pixels.
pub struct ResultOptions<'a> {
    /// The file stem: `<name>.exr`, `<name>.png`, `<name>-retinex.exr`, `<name>-retinex.png`.
    pub name: &'a str,
    /// Recorded in the EXR header (scene, variant, integrator, samples, seed).
    pub info: &'a str,
    pub exposure: Exposure,
    /// `None` skips the Retinex files.
    pub retinex: Option<RetinexParams>,
    /// For a frame of a sequence: the eye's state after the frame before and the time since
    /// (`restauro_spectral::seen::time_course`); `None` sees the image alone.
    pub eye: Option<EyeHistory>,
}

/// The files written (names within `dir`) and the Retinex time.
pub struct Written {
    pub files: Vec<String>,
    pub retinex_s: f64,
    /// The eye's state after the seen image (when it adapted to the render's light): the next
    /// frame's history.
    pub eye: Option<EyeState>,
}

fn write_display_png(path: &Path, image: &XyzImage, exposure: Exposure) -> Result<(), ImageError> {
    let encoded = encode(&image.pixels, &DisplayParams { space: RgbSpace::Srgb, exposure });
    write_png(path, image.width, image.height, &PngPixels::Eight(to_u8(&encoded)), RgbSpace::Srgb)?;
    Ok(())
}

/// The EXR attribute that marks a calculation grid's irradiance, and says how to read it.
pub const GRID_UNITS: &str = "illuminance: Y in lux (K_m = 683 lm/W); a column per grid point, \
                              row 0 direct, row 1 indirect";

/// Writes a finished calculation of the scene's grids (`Plan::grids`) into `dir`: one EXR,
/// `<name>.exr`, whose Y is illuminance in lux (with the 81 bands of the spectral irradiance
/// when kept). There is no picture to show and nothing for the Retinex to adapt to: the
/// client makes the grids' tables and maps from it.
pub fn write_grid_results(
    dir: &Path,
    frame: Framebuffer,
    name: &str,
    info: &str,
) -> Result<Written, ImageError> {
    let image = XyzImage {
        width: frame.width as usize,
        height: frame.height as usize,
        pixels: frame.xyz,
        emitter: None,
        lit_by: None,
        white: None,
    };
    let attrs = [("restauroRender", info), ("restauroXyzUnits", GRID_UNITS)];
    let file = format!("{name}.exr");
    match frame.spectral {
        Some(planes) => {
            let bands =
                planes.into_iter().enumerate().map(|(i, v)| (wavelength_nm(i), v)).collect();
            write_spectral_exr(&dir.join(&file), &image, bands, &attrs)?;
        }
        None => write_xyz_exr(&dir.join(&file), &image, &attrs)?,
    }
    Ok(Written { files: vec![file], retinex_s: 0.0, eye: None })
}

/// Writes a finished render's files into `dir`.
pub fn write_results(
    dir: &Path,
    frame: Framebuffer,
    options: &ResultOptions<'_>,
) -> Result<Written, ImageError> {
    let name = options.name;
    let (width, height) = (frame.width as usize, frame.height as usize);
    // A pixel most of whose camera samples saw the sky is a light source: marked in the EXR's
    // `emitter` channel, and kept from being the Retinex's white (a bright sky in view would
    // otherwise darken the building to a silhouette).
    let sky_at_least =
        |share: f32| frame.sky.as_ref().map(|c| c.iter().map(|&f| f >= share).collect::<Vec<_>>());
    let emitter = sky_at_least(0.5);
    // For the Retinex a pixel is a light source already when a tenth of its samples saw the
    // sky: the mixed pixels along a skyline are bright and blue, and as candidates for the white
    // they would give the whole building a yellow cast.
    let retinex_emitters = sky_at_least(0.1);
    // Which lights light each pixel: the frameworks of illumination the Retinex adapts to
    // apart (the sunlit stone, the sky-lit shadow); kept in the EXR's `lit_by` channel.
    let lit_by = frame.lit_by;
    let image = XyzImage {
        width,
        height,
        pixels: frame.xyz,
        emitter: emitter.clone(),
        lit_by: lit_by.clone(),
        white: frame.white,
    };
    let attrs = [
        ("restauroRender", options.info),
        ("restauroXyzUnits", "absolute: Y in cd/m2 (K_m = 683 lm/W)"),
    ];
    let mut files = vec![format!("{name}.exr"), format!("{name}.png")];
    let bands = frame
        .spectral
        .map(|planes| planes.into_iter().enumerate().map(|(i, v)| (wavelength_nm(i), v)).collect());
    write_render_exr(&dir.join(&files[0]), &image, bands, frame.samples.as_deref(), &attrs)?;
    write_display_png(&dir.join(&files[1]), &image, options.exposure)?;

    let mut retinex_s = 0.0;
    let mut eye = None;
    if let Some(params) = &options.retinex {
        let started = Instant::now();
        let mut params =
            SeenParams { retinex: params.clone(), history: options.eye, ..SeenParams::default() };
        if params.retinex.emitters.is_none() {
            params.retinex.emitters = retinex_emitters.clone();
        }
        if params.retinex.frameworks.is_none() {
            params.retinex.frameworks = lit_by.clone();
        }
        // A render carries its adapting white: the seen image adapts to the light it measured.
        // (A job stored before the white existed is seen by the Retinex alone.)
        let adaptation = match &image.white {
            Some(_) => Adaptation::Light,
            None => Adaptation::Retinex(ChannelSpace::default()),
        };
        let (perceived, report) = seen_image(
            &image.pixels,
            image.white.as_deref(),
            (width, height),
            &params,
            adaptation,
            &|_, _| {},
        )
        .map_err(ImageError::Retinex)?;
        retinex_s = started.elapsed().as_secs_f64();
        eye = report.light.as_ref().map(|l| l.eye);
        let settings = report.settings(&params);
        let perceived = XyzImage { width, height, pixels: perceived, emitter, lit_by, white: None };
        let exr = format!("{name}-retinex.exr");
        let png = format!("{name}-retinex.png");
        write_xyz_exr(
            &dir.join(&exr),
            &perceived,
            &[
                ("restauroRender", options.info),
                ("restauroRetinex", settings.as_str()),
                ("restauroXyzScale", "relative: Y = 1 is the reference white, D65"),
            ],
        )?;
        write_display_png(&dir.join(&png), &perceived, Exposure::Relative)?;
        files.push(exr);
        files.push(png);
    }
    Ok(Written { files, retinex_s, eye })
}
