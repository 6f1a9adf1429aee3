//! `restauro color`: what colour is this stone under this light, and how far is the cleaned
//! stone from the dirty one.

use crate::cli::{AdaptArg, ColorArgs};
use anyhow::{Context, Result};
use restauro_spectral::adaptation::adapt;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::{Chromaticity, relative_xyz, white_point};
use restauro_spectral::csv::{LoadedSpectrum, Quantity, load};
use restauro_spectral::rgb_space::RgbSpace;
use restauro_spectral::tabulated::{Coverage, Note};
use restauro_spectral::{Error, Illuminant, Lab, Observer, Spectrum, Xyz, library};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// The version tag of the JSON output; bumped when a field changes meaning or disappears.
pub const JSON_SCHEMA: &str = "restauro.color/1";

/// A spectrum as the user named it.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// What the user typed.
    pub name: String,
    /// `library` or `file`, and the path.
    pub origin: Origin,
    pub loaded: LoadedSpectrum,
}

#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Origin {
    Library { path: String },
    File { path: String },
}

fn coverage(extrapolate: bool) -> Coverage {
    if extrapolate { Coverage::HoldEnds } else { Coverage::Require }
}

/// The most bytes a spectrum file may have; real ones are a few kB.
const MAX_SPECTRUM_FILE_BYTES: u64 = 64 << 20;

fn read_file(path: &Path, quantity: Quantity, extrapolate: bool) -> Result<LoadedSpectrum> {
    let bytes = restauro_scene::assets::read_regular_file(
        path,
        MAX_SPECTRUM_FILE_BYTES,
        "a spectrum file is a few kB; check that this is the right file",
    )?;
    let text = restauro_scene::assets::utf8_text(bytes, path)?;
    Ok(load(&text, &path.display().to_string(), quantity, coverage(extrapolate))?)
}

/// A reflectance by file path or library name. A path that exists wins over a library name.
pub fn resolve_reflectance(name: &str, extrapolate: bool) -> Result<Resolved> {
    let path = Path::new(name);
    if path.is_file() {
        let loaded = read_file(path, Quantity::Reflectance, extrapolate)?;
        return Ok(Resolved {
            name: name.to_owned(),
            origin: Origin::File { path: name.to_owned() },
            loaded,
        });
    }
    if library::text(name).is_some() {
        let loaded = library::load_reflectance(name)?;
        let path = format!("data/spectra/{name}.csv");
        return Ok(Resolved { name: name.to_owned(), origin: Origin::Library { path }, loaded });
    }
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or(name);
    Err(Error::UnknownSpectrum { name: name.to_owned(), suggestions: library::suggest(stem) }
        .into())
}

/// An illuminant by CIE name or relative-power CSV file.
pub fn resolve_illuminant(name: &str, extrapolate: bool) -> Result<(String, Spectrum, Vec<Note>)> {
    match name.parse::<Illuminant>() {
        Ok(illuminant) => Ok((illuminant.to_string(), illuminant.spd()?, Vec::new())),
        Err(err) => {
            let path = Path::new(name);
            if path.is_file() {
                let loaded = read_file(path, Quantity::RelativePower, extrapolate)?;
                if loaded.spectrum.is_black() {
                    anyhow::bail!(
                        "{name}: the light emits nothing between 380 and 780 nm; check the file"
                    );
                }
                Ok((name.to_owned(), loaded.spectrum, loaded.notes))
            } else {
                Err(err.into())
            }
        }
    }
}

/// The colour of one material, every number of the report.
#[derive(Clone, Debug, Serialize)]
pub struct Colour {
    pub name: String,
    pub origin: Origin,
    /// Relative tristimulus values, Y = 100 for the perfect white under the illuminant.
    pub xyz: Xyz,
    /// Chromaticity; `null` for a black sample.
    pub xy: Option<Chromaticity>,
    /// CIELAB relative to the illuminant's white.
    pub lab: Lab,
    pub chroma: f64,
    pub hue_deg: f64,
    /// Linear display RGB (white = 1), after adaptation; may lie outside 0..1.
    pub rgb_linear: [f64; 3],
    /// Encoded RGB 0..1 through the display's transfer function, clipped to 0..1.
    pub rgb_encoded: [f64; 3],
    pub rgb8: [u8; 3],
    pub hex: String,
    /// False when a linear component lies outside 0..1 and was clipped.
    pub in_gamut: bool,
    /// What the reader did to the data: extrapolation, clamped noise.
    pub notes: Vec<Note>,
    /// The acknowledgement the data's licence requires, if any.
    pub acknowledgement: Option<&'static str>,
}

#[derive(Clone, Debug, Serialize)]
pub struct IlluminantReport {
    pub name: String,
    /// The white point, Y = 100.
    pub white_xyz: Xyz,
    pub notes: Vec<Note>,
}

/// The whole answer of `restauro color`.
#[derive(Clone, Debug, Serialize)]
pub struct ColorReport {
    pub schema: &'static str,
    pub illuminant: IlluminantReport,
    pub observer: Observer,
    pub space: RgbSpace,
    /// The chromatic adaptation to the display white, or "none".
    pub adaptation: String,
    pub sample: Colour,
    pub compare: Option<Colour>,
    /// CIEDE2000 between `sample` (reference) and `compare`, under the illuminant.
    pub delta_e00: Option<f64>,
}

/// Everything about one material under one light, shown on a display.
pub struct Viewing {
    pub illuminant: Spectrum,
    pub observer: Observer,
    pub space: RgbSpace,
    pub adapt: AdaptArg,
    white: Xyz,
}

impl Viewing {
    pub fn new(illuminant: Spectrum, observer: Observer, space: RgbSpace, adapt: AdaptArg) -> Self {
        let white = white_point(&illuminant, observer);
        Self { illuminant, observer, space, adapt, white }
    }

    pub fn white(&self) -> Xyz {
        self.white
    }

    /// The colour of `resolved` under this light.
    pub fn colour(&self, resolved: &Resolved) -> Colour {
        let xyz = relative_xyz(&resolved.loaded.spectrum, &self.illuminant, self.observer);
        let lab = Lab::from_xyz(xyz, self.white);
        // The display's white is Y = 1; carry the light's white onto it unless asked not to.
        let seen = xyz.scale(0.01);
        let on_display = match self.adapt.cone_space() {
            Some(cat) => adapt(seen, self.white.scale(0.01), self.space.white(), cat),
            None => seen,
        };
        let rgb_linear = self.space.linear_from_xyz(on_display);
        const EPS: f64 = 1e-9;
        let in_gamut = rgb_linear.iter().all(|v| (-EPS..=1.0 + EPS).contains(v));
        let transfer = self.space.transfer();
        let rgb_encoded = rgb_linear.map(|v| transfer.encode(v));
        let rgb8 = rgb_encoded.map(|v| (v * 255.0).round() as u8);
        let acknowledgement =
            library::requires_ecostress_acknowledgement(&resolved.loaded.comments)
                .then_some(library::ECOSTRESS_ACKNOWLEDGEMENT);
        Colour {
            name: resolved.name.clone(),
            origin: resolved.origin.clone(),
            xyz,
            xy: xyz.chromaticity(),
            lab,
            chroma: lab.chroma(),
            hue_deg: lab.hue_deg(),
            rgb_linear,
            rgb_encoded,
            rgb8,
            hex: format!("#{:02x}{:02x}{:02x}", rgb8[0], rgb8[1], rgb8[2]),
            in_gamut,
            notes: resolved.loaded.notes.clone(),
            acknowledgement,
        }
    }
}

/// Compute the report of `restauro color`.
pub fn report(args: &ColorArgs) -> Result<ColorReport> {
    let name = args.spectrum.as_deref().context("name a spectrum file or a shipped spectrum")?;
    let (illuminant_name, spd, illuminant_notes) =
        resolve_illuminant(&args.illuminant, args.extrapolate)?;
    let viewing = Viewing::new(spd, args.observer.into(), args.space, args.adapt);
    let sample = viewing.colour(&resolve_reflectance(name, args.extrapolate)?);
    let compare = match &args.compare {
        Some(other) => Some(viewing.colour(&resolve_reflectance(other, args.extrapolate)?)),
        None => None,
    };
    let delta_e00 = compare.as_ref().map(|c| ciede2000(sample.lab, c.lab));
    Ok(ColorReport {
        schema: JSON_SCHEMA,
        illuminant: IlluminantReport {
            name: illuminant_name,
            white_xyz: viewing.white(),
            notes: illuminant_notes,
        },
        observer: viewing.observer,
        space: args.space,
        adaptation: match args.adapt.cone_space() {
            Some(cat) => cat.to_string(),
            None => "none".to_owned(),
        },
        sample,
        compare,
        delta_e00,
    })
}

fn write_colour(out: &mut String, c: &Colour, space: RgbSpace) {
    let origin = match &c.origin {
        Origin::Library { path } => format!("shipped spectrum, {path}"),
        Origin::File { path } => format!("file {path}"),
    };
    let _ = writeln!(out, "{}  ({origin})", c.name);
    let _ = writeln!(
        out,
        "  XYZ       {:8.3} {:8.3} {:8.3}   (Y = 100 for the perfect white)",
        c.xyz.x, c.xyz.y, c.xyz.z
    );
    match c.xy {
        Some(xy) => {
            let _ = writeln!(out, "  xy        {:8.5} {:8.5}", xy.x, xy.y);
        }
        None => {
            let _ = writeln!(out, "  xy        (black: no chromaticity)");
        }
    }
    let _ = writeln!(
        out,
        "  L*a*b*    {:8.2} {:8.2} {:8.2}   (C* {:.2}, h {:.1}°)",
        c.lab.l, c.lab.a, c.lab.b, c.chroma, c.hue_deg
    );
    let [r, g, b] = c.rgb_linear;
    let _ = writeln!(out, "  {space:<9} {r:8.4} {g:8.4} {b:8.4}   linear");
    let [r, g, b] = c.rgb_encoded;
    let [r8, g8, b8] = c.rgb8;
    let _ =
        writeln!(out, "  {space:<9} {r:8.4} {g:8.4} {b:8.4}   encoded = {r8} {g8} {b8}  {}", c.hex);
    if !c.in_gamut {
        let _ = writeln!(
            out,
            "  note: outside the {space} gamut; the encoded values are clipped to 0..1"
        );
    }
    for note in &c.notes {
        let _ = writeln!(out, "  note: {note}");
    }
    if let Some(ack) = c.acknowledgement {
        let _ = writeln!(out, "  {ack}");
    }
}

/// The report as text for a terminal.
pub fn render_text(r: &ColorReport) -> String {
    let mut out = String::new();
    let adaptation = if r.adaptation == "none" {
        "without chromatic adaptation".to_owned()
    } else {
        format!("after {} adaptation to the display's D65 white", r.adaptation)
    };
    let _ = writeln!(
        out,
        "under {}, {} observer; RGB in {} {adaptation}",
        r.illuminant.name, r.observer, r.space
    );
    for note in &r.illuminant.notes {
        let _ = writeln!(out, "  note on the light: {note}");
    }
    write_colour(&mut out, &r.sample, r.space);
    if let (Some(c), Some(de)) = (&r.compare, r.delta_e00) {
        write_colour(&mut out, c, r.space);
        let _ = writeln!(
            out,
            "CIEDE2000 ΔE00 = {de:.3}  ({} → {}, under {})",
            r.sample.name, c.name, r.illuminant.name
        );
    }
    out
}

/// The library listing of `restauro color --list`: each stem and its `# material:` line.
pub fn list_library() -> String {
    let mut out = String::new();
    for name in library::names() {
        let material = library::material(name).unwrap_or("");
        let _ = writeln!(out, "{name:<55} {material}");
    }
    out
}

/// Run `restauro color`, returning what it prints.
pub fn run(args: &ColorArgs) -> Result<String> {
    if args.list {
        return Ok(list_library());
    }
    let report = report(args)?;
    if args.json {
        Ok(serde_json::to_string_pretty(&report)? + "\n")
    } else {
        Ok(render_text(&report))
    }
}
