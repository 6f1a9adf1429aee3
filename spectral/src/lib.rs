//! restauro-spectral: the colour science of restauro, after Rossi, Marini & Rizzi (2004).
//!
//! Pure maths, no I/O beyond parsing text it is handed:
//!
//! | module | what |
//! |---|---|
//! | [`grid`] | the wavelength grid, 380–780 nm in 5 nm steps (81 bands) |
//! | [`spectrum`] | [`Spectrum`], a fixed `[f32; 81]` with band-by-band arithmetic |
//! | [`tabulated`] | measured spectra of any spacing and their resampling onto the grid |
//! | [`csv`] | the `wavelength_nm,value` spectrum file reader |
//! | [`library`] | the shipped measured stone spectra, by file stem |
//! | [`cie`] | the CIE tables: colour-matching functions, V(λ), illuminants, daylight basis |
//! | [`illuminant`] | named illuminants, CIE daylight of any CCT |
//! | [`planck`] | Planck's law and illuminant A |
//! | [`colorimetry`] | spectrum → XYZ, absolute (K_m = 683 lm/W) and relative (Y = 100) |
//! | [`lab`] | CIELAB |
//! | [`ciede2000`] | the CIEDE2000 colour difference |
//! | [`adaptation`] | chromatic adaptation: von Kries, Bradford, CAT02 |
//! | [`rgb_space`] | display RGB spaces from primaries: sRGB, Display P3, Rec. 2020, Adobe RGB |
//! | [`rgb_upsampling`] | linear sRGB reflectance → smooth spectrum, after Jakob & Hanika (2019) |
//! | [`photometry`] | the paper's Eq. 2 and Eq. 8, and distant sources in lux |
//! | [`keyed_random`] | random numbers that are pure functions of a key |
//! | [`retinex`] | the Marini–Rizzi Brownian-path Retinex |
//! | [`appearance`] | the Retinex in cone (LMS) or RGB space, from XYZ to what an observer sees |
//! | [`seen`] | what a person sees: the render adapted to the light the renderer measured there |
//! | [`display`] | XYZ to display code values: exposure, tone curve, gamut mapping, encoding |
//! | [`tone`] | the display's tone curve: the reference white at 0.7, a linear part, a shoulder |

pub mod adaptation;
pub mod appearance;
pub mod cie;
pub mod ciede2000;
pub mod colorimetry;
pub mod csv;
pub mod display;
pub mod error;
pub mod grid;
pub mod illuminant;
pub mod keyed_random;
pub mod lab;
pub mod library;
pub mod photometry;
pub mod planck;
pub mod retinex;
pub mod rgb_space;
pub mod rgb_upsampling;
pub mod seen;
pub mod spectrum;
pub mod tabulated;
pub mod tone;

pub use colorimetry::{Chromaticity, Observer, Xyz};
pub use error::{Error, Result};
pub use illuminant::Illuminant;
pub use lab::Lab;
pub use spectrum::Spectrum;
