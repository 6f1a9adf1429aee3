//! The command-line interface: argument definitions only. Each subcommand's work is a library
//! function the tests call directly.

use clap::{Args, Parser, Subcommand, ValueEnum};
use restauro_spectral::Observer;
use restauro_spectral::adaptation::ConeSpace;
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "restauro",
    version,
    about = "How an ancient building looks to a person standing in front of it: \
spectral rendering from measured stone reflectances and photometric light sources."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// The colour of a measured material under a light: XYZ, xy, L*a*b*, RGB and hex, and with
    /// --compare the CIEDE2000 difference between two materials.
    Color(ColorArgs),
    /// Write the demo: today the colorimetric part of the paper's stone experiment (travertine and
    /// pudding stone, as found and cleaned, under CIE A, B, C and D65).
    Demo(DemoArgs),
}

#[derive(Debug, Args)]
pub struct ColorArgs {
    /// A reflectance CSV file (`wavelength_nm,reflectance`), or the name (file stem) of a shipped
    /// spectrum; `--list` prints them.
    #[arg(required_unless_present = "list")]
    pub spectrum: Option<String>,

    /// The light: A, B, C, D50, D55, D65, D75, E, F1–F12, daylight:<CCT K>, blackbody:<T K>, or a
    /// CSV file of relative spectral power.
    #[arg(long, short = 'i', default_value = "D65")]
    pub illuminant: String,

    /// The CIE standard observer: 2 (CIE 1931) or 10 (CIE 1964).
    #[arg(long, value_enum, default_value = "2")]
    pub observer: ObserverArg,

    /// The display colour space for the RGB values: srgb, p3, rec2020 or adobe-rgb.
    #[arg(long, default_value = "srgb")]
    pub space: restauro_spectral::rgb_space::RgbSpace,

    /// How the colour seen under the light is carried to the display's D65 white for RGB:
    /// bradford, cat02, von-kries, or none (show the light's colour cast as a camera balanced
    /// for D65 would).
    #[arg(long, value_enum, default_value = "bradford")]
    pub adapt: AdaptArg,

    /// A second material: print its colour too and the CIEDE2000 difference between the two.
    #[arg(long)]
    pub compare: Option<String>,

    /// Hold the end values of a file that stops short of 380 or 780 nm constant, instead of
    /// refusing it (the extrapolation is reported). Shipped spectra always do this.
    #[arg(long)]
    pub extrapolate: bool,

    /// Print JSON (schema `restauro.color/1`, documented in docs/color-json.md).
    #[arg(long)]
    pub json: bool,

    /// List the shipped spectra and exit.
    #[arg(long)]
    pub list: bool,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Where to write the results.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObserverArg {
    /// CIE 1931 2°.
    #[value(name = "2")]
    Two,
    /// CIE 1964 10°.
    #[value(name = "10")]
    Ten,
}

impl From<ObserverArg> for Observer {
    fn from(o: ObserverArg) -> Observer {
        match o {
            ObserverArg::Two => Observer::Cie1931TwoDegree,
            ObserverArg::Ten => Observer::Cie1964TenDegree,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AdaptArg {
    Bradford,
    Cat02,
    VonKries,
    None,
}

impl AdaptArg {
    /// The chromatic adaptation transform, or `None` for no adaptation.
    pub fn cone_space(self) -> Option<ConeSpace> {
        match self {
            AdaptArg::Bradford => Some(ConeSpace::Bradford),
            AdaptArg::Cat02 => Some(ConeSpace::Cat02),
            AdaptArg::VonKries => Some(ConeSpace::VonKries),
            AdaptArg::None => None,
        }
    }
}
