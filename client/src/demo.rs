//! `restauro demo`, in its first form: the colorimetric part of the paper's stone experiment
//! (Rossi, Marini & Rizzi 2004, Fig. 12). Travertine and pudding stone, as found and cleaned,
//! under CIE illuminants A, B, C and D65: their CIELAB colours, the CIEDE2000 difference that
//! cleaning makes, and how far each light moves each stone from its D65 colour with and without
//! chromatic adaptation — the gap the Retinex stage will close. The rendered facade replaces this
//! when the tracer and the cluster arrive.
//!
//! No measured spectrum of soiled travertine or puddinga exists in the shipped library, so the
//! as-found state is *derived*: an areal mixture of the clean stone with the carbon-black soot
//! proxy, ρ_found = (1 − f)·ρ_clean + f·ρ_soot with f = [`SOOT_FRACTION`]. It is labelled derived
//! wherever it appears.

use crate::cli::{AdaptArg, DemoArgs};
use crate::color::{Colour, Origin, Resolved, Viewing};
use anyhow::{Context, Result};
use restauro_coordinator::atomic_file;
use restauro_spectral::adaptation::{ConeSpace, adapt};
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::relative_xyz;
use restauro_spectral::rgb_space::RgbSpace;
use restauro_spectral::{Illuminant, Lab, Observer, library};
use serde::Serialize;
use std::fmt::Write as _;

/// The fraction of the surface covered by soot in the derived as-found state.
pub const SOOT_FRACTION: f32 = 0.25;
const SOOT: &str = "carbon_black_soot_proxy__usgs_GDS68";
const STONES: [(&str, &str); 2] = [
    ("travertine", "travertine_tufa_solid__eco_ward73"),
    ("pudding stone", "conglomerate_quartz_solid__eco_ward49"),
];
const LIGHTS: [Illuminant; 4] = [Illuminant::A, Illuminant::B, Illuminant::C, Illuminant::D65];

#[derive(Serialize)]
struct Row {
    stone: &'static str,
    state: &'static str,
    derived: bool,
    illuminant: String,
    colour: Colour,
    /// ΔE00 to the same stone under D65, with no adaptation (what a D65-balanced camera shows).
    delta_e00_to_d65_unadapted: f64,
    /// ΔE00 to the same stone under D65 after Bradford adaptation (a von Kries-type observer).
    delta_e00_to_d65_adapted: f64,
}

#[derive(Serialize)]
struct Cleaning {
    stone: &'static str,
    illuminant: String,
    /// ΔE00 between as found (reference) and cleaned.
    delta_e00: f64,
}

#[derive(Serialize)]
struct DemoReport {
    schema: &'static str,
    soot_fraction: f32,
    rows: Vec<Row>,
    cleaning: Vec<Cleaning>,
}

pub fn run(args: &DemoArgs) -> Result<String> {
    let soot = library::load_reflectance(SOOT)?;
    let observer = Observer::Cie1931TwoDegree;
    let d65 = Illuminant::D65.spd()?;
    let d65_white = restauro_spectral::colorimetry::white_point(&d65, observer);
    let mut rows = Vec::new();
    let mut cleaning = Vec::new();
    for (stone, stem) in STONES {
        let clean = library::load_reflectance(stem)?;
        let mut found = clean.clone();
        found.spectrum = clean.spectrum.lerp(&soot.spectrum, SOOT_FRACTION);
        let states = [
            (
                "cleaned",
                false,
                Resolved {
                    name: stem.to_owned(),
                    origin: Origin::Library { path: format!("data/spectra/{stem}.csv") },
                    loaded: clean,
                },
            ),
            (
                "as found",
                true,
                Resolved {
                    name: format!("{stem} + {SOOT_FRACTION} soot (derived)"),
                    origin: Origin::Library { path: format!("data/spectra/{stem}.csv") },
                    loaded: found,
                },
            ),
        ];
        for light in LIGHTS {
            let spd = light.spd()?;
            let viewing = Viewing::new(spd, observer, RgbSpace::Srgb, AdaptArg::Bradford);
            let mut labs = Vec::new();
            for (state, derived, resolved) in &states {
                let colour = viewing.colour(resolved);
                let reference = Lab::from_xyz(
                    relative_xyz(&resolved.loaded.spectrum, &d65, observer),
                    d65_white,
                );
                // Unadapted: the light's XYZ judged against the D65 white, as a D65-balanced camera.
                let xyz = colour.xyz;
                let unadapted = Lab::from_xyz(xyz, d65_white);
                let adapted = Lab::from_xyz(
                    adapt(xyz, viewing.white(), d65_white, ConeSpace::Bradford),
                    d65_white,
                );
                labs.push(colour.lab);
                rows.push(Row {
                    stone,
                    state,
                    derived: *derived,
                    illuminant: light.to_string(),
                    delta_e00_to_d65_unadapted: ciede2000(reference, unadapted),
                    delta_e00_to_d65_adapted: ciede2000(reference, adapted),
                    colour,
                });
            }
            cleaning.push(Cleaning {
                stone,
                illuminant: light.to_string(),
                delta_e00: ciede2000(labs[1], labs[0]),
            });
        }
    }
    let report = DemoReport {
        schema: "restauro.demo-stones/1",
        soot_fraction: SOOT_FRACTION,
        rows,
        cleaning,
    };

    let markdown = markdown(&report);
    let md_path = args.out.join("stones.md");
    let json_path = args.out.join("stones.json");
    atomic_file::write(&md_path, markdown.as_bytes())
        .with_context(|| format!("cannot write {}", md_path.display()))?;
    atomic_file::write(&json_path, (serde_json::to_string_pretty(&report)? + "\n").as_bytes())
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    Ok(format!("{markdown}\nwrote {}\nwrote {}\n", md_path.display(), json_path.display()))
}

fn markdown(r: &DemoReport) -> String {
    let mut s = String::new();
    let _ =
        writeln!(s, "# restauro demo: travertine and pudding stone under CIE A, B, C and D65\n");
    let _ = writeln!(
        s,
        "CIE 1931 2° observer; CIELAB relative to each light's white; sRGB after Bradford adaptation \
         to D65. *As found* is derived, not measured: {:.0} % of the surface covered by the carbon-black \
         soot proxy (areal mixture).\n",
        r.soot_fraction * 100.0
    );
    let _ = writeln!(
        s,
        "| stone | state | light | L* | a* | b* | sRGB | ΔE00 to D65, unadapted | ΔE00 to D65, adapted |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---|---:|---:|");
    for row in &r.rows {
        let c = &row.colour;
        let _ = writeln!(
            s,
            "| {} | {}{} | {} | {:.1} | {:.1} | {:.1} | `{}` | {:.2} | {:.2} |",
            row.stone,
            row.state,
            if row.derived { " (derived)" } else { "" },
            row.illuminant,
            c.lab.l,
            c.lab.a,
            c.lab.b,
            c.hex,
            row.delta_e00_to_d65_unadapted,
            row.delta_e00_to_d65_adapted
        );
    }
    let _ = writeln!(s, "\n## What cleaning changes (CIEDE2000, as found → cleaned)\n");
    let _ = writeln!(s, "| stone | light | ΔE00 |");
    let _ = writeln!(s, "|---|---|---:|");
    for c in &r.cleaning {
        let _ = writeln!(s, "| {} | {} | {:.2} |", c.stone, c.illuminant, c.delta_e00);
    }
    let _ = writeln!(s, "\n{}", library::ECOSTRESS_ACKNOWLEDGEMENT);
    s
}
