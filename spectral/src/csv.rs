//! The reader for spectrum files: `wavelength_nm,value` per line, `#` comments (whole lines or
//! after the data), blank lines, and one optional header line before the data.
//!
//! Every refusal names the file and the line and says what to do. Small negative reflectances
//! (spectrometer noise near the ends of a measurement) are clamped to 0 and reported, never
//! silently.

use crate::error::{Error, Result, SpectrumProblem};
use crate::spectrum::Spectrum;
use crate::tabulated::{Coverage, Note, TabulatedSpectrum};

/// What the values of a file are; decides which values are refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// A hemispherical reflectance, a fraction 0..1.
    Reflectance,
    /// A relative spectral power distribution (any scale, not negative).
    RelativePower,
}

/// Below this a negative value is an error rather than measurement noise. Spectrometers read a
/// few thousandths below zero at the ends of their range on dark samples (the USGS lichen and
/// carbon-black spectra do); a value of −0.05 is an offset error, not noise.
pub const NEGATIVE_NOISE_TOLERANCE: f64 = 0.01;

/// The largest value a spectrum file may hold. A relative spectral power may be on any scale,
/// but it is multiplied by the colour-matching functions (≤ 2.2), K_m = 683 lm/W and Δλ = 5 nm
/// and summed over 81 bands in 32-bit floats: 10²⁵ × 2.2 × 683 × 5 × 81 ≈ 6 × 10³⁰ stays far
/// inside f32's 3.4 × 10³⁸, while files in photons per second and square metre (about 10¹⁹ for
/// sunlight) still read.
pub const MAX_VALUE: f64 = 1e25;

/// A spectrum file as read: the data, its `#` comment lines (provenance), and notes on what the
/// reader changed.
#[derive(Clone, Debug)]
pub struct SpectrumFile {
    pub data: TabulatedSpectrum,
    /// The text of the `#` comment lines, without the `#` and surrounding blanks.
    pub comments: Vec<String>,
    pub notes: Vec<Note>,
    /// The 1-based line number of each data point, for messages about the data as a whole.
    pub lines: Vec<usize>,
}

/// A spectrum file resampled onto the grid, with everything the reader and the resampler noted.
#[derive(Clone, Debug)]
pub struct LoadedSpectrum {
    pub spectrum: Spectrum,
    pub comments: Vec<String>,
    pub notes: Vec<Note>,
    /// The measured range, in nm.
    pub range_nm: (f64, f64),
}

fn parse_field(text: &str, field: &'static str) -> std::result::Result<f64, SpectrumProblem> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(SpectrumProblem::NotFinite { field, text: text.to_owned() }),
        Err(_) => Err(SpectrumProblem::NotANumber { field, text: text.to_owned() }),
    }
}

/// Parse the text of a spectrum file. `file` names it in messages.
pub fn parse(text: &str, file: &str, quantity: Quantity) -> Result<SpectrumFile> {
    let mut points = Points::default();
    let mut comments = Vec::new();
    let mut header_allowed = true;

    // Spreadsheet exports often begin with a UTF-8 byte-order mark; without this the first data
    // line would not parse as a number and be taken for a header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let err = |problem| Error::spectrum(file, Some(line), problem);
        let trimmed = raw.trim();
        if let Some(comment) = trimmed.strip_prefix('#') {
            comments.push(comment.trim().to_owned());
            continue;
        }
        let content = trimmed.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let Some((wavelength, value)) = data_point(content, &mut header_allowed).map_err(err)?
        else {
            continue;
        };
        points.push(line, wavelength, value, quantity).map_err(err)?;
    }
    points.finish(file, comments)
}

/// The wavelength and value on a line with content, or `None` for the header: the first such
/// line, when its first field is not a number.
fn data_point(
    content: &str,
    header_allowed: &mut bool,
) -> std::result::Result<Option<(f64, f64)>, SpectrumProblem> {
    let fields: Vec<&str> = content.split(',').map(str::trim).collect();
    if fields.len() != 2 {
        // A header may name more columns than two, but data may not.
        if *header_allowed && fields[0].parse::<f64>().is_err() {
            *header_allowed = false;
            return Ok(None);
        }
        return Err(SpectrumProblem::FieldCount { found: fields.len() });
    }
    let wavelength = match parse_field(fields[0], "wavelength") {
        Ok(v) => v,
        Err(SpectrumProblem::NotANumber { .. }) if *header_allowed => {
            *header_allowed = false;
            return Ok(None);
        }
        Err(p) => return Err(p),
    };
    *header_allowed = false;
    let value = parse_field(fields[1], "value")?;
    Ok(Some((wavelength, value)))
}

/// The data points read so far, each checked against the one before it.
#[derive(Default)]
struct Points {
    wavelengths: Vec<f64>,
    values: Vec<f64>,
    /// The 1-based line of each point.
    lines: Vec<usize>,
    /// The negative values clamped to 0: (count, most negative, first line).
    clamped: Option<(usize, f64, usize)>,
}

impl Points {
    /// Adds the point on line `line`, after its checks: the wavelength positive and above the
    /// one before, the value as `quantity` allows.
    fn push(
        &mut self,
        line: usize,
        wavelength: f64,
        value: f64,
        quantity: Quantity,
    ) -> std::result::Result<(), SpectrumProblem> {
        if wavelength <= 0.0 {
            return Err(SpectrumProblem::NonPositiveWavelength { wavelength_nm: wavelength });
        }
        self.check_order(wavelength)?;
        let value = self.checked_value(line, value, quantity)?;
        self.wavelengths.push(wavelength);
        self.values.push(value);
        self.lines.push(line);
        Ok(())
    }

    /// Refuses a wavelength equal to or below the previous point's.
    fn check_order(&self, wavelength: f64) -> std::result::Result<(), SpectrumProblem> {
        let (Some(&previous_nm), Some(&previous_line)) =
            (self.wavelengths.last(), self.lines.last())
        else {
            return Ok(());
        };
        if wavelength == previous_nm {
            return Err(SpectrumProblem::Duplicate { wavelength_nm: wavelength, previous_line });
        }
        if wavelength < previous_nm {
            return Err(SpectrumProblem::Unsorted {
                previous_nm,
                wavelength_nm: wavelength,
                previous_line,
            });
        }
        Ok(())
    }

    /// The value as kept: noise just below zero clamped to 0 (and counted), anything else
    /// below, above one for a reflectance, or above [`MAX_VALUE`] refused.
    fn checked_value(
        &mut self,
        line: usize,
        mut value: f64,
        quantity: Quantity,
    ) -> std::result::Result<f64, SpectrumProblem> {
        if value < 0.0 {
            if value < -NEGATIVE_NOISE_TOLERANCE {
                return Err(SpectrumProblem::Negative {
                    value,
                    tolerance: NEGATIVE_NOISE_TOLERANCE,
                });
            }
            let c = self.clamped.get_or_insert((0, 0.0, line));
            c.0 += 1;
            c.1 = c.1.min(value);
            value = 0.0;
        }
        if quantity == Quantity::Reflectance && value > 1.0 {
            return Err(SpectrumProblem::AboveOne { value });
        }
        if value > MAX_VALUE {
            return Err(SpectrumProblem::TooLarge { value, max: MAX_VALUE });
        }
        Ok(value)
    }

    /// The file, after the checks on the data as a whole: at least two points, in nanometres.
    fn finish(self, file: &str, comments: Vec<String>) -> Result<SpectrumFile> {
        let Points { wavelengths, values, lines, clamped } = self;
        if wavelengths.len() < 2 {
            return Err(Error::spectrum(
                file,
                None,
                SpectrumProblem::TooFewPoints { found: wavelengths.len() },
            ));
        }
        let largest = *wavelengths.last().expect("two points");
        if largest < 100.0 {
            let line = *lines.last().expect("two points");
            return Err(Error::spectrum(
                file,
                Some(line),
                SpectrumProblem::Micrometres { largest },
            ));
        }
        let notes = clamped
            .map(|(count, most_negative, first_line)| Note::ClampedNegative {
                count,
                most_negative,
                first_line,
            })
            .into_iter()
            .collect();
        Ok(SpectrumFile {
            data: TabulatedSpectrum::new(file, wavelengths, values)?,
            comments,
            notes,
            lines,
        })
    }
}

/// Parse and resample onto the grid in one step.
pub fn load(
    text: &str,
    file: &str,
    quantity: Quantity,
    coverage: Coverage,
) -> Result<LoadedSpectrum> {
    let SpectrumFile { data, comments, mut notes, lines } = parse(text, file, quantity)?;
    let (spectrum, more) = data.resample(coverage).map_err(|e| match e {
        // Point at the line where the data stop short: the first line if they start above
        // 380 nm, else the last.
        Error::Spectrum {
            file,
            line: None,
            problem: problem @ SpectrumProblem::DoesNotCover { first_nm, .. },
        } => {
            let line =
                if first_nm > crate::grid::LAMBDA_MIN_NM { lines.first() } else { lines.last() };
            Error::Spectrum { file, line: line.copied(), problem }
        }
        other => other,
    })?;
    notes.extend(more);
    Ok(LoadedSpectrum { spectrum, comments, notes, range_nm: data.range_nm() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(text: &str, quantity: Quantity) -> (Option<usize>, SpectrumProblem, String) {
        let err = parse(text, "stone.csv", quantity).unwrap_err();
        let message = err.to_string();
        match err {
            Error::Spectrum { file, line, problem } => {
                assert_eq!(file, "stone.csv");
                assert!(message.starts_with("stone.csv"), "{message}");
                (line, problem, message)
            }
            other => panic!("unexpected error {other}"),
        }
    }

    #[test]
    fn reads_comments_header_and_inline_comments() {
        let text =
            "# material: test\n\nwavelength_nm,reflectance\n380, 0.1\n500,0.2 # peak\r\n780,0.3\n";
        let f = parse(text, "t.csv", Quantity::Reflectance).unwrap();
        assert_eq!(f.comments, vec!["material: test"]);
        assert_eq!(f.data.wavelengths_nm, vec![380.0, 500.0, 780.0]);
        assert_eq!(f.data.values, vec![0.1, 0.2, 0.3]);
        assert!(f.notes.is_empty());
    }

    #[test]
    fn a_byte_order_mark_does_not_hide_the_first_line() {
        let f = parse("\u{feff}380,0.1\n780,0.3\n", "t.csv", Quantity::Reflectance).unwrap();
        assert_eq!(f.data.wavelengths_nm, vec![380.0, 780.0]);
    }

    #[test]
    fn refuses_unsorted_wavelengths() {
        let (line, p, msg) = problem("380,0.1\n500,0.2\n450,0.3\n", Quantity::Reflectance);
        assert_eq!(line, Some(3));
        assert!(matches!(p, SpectrumProblem::Unsorted { previous_line: 2, .. }));
        assert!(msg.contains("sort the lines"), "{msg}");
    }

    #[test]
    fn refuses_duplicate_wavelengths() {
        let (line, p, msg) = problem("# c\n380,0.1\n380,0.2\n", Quantity::Reflectance);
        assert_eq!(line, Some(3));
        assert!(matches!(p, SpectrumProblem::Duplicate { previous_line: 2, .. }));
        assert!(msg.contains("already appears on line 2"), "{msg}");
    }

    #[test]
    fn refuses_text_in_a_number_field() {
        let (line, p, msg) = problem("wavelength,value\n380,0.1\n385,abc\n", Quantity::Reflectance);
        assert_eq!(line, Some(3));
        assert!(matches!(p, SpectrumProblem::NotANumber { field: "value", .. }));
        assert!(msg.starts_with("stone.csv:3: the value `abc` is not a number"), "{msg}");
        // A second header-like line, after the data started, is text in a number field.
        let (line, _, _) = problem("380,0.1\nfoo,0.2\n", Quantity::Reflectance);
        assert_eq!(line, Some(2));
    }

    #[test]
    fn refuses_nan_and_infinity() {
        for bad in ["NaN", "inf", "-infinity"] {
            let (line, p, msg) = problem(&format!("380,0.1\n385,{bad}\n"), Quantity::Reflectance);
            assert_eq!(line, Some(2));
            assert!(matches!(p, SpectrumProblem::NotFinite { .. }), "{bad}");
            assert!(msg.contains("not a finite number"), "{msg}");
        }
        let (line, p, _) = problem("380,0.1\nnan,0.2\n", Quantity::Reflectance);
        assert_eq!(line, Some(2));
        assert!(matches!(p, SpectrumProblem::NotFinite { field: "wavelength", .. }));
    }

    #[test]
    fn refuses_reflectance_out_of_range() {
        let (line, p, msg) = problem("380,0.1\n385,1.2\n", Quantity::Reflectance);
        assert_eq!(line, Some(2));
        assert_eq!(p, SpectrumProblem::AboveOne { value: 1.2 });
        assert!(msg.contains("divide percent values by 100"), "{msg}");
        let (line, p, _) = problem("380,0.1\n385,-0.2\n", Quantity::Reflectance);
        assert_eq!(line, Some(2));
        assert!(matches!(p, SpectrumProblem::Negative { .. }));
        // A relative power distribution may exceed 1 but not be negative.
        assert!(parse("380,10\n385,120\n", "s.csv", Quantity::RelativePower).is_ok());
        assert!(parse("380,10\n385,-5\n", "s.csv", Quantity::RelativePower).is_err());
    }

    #[test]
    fn refuses_values_whose_products_would_overflow() {
        // 1e300 is finite as f64, but not as the f32 of a spectrum, nor once multiplied by the
        // colour-matching functions: refused with the bound, on its line.
        let (line, p, msg) = problem("380,1e300\n780,1e300\n", Quantity::RelativePower);
        assert_eq!(line, Some(1));
        assert!(matches!(p, SpectrumProblem::TooLarge { .. }), "{p:?}");
        assert!(msg.contains("larger than the 1e25 restauro accepts"), "{msg}");
        // Photon-count scales still read.
        assert!(parse("380,4e18\n780,2e19\n", "s.csv", Quantity::RelativePower).is_ok());
    }

    #[test]
    fn clamps_and_reports_noise_below_zero() {
        let f = parse("380,-0.002\n385,-0.004\n390,0.1\n", "s.csv", Quantity::Reflectance).unwrap();
        assert_eq!(f.data.values, vec![0.0, 0.0, 0.1]);
        assert_eq!(
            f.notes,
            vec![Note::ClampedNegative { count: 2, most_negative: -0.004, first_line: 1 }]
        );
        assert!(f.notes[0].to_string().contains("clamped to 0"));
    }

    #[test]
    fn refuses_wrong_shapes() {
        let (line, p, _) = problem("380,0.1,7\n", Quantity::Reflectance);
        assert_eq!((line, p), (Some(1), SpectrumProblem::FieldCount { found: 3 }));
        let (line, p, _) = problem("# only\n380,0.1\n", Quantity::Reflectance);
        assert_eq!((line, p), (None, SpectrumProblem::TooFewPoints { found: 1 }));
        let (line, p, msg) = problem("0.38,0.1\n0.78,0.2\n", Quantity::Reflectance);
        assert_eq!((line, p), (Some(2), SpectrumProblem::Micrometres { largest: 0.78 }));
        assert!(msg.contains("nanometres"));
        let (_, p, _) = problem("-5,0.1\n385,0.2\n", Quantity::Reflectance);
        assert!(matches!(p, SpectrumProblem::NonPositiveWavelength { .. }));
    }

    #[test]
    fn refuses_a_range_short_of_the_grid_unless_allowed() {
        let text = "400,0.2\n780,0.4\n";
        let err = load(text, "short.csv", Quantity::Reflectance, Coverage::Require).unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with("short.csv:1: the data cover 400–780 nm"), "{msg}");
        assert!(msg.contains("--extrapolate"), "{msg}");
        let loaded = load(text, "short.csv", Quantity::Reflectance, Coverage::HoldEnds).unwrap();
        assert_eq!(loaded.spectrum[0], 0.2);
        assert_eq!(loaded.notes.len(), 1);
        assert!(loaded.notes[0].to_string().starts_with("380–395 nm extrapolated"));
    }
}
