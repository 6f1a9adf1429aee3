//! The `[spectra]` table and what a use asks of a spectrum: every named spectrum resolved onto
//! the grid (a shipped reflectance, a CSV file, a CIE illuminant, a constant, or a mixture of
//! others, its cycles refused), a reflectance at most 1, a light's spectrum one that emits at
//! 555 nm; and the D65 a sky is given without a spectrum of its own.

use super::{Ctx, unknown};
use crate::assets::utf8_text;
use crate::error::Result;
use crate::scene_file::SpectrumSource;
use restauro_spectral::csv::{Quantity, load as load_csv};
use restauro_spectral::tabulated::Coverage;
use restauro_spectral::{Illuminant, Spectrum, library};

/// Every spectrum must resolve, used or not, so mistakes surface now.
pub(super) fn check_spectra(ctx: &mut Ctx) -> Result<()> {
    let file = ctx.file;
    for name in file.spectra.keys() {
        ctx.spectrum(name, &format!("spectra.{name}"), &mut Vec::new())?;
    }
    Ok(())
}

impl Ctx<'_> {
    /// Resolve a named spectrum (and what it mixes), detecting cycles.
    pub(super) fn spectrum(
        &mut self,
        name: &str,
        place: &str,
        visiting: &mut Vec<String>,
    ) -> Result<Spectrum> {
        if let Some(s) = self.spectra.get(name) {
            return Ok(*s);
        }
        let source = self
            .file
            .spectra
            .get(name)
            .ok_or_else(|| {
                self.invalid(
                    place,
                    unknown("spectrum", name, self.file.spectra.keys().map(String::as_str)),
                )
            })?
            .clone();
        if visiting.iter().any(|v| v == name) {
            return Err(self.invalid(
                format!("spectra.{name}"),
                format!("the mixture refers to itself ({} → {name})", visiting.join(" → ")),
            ));
        }
        visiting.push(name.to_owned());
        let spectrum_place = format!("spectra.{name}");
        let s = match &source {
            SpectrumSource::Library(stem) => {
                let loaded = library::load_reflectance(stem)
                    .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?;
                self.notes.extend(
                    loaded.notes.iter().map(|n| format!("spectrum `{name}` ({stem}): {n}")),
                );
                loaded.spectrum
            }
            SpectrumSource::File { file, extrapolate } => {
                let bytes = self.assets.read(file, &spectrum_place)?;
                let shown = self.assets.display_path(file);
                let text = utf8_text(bytes, &shown)?;
                let coverage = if *extrapolate { Coverage::HoldEnds } else { Coverage::Require };
                let loaded = load_csv(
                    &text,
                    &shown.display().to_string(),
                    Quantity::RelativePower,
                    coverage,
                )
                .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?;
                self.notes.extend(
                    loaded.notes.iter().map(|n| format!("spectrum `{name}` ({file}): {n}")),
                );
                loaded.spectrum
            }
            SpectrumSource::Illuminant { illuminant } => illuminant
                .parse::<Illuminant>()
                .and_then(|i| i.spd())
                .map_err(|e| self.invalid(&spectrum_place, e.to_string()))?,
            SpectrumSource::Constant { constant } => {
                if !(constant.is_finite() && (0.0..=1e6).contains(constant)) {
                    return Err(self.invalid(
                        &spectrum_place,
                        format!("constant = {constant}: give a value from 0 (a black surface) to 1 for a reflectance, or up to 1e6 for a light"),
                    ));
                }
                Spectrum::splat(*constant as f32)
            }
            SpectrumSource::Mix { mix } => {
                if mix.is_empty() {
                    return Err(self.invalid(
                        &spectrum_place,
                        "an empty mixture; list the spectra and their weights",
                    ));
                }
                let total: f64 = mix.iter().map(|p| p.weight).sum();
                if mix.iter().any(|p| !(p.weight.is_finite() && p.weight >= 0.0))
                    || (total - 1.0).abs() > 1e-6
                {
                    return Err(self.invalid(
                        &spectrum_place,
                        format!("mixture weights must be ≥ 0 and sum to 1 (they sum to {total})"),
                    ));
                }
                let mut out = Spectrum::ZERO;
                for part in mix {
                    let s = self.spectrum(&part.spectrum, &spectrum_place, visiting)?;
                    out += s * part.weight as f32;
                }
                out
            }
        };
        visiting.pop();
        self.spectra.insert(name.to_owned(), s);
        self.spectrum_max.insert(name.to_owned(), s.max_value());
        Ok(s)
    }

    /// A spectrum used as a reflectance: at most 1.
    pub(super) fn reflectance(&mut self, name: &str, place: &str) -> Result<()> {
        self.spectrum(name, place, &mut Vec::new())?;
        let max = self.spectrum_max[name];
        if max > 1.0 {
            return Err(self.invalid(
                place,
                format!(
                    "spectrum `{name}` reaches {max} but is used as a reflectance, which cannot \
                     exceed 1; give reflectance as a fraction 0..1"
                ),
            ));
        }
        Ok(())
    }

    /// A spectrum used as a light: it must emit at 555 nm (Eq. 2 normalises there).
    pub(super) fn emission(&mut self, name: &str, place: &str) -> Result<()> {
        let s = self.spectrum(name, place, &mut Vec::new())?;
        restauro_spectral::photometry::LuminousSpectrum::new(&s, name)
            .map_err(|e| self.invalid(place, e.to_string()))?;
        Ok(())
    }
}

/// The name of the spectrum a sky is given without one: CIE D65, the daylight of the CIE
/// general sky's definition. A `[spectra]` entry of this name is the user's own, and wins.
pub const DEFAULT_SKY_SPECTRUM: &str = "cie:D65";

/// A sky's spectrum: its own, or [`DEFAULT_SKY_SPECTRUM`], resolved into the scene's spectra.
pub(super) fn sky_spectrum(ctx: &mut Ctx, given: &str) -> Result<String> {
    if !given.is_empty() {
        return Ok(given.to_owned());
    }
    if !ctx.file.spectra.contains_key(DEFAULT_SKY_SPECTRUM) {
        let d65 = Illuminant::D65.spd().map_err(|e| ctx.invalid("spectrum", e.to_string()))?;
        ctx.spectra.insert(DEFAULT_SKY_SPECTRUM.to_owned(), d65);
    }
    Ok(DEFAULT_SKY_SPECTRUM.to_owned())
}
