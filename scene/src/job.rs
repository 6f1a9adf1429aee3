//! A job as a client asks for it: which render of the scene (the [`RenderOptions`] a [`Plan`]
//! resolves), how it is shown (the display exposure), how the Retinex runs, its name and its
//! priority. Every field is checked here, once, when the job is made — by the client before it
//! submits and by the coordinator when the job arrives from the wire — so nothing later in the
//! job's life (planning, assembly, writing the result files) meets a value it cannot use.
//!
//! [`Plan`]: crate::plan::Plan

use crate::plan::{RenderOptions, ZERO_COUNT};
use restauro_spectral::display::Exposure;
use restauro_spectral::retinex::MAX_PATHS;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::num::NonZeroU32;

/// A job's field that cannot be used, and what to do instead.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct JobSpecError {
    pub field: &'static str,
    pub problem: String,
}

fn refuse(field: &'static str, problem: impl Into<String>) -> JobSpecError {
    JobSpecError { field, problem: problem.into() }
}

/// A count a render option gives (samples per pixel, a size, a tile edge) as the checked value
/// [`RenderOptions`] holds: a zero is refused, naming `field`. Each edge where an option enters
/// (the wire, the studio's request, the command line) calls it once.
pub fn option_count(field: &'static str, value: u32) -> Result<NonZeroU32, JobSpecError> {
    NonZeroU32::new(value).ok_or_else(|| refuse(field, ZERO_COUNT))
}

/// A job's name, as lists show it and as its result files are called: at most
/// [`JobName::MAX_CHARS`] characters, none of them a control character or a bidirectional
/// override (either could rewrite what a terminal shows around it).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct JobName(String);

impl JobName {
    pub const MAX_CHARS: usize = 128;

    pub fn new(name: &str) -> Result<Self, JobSpecError> {
        check_label("name", name, Self::MAX_CHARS)?;
        Ok(Self(name.to_owned()))
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The stem of the result files: the name kept to characters safe in a file name.
    pub fn file_stem(&self) -> String {
        let stem: String = self
            .0
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' })
            .collect();
        let stem = stem.trim_start_matches('.');
        if stem.is_empty() { "render".to_owned() } else { stem.to_owned() }
    }
}

/// Checks a text others will read (a name, a build): at most `max_chars` characters, and no
/// control characters or bidirectional overrides.
pub fn check_label(field: &'static str, text: &str, max_chars: usize) -> Result<(), JobSpecError> {
    let count = text.chars().count();
    if count > max_chars {
        return Err(refuse(field, format!("{count} characters; use at most {max_chars}")));
    }
    if let Some((at, c)) = text.char_indices().find(|&(_, c)| is_unprintable(c)) {
        return Err(refuse(
            field,
            format!(
                "character {} (U+{:04X}) at byte {at} is a control character; use printable text",
                c.escape_unicode(),
                u32::from(c)
            ),
        ));
    }
    Ok(())
}

/// `text` with every control character and bidirectional override replaced by `?` and cut to
/// `max_chars` characters: for texts that are shown but cannot be refused (a worker's reason
/// for a failed tile).
pub fn printable(text: &str, max_chars: usize) -> String {
    text.chars().take(max_chars).map(|c| if is_unprintable(c) { '?' } else { c }).collect()
}

/// Control characters (C0, DEL, C1) and the Unicode bidirectional embeddings, overrides and
/// isolates (U+202A–U+202E, U+2066–U+2069), which reorder the text around them.
fn is_unprintable(c: char) -> bool {
    c.is_control()
        || ('\u{202a}'..='\u{202e}').contains(&c)
        || ('\u{2066}'..='\u{2069}').contains(&c)
}

impl TryFrom<String> for JobName {
    type Error = JobSpecError;
    fn try_from(s: String) -> Result<Self, JobSpecError> {
        JobName::new(&s)
    }
}

impl From<JobName> for String {
    fn from(n: JobName) -> String {
        n.0
    }
}

impl fmt::Display for JobName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// The Retinex of a job (Marini–Rizzi Brownian paths; the rest of its parameters are the
/// defaults of `restauro_spectral::retinex::RetinexParams`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RetinexOptions {
    /// Path samples per pixel, 1 to 4096.
    pub paths: u32,
    pub seed: u64,
}

impl Default for RetinexOptions {
    fn default() -> Self {
        Self { paths: restauro_spectral::retinex::RetinexParams::default().paths, seed: 0 }
    }
}

impl RetinexOptions {
    pub fn new(paths: Option<u32>, seed: Option<u64>) -> Result<Self, JobSpecError> {
        let default = Self::default();
        let paths = paths.unwrap_or(default.paths);
        if !(1..=MAX_PATHS).contains(&paths) {
            return Err(refuse(
                "retinex.paths",
                format!("{paths} paths per pixel; use 1 to {MAX_PATHS}"),
            ));
        }
        Ok(Self { paths, seed: seed.unwrap_or(default.seed) })
    }
}

/// Everything a client asks of one job besides the scene itself.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JobSpec {
    pub name: JobName,
    /// Higher first; jobs of equal priority share the workers.
    pub priority: i32,
    pub render: RenderOptions,
    pub exposure: Exposure,
    pub retinex: RetinexOptions,
    /// A sequence's frames, each the scene with its changes; none for a still. Absent in jobs
    /// stored before sequences existed.
    #[serde(default)]
    pub frames: Vec<crate::sequence::Frame>,
}

impl JobSpec {
    /// Checks what the plan does not: the exposure's number, and that the options name no
    /// empty variant.
    pub fn checked(self) -> Result<Self, JobSpecError> {
        self.exposure.checked().map_err(|e| refuse("exposure", e.to_string()))?;
        if self.render.variant.as_deref().is_some_and(str::is_empty) {
            return Err(refuse("render.variant", "an empty variant name; leave it out instead"));
        }
        if let Some(target) = self.render.noise_target {
            crate::scene_file::check_noise_target(target)
                .map_err(|problem| refuse("render.noise_target", problem))?;
        }
        for (index, frame) in self.frames.iter().enumerate() {
            frame.check(index)?;
        }
        crate::sequence::check_times(&self.frames)?;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_with_controls_or_overrides_or_too_long_are_refused() {
        assert!(JobName::new("aosta-cleaned").is_ok());
        assert!(JobName::new("façade sud, été").is_ok());
        for bad in ["a\u{1b}[2Jb", "two\nlines", "tab\there", "rtl\u{202e}txt", "\u{7f}", "\u{85}"]
        {
            let e = JobName::new(bad).unwrap_err();
            assert_eq!(e.field, "name");
            assert!(e.problem.contains("control character"), "{e}");
        }
        let long = "x".repeat(JobName::MAX_CHARS + 1);
        assert!(JobName::new(&long).unwrap_err().problem.contains("at most 128"));
        assert!(JobName::new(&"é".repeat(JobName::MAX_CHARS)).is_ok());
    }

    #[test]
    fn file_stems_are_plain_file_names() {
        let stem = |s: &str| JobName::new(s).unwrap().file_stem();
        assert_eq!(stem("../../etc/passwd"), "_.._etc_passwd");
        assert_eq!(stem(""), "render");
        assert_eq!(stem("..."), "render");
        assert_eq!(stem("aosta-cleaned"), "aosta-cleaned");
    }

    #[test]
    fn retinex_paths_are_bounded() {
        assert_eq!(RetinexOptions::new(None, None).unwrap(), RetinexOptions::default());
        assert!(RetinexOptions::new(Some(4096), Some(7)).is_ok());
        for bad in [0, 4097, 4_000_000_000] {
            let e = RetinexOptions::new(Some(bad), None).unwrap_err();
            assert_eq!(e.field, "retinex.paths");
        }
    }

    #[test]
    fn unusable_exposures_and_zero_options_are_refused() {
        let spec = |exposure| JobSpec { exposure, ..JobSpec::default() }.checked();
        assert!(spec(Exposure::Automatic { key: f64::NAN }).is_err());
        assert!(spec(Exposure::Absolute { white_cd_m2: 0.0 }).is_err());
        assert!(spec(Exposure::Absolute { white_cd_m2: f64::INFINITY }).is_err());
        assert!(spec(Exposure::Relative).is_ok());
        let zero = option_count("render.samples_per_pixel", 0).unwrap_err();
        assert_eq!(zero.field, "render.samples_per_pixel");
        assert!(zero.problem.contains("use at least 1"), "{zero}");
        assert_eq!(option_count("render.tile", 16).unwrap().get(), 16);
        // A stored job's options are read back as the same checked values: a zero is refused.
        let stored = r#"{"variant":null,"integrator":null,"samples_per_pixel":0,"width":null,
            "height":null,"spectral":false,"tile":null}"#;
        assert!(serde_json::from_str::<RenderOptions>(stored).is_err());
        let stored = stored.replace("\"samples_per_pixel\":0", "\"samples_per_pixel\":4");
        let options: RenderOptions = serde_json::from_str(&stored).unwrap();
        assert_eq!(options.samples_per_pixel.map(NonZeroU32::get), Some(4));
    }
}
