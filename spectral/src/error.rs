//! The one error type of restauro-spectral. Every message names the file (or the name the
//! caller gave), the line where there is one, what is wrong, and what to do about it.

use std::fmt;

/// What is wrong with a line or with the whole of a spectrum file. `Display` states the problem
/// and the fix.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumProblem {
    /// A line that is not `wavelength_nm,value`.
    FieldCount { found: usize },
    /// Text where a number belongs.
    NotANumber { field: &'static str, text: String },
    /// NaN or infinity.
    NotFinite { field: &'static str, text: String },
    /// A wavelength of zero or less.
    NonPositiveWavelength { wavelength_nm: f64 },
    /// A wavelength smaller than the one on the line before.
    Unsorted { previous_nm: f64, wavelength_nm: f64, previous_line: usize },
    /// The same wavelength twice.
    Duplicate { wavelength_nm: f64, previous_line: usize },
    /// A reflectance below 0 by more than measurement noise.
    Negative { value: f64, tolerance: f64 },
    /// A reflectance above 1: a passive surface cannot reflect more than it receives.
    AboveOne { value: f64 },
    /// Wavelengths that look like micrometres.
    Micrometres { largest: f64 },
    /// Fewer than two data lines.
    TooFewPoints { found: usize },
    /// The data do not reach across 380–780 nm.
    DoesNotCover { first_nm: f64, last_nm: f64 },
    /// A value so large that products with the colour-matching functions and K_m would overflow
    /// 32-bit floats.
    TooLarge { value: f64, max: f64 },
    /// A value that every band of the spectrum must exceed, e.g. a zero at 555 nm where the
    /// photometric normalisation divides by it.
    Degenerate { what: String },
}

impl fmt::Display for SpectrumProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SpectrumProblem::*;
        match self {
            FieldCount { found } => write!(
                f,
                "expected two fields `wavelength_nm,value`, found {found}; \
                 write one sample per line, separated by a comma"
            ),
            NotANumber { field, text } => write!(
                f,
                "the {field} `{text}` is not a number; write a decimal number such as 555 or 0.42 \
                 (only the first line may be a header)"
            ),
            NotFinite { field, text } => write!(
                f,
                "the {field} is `{text}`, which is not a finite number; replace it with the \
                 measured value or delete the line"
            ),
            NonPositiveWavelength { wavelength_nm } => write!(
                f,
                "the wavelength {wavelength_nm} nm is not positive; wavelengths are in nanometres"
            ),
            Unsorted { previous_nm, wavelength_nm, previous_line } => write!(
                f,
                "the wavelength {wavelength_nm} nm is smaller than {previous_nm} nm on line \
                 {previous_line}; sort the lines by increasing wavelength"
            ),
            Duplicate { wavelength_nm, previous_line } => write!(
                f,
                "the wavelength {wavelength_nm} nm already appears on line {previous_line}; \
                 keep one value per wavelength (average repeated measurements first)"
            ),
            Negative { value, tolerance } => write!(
                f,
                "the reflectance {value} is below 0 by more than the measurement-noise tolerance \
                 of {tolerance}; a reflectance is a fraction 0..1 (percent values must be divided \
                 by 100, and a negative calibration offset corrected)"
            ),
            AboveOne { value } => write!(
                f,
                "the reflectance {value} is above 1, which a passive surface cannot reflect; \
                 give reflectance as a fraction 0..1 (divide percent values by 100)"
            ),
            Micrometres { largest } => write!(
                f,
                "the largest wavelength is {largest}, which looks like micrometres; give \
                 wavelengths in nanometres (multiply by 1000)"
            ),
            TooFewPoints { found } => {
                write!(f, "found {found} data line(s), need at least 2 `wavelength_nm,value` lines")
            }
            DoesNotCover { first_nm, last_nm } => write!(
                f,
                "the data cover {first_nm}–{last_nm} nm but restauro renders 380–780 nm; add \
                 measurements that reach 380 and 780 nm, or allow extrapolation (`--extrapolate` \
                 on the command line) to hold the end values constant, which is then reported"
            ),
            TooLarge { value, max } => write!(
                f,
                "the value {value:e} is larger than the {max:e} restauro accepts (beyond it, \
                 colour and radiance sums overflow 32-bit floats); give the spectrum on a smaller \
                 scale, e.g. relative to 100 at 555 nm"
            ),
            Degenerate { what } => write!(f, "{what}"),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A spectrum file or text that cannot be used; `line` is 1-based where one line is at fault.
    #[error("{file}{}: {problem}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Spectrum { file: String, line: Option<usize>, problem: SpectrumProblem },

    /// An illuminant name that is not known.
    #[error(
        "unknown illuminant `{name}`; use one of A, B, C, D50, D55, D65, D75, E, F1–F12, \
         daylight:<CCT in K> (4000–25000), blackbody:<T in K>, or a CSV file of a relative \
         spectral power distribution{}",
        suggestion_text(suggestions)
    )]
    UnknownIlluminant { name: String, suggestions: Vec<String> },

    /// A name that is neither a file nor a spectrum of the shipped library.
    #[error(
        "`{name}` is neither a readable file nor a spectrum of the shipped library{}; \
         `restauro color --list` prints the library",
        suggestion_text(suggestions)
    )]
    UnknownSpectrum { name: String, suggestions: Vec<String> },

    /// An image that cannot be processed.
    #[error("image: {problem}")]
    Image { problem: String },

    /// A number outside the range where a formula holds.
    #[error("{quantity} = {value} is out of range: {expected}")]
    OutOfRange { quantity: &'static str, value: f64, expected: &'static str },

    /// A name that is none of a closed set's (a colour space, a chromatic adaptation, a
    /// Retinex channel space), with the names it may be.
    #[error("unknown {kind} `{name}`; use {choices}")]
    UnknownChoice { kind: &'static str, name: String, choices: &'static str },

    /// An exposure whose number is unusable.
    #[error("{0}")]
    Exposure(ExposureProblem),

    /// The number of an exposure given as text (`auto:<key>`, `absolute:<cd/m²>`) that is no
    /// number.
    #[error("`{text}` is not a number")]
    NotANumber { text: String },

    /// Exposure text of none of the forms.
    #[error("exposure `{text}`: use auto, auto:<key>, absolute:<cd/m²> or relative")]
    UnknownExposure { text: String },

    /// Exposure text whose number is unusable.
    #[error("exposure `{text}`: {problem}")]
    ExposureText { text: String, problem: ExposureProblem },
}

/// What is wrong with an exposure's number (`restauro_spectral::display::Exposure`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExposureProblem {
    #[error("an automatic exposure's key of {key}: use a number above 0, at most 1")]
    Key { key: f64 },
    #[error("an absolute exposure's white of {white_cd_m2} cd/m²: use a luminance above 0")]
    White { white_cd_m2: f64 },
}

fn suggestion_text(suggestions: &[String]) -> String {
    if suggestions.is_empty() {
        String::new()
    } else {
        format!(" (did you mean {}?)", suggestions.join(", "))
    }
}

impl Error {
    pub(crate) fn spectrum(file: &str, line: Option<usize>, problem: SpectrumProblem) -> Self {
        Error::Spectrum { file: file.to_owned(), line, problem }
    }

    /// The problem with a spectrum file, if that is what this error is.
    pub fn spectrum_problem(&self) -> Option<&SpectrumProblem> {
        match self {
            Error::Spectrum { problem, .. } => Some(problem),
            _ => None,
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
