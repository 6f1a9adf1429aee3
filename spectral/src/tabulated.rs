//! A spectrum as measured: values at wavelengths of any spacing and range, and its resampling
//! onto the 81-band grid.
//!
//! Resampling rule, band by band (λᵢ = 380, 385, … 780 nm, window λᵢ ± 2.5 nm):
//! * where the data are finer than the grid (two or more samples inside the window) the band
//!   value is the mean of the piecewise-linear measured curve over the window, clipped to the
//!   measured range — a 5 nm box filter that uses every measured sample and averages away the
//!   noise of 1 nm spectrometer data instead of picking one sample in five;
//! * elsewhere (data at 5 nm or coarser) it is the linear interpolation at λᵢ, so a table given
//!   on the grid is reproduced exactly.
//!
//! Outside the measured range nothing is invented unless the caller allows it
//! ([`Coverage::HoldEnds`]), and then every extrapolated stretch is reported as a [`Note`].

use crate::error::{Error, Result, SpectrumProblem};
use crate::grid::{BANDS, STEP_NM, wavelength_nm};
use crate::spectrum::Spectrum;
use serde::Serialize;
use std::fmt;

/// A validated measured spectrum: strictly increasing, finite wavelengths (nm) and finite values.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedSpectrum {
    /// Where it came from (a path or a library name), for messages.
    pub source: String,
    pub wavelengths_nm: Vec<f64>,
    pub values: Vec<f64>,
}

/// What to do where the data stop short of 380 or 780 nm.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coverage {
    /// Refuse the spectrum with [`SpectrumProblem::DoesNotCover`].
    #[default]
    Require,
    /// Hold the first (last) measured value constant below (above) the data, and report it.
    HoldEnds,
}

/// Something the reader or the resampler did to the data that the user should know about.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Note {
    /// Bands from `from_nm` to `to_nm` (inclusive) had no data and hold the value measured at
    /// `held_from_nm`.
    Extrapolated { from_nm: f64, to_nm: f64, held_from_nm: f64, value: f64 },
    /// `count` small negative values (measurement noise, the most negative `most_negative`, the
    /// first on line `first_line`) were set to 0.
    ClampedNegative { count: usize, most_negative: f64, first_line: usize },
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::Extrapolated { from_nm, to_nm, held_from_nm, value } => write!(
                f,
                "{from_nm}–{to_nm} nm extrapolated: not measured, the value {value} at \
                 {held_from_nm} nm is held constant"
            ),
            Note::ClampedNegative { count, most_negative, first_line } => write!(
                f,
                "{count} slightly negative value(s) (measurement noise, down to {most_negative}, \
                 first on line {first_line}) clamped to 0"
            ),
        }
    }
}

impl TabulatedSpectrum {
    /// Check the invariants (at least two points, strictly increasing finite wavelengths, finite
    /// values) and build. Readers that know line numbers check these themselves first, so that
    /// their messages can name the line; this is the backstop for data built in code.
    pub fn new(source: &str, wavelengths_nm: Vec<f64>, values: Vec<f64>) -> Result<Self> {
        let bad = |problem| Err(Error::spectrum(source, None, problem));
        if wavelengths_nm.len() != values.len() || wavelengths_nm.len() < 2 {
            return bad(SpectrumProblem::TooFewPoints {
                found: wavelengths_nm.len().min(values.len()),
            });
        }
        for (i, (&w, &v)) in wavelengths_nm.iter().zip(&values).enumerate() {
            if !w.is_finite() {
                return bad(SpectrumProblem::NotFinite {
                    field: "wavelength",
                    text: w.to_string(),
                });
            }
            if !v.is_finite() {
                return bad(SpectrumProblem::NotFinite { field: "value", text: v.to_string() });
            }
            if i > 0 && w <= wavelengths_nm[i - 1] {
                return bad(SpectrumProblem::Unsorted {
                    previous_nm: wavelengths_nm[i - 1],
                    wavelength_nm: w,
                    previous_line: i,
                });
            }
        }
        Ok(Self { source: source.to_owned(), wavelengths_nm, values })
    }

    /// The first and last measured wavelength, in nm.
    pub fn range_nm(&self) -> (f64, f64) {
        (self.wavelengths_nm[0], *self.wavelengths_nm.last().expect("at least two points"))
    }

    /// The linear interpolation of the data at `x` nm, `x` inside the measured range.
    fn interpolate(&self, x: f64) -> f64 {
        let w = &self.wavelengths_nm;
        // Index of the first sample strictly greater than x, kept inside 1..len-1.
        let j = w.partition_point(|&v| v <= x).clamp(1, w.len() - 1);
        let (x0, x1) = (w[j - 1], w[j]);
        let (y0, y1) = (self.values[j - 1], self.values[j]);
        y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    }

    /// The integral of the piecewise-linear curve over [a, b], both inside the measured range.
    fn integrate(&self, a: f64, b: f64) -> f64 {
        let w = &self.wavelengths_nm;
        let mut total = 0.0;
        let mut x = a;
        let mut y = self.interpolate(a);
        let start = w.partition_point(|&v| v <= a);
        for &knot in w[start..].iter().take_while(|&&k| k < b) {
            let yk = self.interpolate(knot);
            total += 0.5 * (y + yk) * (knot - x);
            x = knot;
            y = yk;
        }
        let yb = self.interpolate(b);
        total + 0.5 * (y + yb) * (b - x)
    }

    /// Resample onto the 81-band grid by the rule in the module documentation.
    pub fn resample(&self, coverage: Coverage) -> Result<(Spectrum, Vec<Note>)> {
        let (first, last) = self.range_nm();
        let (grid_first, grid_last) = (wavelength_nm(0), wavelength_nm(BANDS - 1));
        let covers = first <= grid_first && last >= grid_last;
        if !covers && coverage == Coverage::Require {
            return Err(Error::spectrum(
                &self.source,
                None,
                SpectrumProblem::DoesNotCover { first_nm: first, last_nm: last },
            ));
        }
        let half = STEP_NM / 2.0;
        let w = &self.wavelengths_nm;
        let mut out = Spectrum::ZERO;
        for i in 0..BANDS {
            let lambda = wavelength_nm(i);
            let value = if lambda < first {
                self.values[0]
            } else if lambda > last {
                *self.values.last().expect("at least two points")
            } else {
                let inside = w.partition_point(|&v| v < lambda + half)
                    - w.partition_point(|&v| v <= lambda - half);
                if inside >= 2 {
                    let (a, b) = ((lambda - half).max(first), (lambda + half).min(last));
                    self.integrate(a, b) / (b - a)
                } else {
                    self.interpolate(lambda)
                }
            };
            out[i] = value as f32;
        }
        let mut notes = Vec::new();
        let grid = || (0..BANDS).map(wavelength_nm);
        if let Some(to_nm) = grid().rfind(|&l| l < first) {
            notes.push(Note::Extrapolated {
                from_nm: grid_first,
                to_nm,
                held_from_nm: first,
                value: self.values[0],
            });
        }
        if let Some(from_nm) = grid().find(|&l| l > last) {
            let value = *self.values.last().expect("at least two points");
            notes.push(Note::Extrapolated { from_nm, to_nm: grid_last, held_from_nm: last, value });
        }
        Ok((out, notes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tab(w: &[f64], v: &[f64]) -> TabulatedSpectrum {
        TabulatedSpectrum::new("test", w.to_vec(), v.to_vec()).unwrap()
    }

    #[test]
    fn data_on_the_grid_are_reproduced_exactly() {
        let w: Vec<f64> = (0..BANDS).map(wavelength_nm).collect();
        let v: Vec<f64> = w.iter().map(|l| (l / 100.0).sin().abs()).collect();
        let (s, notes) = tab(&w, &v).resample(Coverage::Require).unwrap();
        assert!(notes.is_empty());
        for i in 0..BANDS {
            assert_eq!(s[i], v[i] as f32);
        }
    }

    #[test]
    fn a_line_is_reproduced_by_both_branches() {
        // 1 nm data (box filter) and 10 nm data (interpolation) of a straight line both give the
        // line itself: the mean of a linear function over a symmetric window is its centre value.
        for step in [1.0, 10.0, 7.0] {
            let w: Vec<f64> =
                (0..).map(|k| 370.0 + step * k as f64).take_while(|&l| l <= 800.0).collect();
            let v: Vec<f64> = w.iter().map(|l| 0.001 * l - 0.2).collect();
            let (s, _) = tab(&w, &v).resample(Coverage::Require).unwrap();
            for i in 0..BANDS {
                let expect = 0.001 * wavelength_nm(i) - 0.2;
                assert!((f64::from(s[i]) - expect).abs() < 1e-6, "step {step} band {i}");
            }
        }
    }

    #[test]
    fn fine_data_are_averaged_over_the_band() {
        // 1 nm data alternating 0 and 1: point sampling would alias to 0 or 1, the box filter
        // gives the local mean: 0.45 or 0.55, as the ±2.5 nm window holds four whole 1 nm
        // segments (mean 0.5 each) and two half segments whose ends differ with the parity.
        let w: Vec<f64> = (370..=790).map(f64::from).collect();
        let v: Vec<f64> = (370..=790).map(|k| f64::from(k % 2)).collect();
        let (s, _) = tab(&w, &v).resample(Coverage::Require).unwrap();
        for i in 0..BANDS {
            assert!((f64::from(s[i]) - 0.5).abs() <= 0.1 + 1e-6, "band {i}: {}", s[i]);
        }
    }

    #[test]
    fn short_data_are_refused_or_held_and_reported() {
        let t = tab(&[400.0, 500.0, 760.0], &[0.2, 0.4, 0.6]);
        let err = t.resample(Coverage::Require).unwrap_err();
        assert_eq!(
            err.spectrum_problem(),
            Some(&SpectrumProblem::DoesNotCover { first_nm: 400.0, last_nm: 760.0 })
        );
        assert!(err.to_string().contains("400–760 nm"), "{err}");
        let (s, notes) = t.resample(Coverage::HoldEnds).unwrap();
        assert_eq!(s[0], 0.2);
        assert_eq!(s[3], 0.2);
        assert_eq!(s[80], 0.6);
        assert_eq!(
            notes,
            vec![
                Note::Extrapolated {
                    from_nm: 380.0,
                    to_nm: 395.0,
                    held_from_nm: 400.0,
                    value: 0.2
                },
                Note::Extrapolated {
                    from_nm: 765.0,
                    to_nm: 780.0,
                    held_from_nm: 760.0,
                    value: 0.6
                },
            ]
        );
    }

    #[test]
    fn invariants_are_checked() {
        assert!(TabulatedSpectrum::new("t", vec![500.0], vec![1.0]).is_err());
        assert!(TabulatedSpectrum::new("t", vec![500.0, 500.0], vec![1.0, 1.0]).is_err());
        assert!(TabulatedSpectrum::new("t", vec![500.0, 510.0], vec![1.0, f64::NAN]).is_err());
    }
}
