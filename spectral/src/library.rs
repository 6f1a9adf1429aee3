//! The library of measured reflectance spectra shipped with restauro (`data/spectra/`):
//! travertines, conglomerates ("pudding stone"), limestones, marbles, sandstones, granites,
//! bricks, concretes, the carbon-black soot proxy, lichens. Each is named by its file stem and
//! embedded in the program, with the provenance header of its file.
//!
//! Many of these measurements start at 400 nm (the ECOSTRESS/JPL instrument's range). The
//! library's documented policy for them is [`Coverage::HoldEnds`]: the first measured value is
//! held constant down to 380 nm, and every such extrapolation is reported with the spectrum.

use crate::csv::{LoadedSpectrum, Quantity, load};
use crate::error::{Error, Result};
use crate::tabulated::Coverage;

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/library.rs"));
}

/// The acknowledgement that JPL requires wherever an ECOSTRESS spectrum is reproduced.
pub const ECOSTRESS_ACKNOWLEDGEMENT: &str = "Reproduced from the ECOSTRESS Spectral Library \
    through the courtesy of the Jet Propulsion Laboratory, California Institute of Technology, \
    Pasadena, California. Copyright © 2017, California Institute of Technology. ALL RIGHTS \
    RESERVED.";

/// The stems of every library spectrum, sorted.
pub fn names() -> impl Iterator<Item = &'static str> {
    embedded::FILES.iter().map(|(stem, _)| *stem)
}

/// The text of a library file.
pub fn text(stem: &str) -> Option<&'static str> {
    embedded::FILES.iter().find(|(s, _)| *s == stem).map(|(_, text)| *text)
}

/// What a library spectrum is of, in a few words: its file's `# material:` line.
pub fn material(stem: &str) -> Option<&'static str> {
    text(stem)?.lines().find_map(|l| l.strip_prefix("# material:")).map(str::trim)
}

/// True when a spectrum file's comment lines (its provenance header) say it comes from the
/// ECOSTRESS library, whose licence requires [`ECOSTRESS_ACKNOWLEDGEMENT`] wherever it is shown.
pub fn requires_ecostress_acknowledgement(comments: &[String]) -> bool {
    comments.iter().any(|c| c.starts_with("source:") && c.contains("ECOSTRESS"))
}

/// Library names close to `name`, best first, for "did you mean" messages: names containing it,
/// then names within a small edit distance.
pub fn suggest(name: &str) -> Vec<String> {
    let lower = name.to_ascii_lowercase();
    let mut scored: Vec<(f64, &str)> = names()
        .map(|n| {
            let score = if n.contains(&lower) { 2.0 } else { strsim::jaro_winkler(n, &lower) };
            (score, n)
        })
        .filter(|(score, _)| *score > 0.85)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(b.1)));
    scored.into_iter().take(5).map(|(_, n)| n.to_owned()).collect()
}

/// Load a library reflectance onto the grid, with the library's coverage policy.
pub fn load_reflectance(stem: &str) -> Result<LoadedSpectrum> {
    let text = text(stem).ok_or_else(|| Error::UnknownSpectrum {
        name: stem.to_owned(),
        suggestions: suggest(stem),
    })?;
    load(text, &format!("data/spectra/{stem}.csv"), Quantity::Reflectance, Coverage::HoldEnds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_holds_the_stones_the_paper_needs() {
        let all: Vec<&str> = names().collect();
        for family in [
            "travertine",
            "conglomerate",
            "limestone",
            "marble",
            "sandstone",
            "brick",
            "carbon_black_soot_proxy",
        ] {
            assert!(all.iter().any(|n| n.starts_with(family)), "no {family} in {all:?}");
        }
        assert!(all.len() >= 40, "{}", all.len());
        assert!(!all.iter().any(|n| n.starts_with('_')));
    }

    #[test]
    fn every_library_spectrum_loads_within_0_1() {
        for name in names() {
            let loaded = load_reflectance(name).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                loaded.spectrum.min_value() >= 0.0 && loaded.spectrum.max_value() <= 1.0,
                "{name}"
            );
            // Every extrapolation is reported: the notes are there exactly when the data stop short.
            let short = loaded.range_nm.0 > 380.0 || loaded.range_nm.1 < 780.0;
            let reported = loaded
                .notes
                .iter()
                .any(|n| matches!(n, crate::tabulated::Note::Extrapolated { .. }));
            assert_eq!(short, reported, "{name}");
        }
    }

    #[test]
    fn ecostress_files_are_flagged_for_acknowledgement() {
        let needs =
            |stem| requires_ecostress_acknowledgement(&load_reflectance(stem).unwrap().comments);
        assert!(needs("travertine_tufa_solid__eco_ward73"));
        assert!(!needs("carbon_black_soot_proxy__usgs_GDS68"));
        // Every ECOSTRESS file (stem `__eco_`) carries the source line, and no other does.
        for stem in names() {
            assert_eq!(needs(stem), stem.contains("__eco_"), "{stem}");
        }
    }

    #[test]
    fn unknown_names_get_suggestions() {
        let err = load_reflectance("travertine").unwrap_err().to_string();
        assert!(err.contains("did you mean travertine_"), "{err}");
    }
}
