//! Photometric files: a luminaire's measured luminous intensity distribution, read from IES
//! LM-63 (`.ies`) or EULUMDAT (`.ldt`) files and held as one type C web in candela.
//!
//! Why one representation: the renderer only ever asks "how many candela towards this
//! direction?" and "how many lumens in total?". Both formats are brought to the CIE 121 /
//! LM-63-2002 type C coordinate system (vertical angle γ from the nadir, horizontal angle C
//! counter-clockwise from +X seen from above), every multiplier applied, every symmetry expanded
//! to a full 0..360° circle, so nothing downstream needs to know which file a light came from.
//!
//! # IES LM-63 (1986, 1991, 1995, 2002; 2019 read like 2002)
//! * Versions: the first line `IESNA:LM-63-2002`, `IESNA:LM-63-1995`, `IESNA91` (1991),
//!   `IES:LM-63-2019`, or no version line at all (1986: label lines up to `TILT=`).
//! * `TILT=NONE` and `TILT=INCLUDE` (lamp-to-luminaire geometry, number of pairs, angles,
//!   multiplying factors) are read. The candela values are multiplied by the tilt factor at a tilt
//!   of 0°, the luminaire as it was measured (linear interpolation, the end value outside the
//!   table). `TILT=<file>` is refused: the tilt file is not at hand, so the file must carry it
//!   inline.
//! * Photometric type 1 (type C) is read. Types 2 (B) and 3 (A) are refused with a message asking
//!   for a type C export: their planes share a horizontal axis, converting them means resampling
//!   the web (the measured values no longer appear in it) and LM-63-2002 §3.0 counts their
//!   horizontal angles clockwise where type C counts counter-clockwise — a sign slip mirrors the
//!   beam silently, and no test file of either type was at hand to check a conversion against.
//! * Multipliers (LM-63-2002, the two lines after the TILT block): candela multiplier ×
//!   ballast factor × (1986–1995 only) ballast-lamp photometric factor, which LM-63-2002 renamed
//!   "future use" and which is therefore ignored in 2002 and 2019 files. Relative photometry
//!   (lumens per lamp > 0) gives candela values for the rated lamp lumens already; the scaling LM-63
//!   defines (× actual lamp lumens ÷ rated lamp lumens) is 1 because the rated lamp is the lamp
//!   rendered. Absolute photometry (lumens per lamp = −1) gives candela directly.
//! * Horizontal angles (LM-63-2002, type C): a single angle (rotationally symmetric), 0–90
//!   (quadrant symmetry), 0–180 (bilateral about the 0–180 plane), 90–270 (bilateral about the
//!   90–270 plane), or 0 to more than 180 up to 360 (no symmetry; a closing 360° plane is dropped as
//!   the same plane as 0°). Values may be separated by spaces, commas or line breaks (LM-63-2002
//!   §3.0, "delimiter").
//!
//! # EULUMDAT
//! Fields are numbered as in the EULUMDAT description (Stockmar 1990; reproduced e.g. in the AGi32
//! and Helios32 documentation): one field per line, lines 1–26, then 6 lines per lamp set (each
//! field for all sets before the next field: 26a for sets 1..n, then 26b, ...), 10 direct ratios,
//! the Mc C-angles, the Ng γ angles and the intensities (field 30) in cd/klm for the C-planes Mc1
//! to Mc2 (Isym 0: 1..Mc; 1: 1..1; 2: 1..Mc/2+1; 3: 3Mc/4+1..3Mc/4+Mc/2+1, counted round the
//! circle, i.e. C270 through C0 to C90; 4: 1..Mc/4+1).
//! * Intensities become candela as value × field 24 (conversion factor) × field 26c of the first
//!   lamp set ÷ 1000. Field 26c is the *total* luminous flux of the lamps of the set, so it is not
//!   multiplied again by the number of lamps (field 26a).
//! * A negative number of lamps (field 26a) is the convention some writers use for absolute
//!   photometry: field 26c then holds the luminaire's own flux and the table is still cd/klm of
//!   it, so the same scaling gives candela; only the sign is ignored.
//! * Numbers may use a decimal comma (`83,4`), as files written under European locales do.
//!
//! # Both
//! Files that are not UTF-8 are read as Latin-1 (EULUMDAT files often are). Every refusal is a
//! [`SceneError`] naming the file, the line and column (or the field) and what to do.

use std::f64::consts::PI;
use std::path::Path;

use crate::{Result, SceneError};

/// The most angles of one kind (vertical, horizontal, C-planes, γ, tilt pairs) a file may have.
/// Real files have at most a few hundred; the limit keeps a corrupt count from reserving memory.
const MAX_ANGLES: usize = 100_000;

/// The most intensity values a file's table may hold (before symmetry expansion, which at most
/// quadruples it). A 0.5° × 0.5° full web is 361 × 720 = 259 920 values.
const MAX_TABLE_VALUES: u64 = 4_000_000;

/// The most lamp sets an EULUMDAT file may declare (the format itself allows 20).
const MAX_LAMP_SETS: usize = 1_000;

/// The largest photometric file [`load`] reads; real ones are a few kB to a few hundred kB.
const MAX_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// Two angles closer than this (degrees) are the same angle when a symmetry is recognised.
const ANGLE_TOLERANCE: f64 = 1e-6;

const LIMIT_FIX: &str = "resample the distribution to fewer angles, or raise the limit in \
                         restauro-scene's photometric.rs if such a file is genuine";

/// A luminaire's measured luminous intensity distribution, in candela, in the photometric
/// coordinate system of CIE 121 / IES LM-63 type C: γ (vertical angle) 0° = nadir (straight down,
/// the luminaire's −Z axis), 180° = zenith; C (horizontal angle) 0° along +X, 90° along +Y.
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// Vertical angles γ in degrees, increasing, within 0..=180.
    pub gamma_deg: Vec<f64>,
    /// Horizontal angles C in degrees, increasing, within 0..360 (full circle after symmetry is expanded).
    pub c_deg: Vec<f64>,
    /// `candela[c][g]` = intensity (cd) at `c_deg[c]`, `gamma_deg[g]`, multipliers applied (candela multiplier, ballast factor, lamp lumens scaling for relative photometry as LM-63 defines it, TILT factor at the file's lamp tilt if any).
    pub candela: Vec<Vec<f64>>,
    /// Text fields for information: manufacturer / luminaire / lamp keywords (IES) or the EULUMDAT header fields.
    pub description: String,
}

impl Photometry {
    /// Intensity in cd towards a direction given in the luminaire's frame (x, y, z; not necessarily normalised), by bilinear interpolation in (C, γ), honouring the file's symmetry (the stored grid is already expanded to a full 0..360 circle) and wrapping C around 360°. Outside the measured γ range the intensity is 0.
    ///
    /// A zero or non-finite direction has no intensity (0). γ is computed with `atan2` rather
    /// than `acos`, which loses precision next to the nadir and zenith.
    pub fn intensity_cd(&self, direction: [f64; 3]) -> f64 {
        let [x, y, z] = direction;
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return 0.0;
        }
        // Scale first so that squaring cannot overflow or underflow.
        let m = x.abs().max(y.abs()).max(z.abs());
        if m <= 0.0 {
            return 0.0;
        }
        let (x, y, z) = (x / m, y / m, z / m);
        let horizontal = (x * x + y * y).sqrt();
        let gamma = horizontal.atan2(-z).to_degrees();
        let c = y.atan2(x).to_degrees();
        self.intensity_at(c, gamma)
    }

    /// Intensity at explicit angles (degrees).
    ///
    /// Bilinear: linear in γ within each plane, then linear in C between the two planes either
    /// side (the last plane and the first + 360° across the wrap). At a measured (C, γ) the
    /// stored value is returned exactly. A web with one plane is rotationally symmetric.
    pub fn intensity_at(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        if !c_deg.is_finite() || !gamma_deg.is_finite() {
            return 0.0;
        }
        let Some((gi, t)) = self.gamma_cell(gamma_deg) else {
            return 0.0;
        };
        let n = self.c_deg.len().min(self.candela.len());
        if n == 0 {
            return 0.0;
        }
        if n == 1 {
            return self.plane_value(0, gi, t);
        }
        let c = normalise_c(c_deg);
        let planes = self.c_deg.get(..n).unwrap_or(&[]);
        let (Some(&first), Some(&last)) = (planes.first(), planes.last()) else {
            return 0.0;
        };
        let (k0, k1, c0, c1) = if c < first {
            (n - 1, 0, last - 360.0, first)
        } else {
            let k0 = planes.partition_point(|&a| a <= c).saturating_sub(1);
            let c0 = planes.get(k0).copied().unwrap_or(first);
            match planes.get(k0 + 1) {
                Some(&c1) => (k0, k0 + 1, c0, c1),
                None => (k0, 0, c0, first + 360.0),
            }
        };
        let width = c1 - c0;
        let s = if width > 0.0 { ((c - c0) / width).clamp(0.0, 1.0) } else { 0.0 };
        let a = self.plane_value(k0, gi, t);
        if s == 0.0 {
            return a;
        }
        let b = self.plane_value(k1, gi, t);
        (1.0 - s) * a + s * b
    }

    /// The total luminous flux in lumens: ∫ I dΩ over the sphere, by integrating the interpolated distribution (e.g. zonal sums over γ bands × C sectors, fine enough to be accurate to 1e-3 relative on smooth distributions).
    ///
    /// The integral of the bilinear interpolant is computed in closed form, so it is exact for
    /// the distribution [`Photometry::intensity_at`] returns (no sampling error on top of the
    /// interpolation): dΩ = sin γ dγ dC; in C the interpolant is linear, so a sector contributes
    /// its width × the mean of its two planes' zonal integrals; in γ each band contributes
    /// ∫ (w0·I0 + w1·I1) sin γ dγ with the weights of `band_weights`.
    pub fn flux_lm(&self) -> f64 {
        if self.gamma_deg.len() < 2 {
            return 0.0;
        }
        let weights: Vec<(f64, f64)> = self
            .gamma_deg
            .windows(2)
            .map(|w| match w {
                [a, b] => band_weights(a.to_radians(), b.to_radians()),
                _ => (0.0, 0.0),
            })
            .collect();
        let zonal = |row: &Vec<f64>| -> f64 {
            weights
                .iter()
                .enumerate()
                .map(|(i, &(w0, w1))| {
                    w0 * row.get(i).copied().unwrap_or(0.0)
                        + w1 * row.get(i + 1).copied().unwrap_or(0.0)
                })
                .sum()
        };
        let n = self.c_deg.len().min(self.candela.len());
        let planes: Vec<f64> = self.candela.iter().take(n).map(zonal).collect();
        match n {
            0 => 0.0,
            1 => 2.0 * PI * planes.first().copied().unwrap_or(0.0),
            _ => {
                let mut total = 0.0;
                for k in 0..n {
                    let (k1, c1) = if k + 1 < n {
                        (k + 1, self.c_deg.get(k + 1).copied().unwrap_or(0.0))
                    } else {
                        (0, self.c_deg.first().copied().unwrap_or(0.0) + 360.0)
                    };
                    let c0 = self.c_deg.get(k).copied().unwrap_or(0.0);
                    let f0 = planes.get(k).copied().unwrap_or(0.0);
                    let f1 = planes.get(k1).copied().unwrap_or(0.0);
                    total += (c1 - c0).max(0.0).to_radians() * 0.5 * (f0 + f1);
                }
                total
            }
        }
    }

    /// The largest intensity in the file (cd).
    pub fn peak_cd(&self) -> f64 {
        self.candela.iter().flatten().fold(0.0, |m: f64, &v| m.max(v))
    }

    /// The beam angle (degrees): the full apex angle of the cone whose solid angle is that of the
    /// directions receiving at least half the peak intensity (the 50 %-of-peak beam of CIE
    /// 121 / IES LM-63 usage, as one equivalent cone, so that it is defined for asymmetric beams
    /// too): Ω = 2π(1 − cos(θ/2)). Integrated over the interpolated distribution on a ¼° × ½°
    /// grid of (γ, C).
    pub fn beam_angle_deg(&self) -> f64 {
        let half = 0.5 * self.peak_cd();
        if half <= 0.0 {
            return 0.0;
        }
        let (dg, dc) = (0.25f64, 0.5f64);
        let mut solid_angle = 0.0;
        for i in 0..(180.0 / dg) as usize {
            let gamma = (i as f64 + 0.5) * dg;
            let band = dg.to_radians() * dc.to_radians() * gamma.to_radians().sin();
            let inside = (0..(360.0 / dc) as usize)
                .filter(|&k| self.intensity_at((k as f64 + 0.5) * dc, gamma) >= half)
                .count();
            solid_angle += band * inside as f64;
        }
        2.0 * (1.0 - solid_angle / (2.0 * PI)).clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// The γ band holding `gamma` and the fraction across it, or `None` outside the measured
    /// range (a hair of rounding at either end is taken as the end itself).
    fn gamma_cell(&self, gamma: f64) -> Option<(usize, f64)> {
        let gs = &self.gamma_deg;
        let (first, last) = (*gs.first()?, *gs.last()?);
        let g = if gamma < first && gamma >= first - 1e-9 {
            first
        } else if gamma > last && gamma <= last + 1e-9 {
            last
        } else {
            gamma
        };
        if !(g >= first && g <= last) {
            return None;
        }
        if gs.len() == 1 {
            return Some((0, 0.0));
        }
        let i = gs.partition_point(|&a| a <= g).saturating_sub(1).min(gs.len() - 2);
        let (a, b) = (*gs.get(i)?, *gs.get(i + 1)?);
        let t = if b > a { ((g - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
        Some((i, t))
    }

    /// Plane `k` interpolated at fraction `t` of γ band `i`; the stored value itself at t = 0
    /// or 1 (written as (1 − t)·a + t·b, which is exact at both ends).
    fn plane_value(&self, k: usize, i: usize, t: f64) -> f64 {
        let Some(row) = self.candela.get(k) else {
            return 0.0;
        };
        let a = row.get(i).copied().unwrap_or(0.0);
        if t == 0.0 {
            return a;
        }
        let b = row.get(i + 1).copied().unwrap_or(0.0);
        (1.0 - t) * a + t * b
    }
}

/// Weights (w0, w1) with ∫ₐᵇ I(γ) sin γ dγ = w0·I(a) + w1·I(b) for I linear on [a, b]
/// (radians): w1 = (1/h)∫ₐᵇ (γ − a) sin γ dγ = (sin b − sin a − h cos b)/h and
/// w0 + w1 = cos a − cos b, both written with half-angle products to keep precision in
/// narrow bands.
fn band_weights(a: f64, b: f64) -> (f64, f64) {
    let h = b - a;
    if h <= 0.0 || !h.is_finite() {
        return (0.0, 0.0);
    }
    let mid = 0.5 * (a + b);
    let sin_half = (0.5 * h).sin();
    let total = 2.0 * mid.sin() * sin_half; // cos a − cos b
    let w1 = (2.0 * mid.cos() * sin_half - h * b.cos()) / h; // (sin b − sin a − h cos b)/h
    (total - w1, w1)
}

/// C in [0, 360), with a value a rounding error short of 360 taken as 0.
fn normalise_c(c: f64) -> f64 {
    let r = c.rem_euclid(360.0);
    if r >= 360.0 - 1e-9 { 0.0 } else { r }
}

/// The photometric frame of a luminaire at `position` aimed at `aim`: rows `[x, y, z]` that map
/// world directions to the frame, in which γ = 0 (the nadir) is −z, pointing at the aim (world
/// down without one), and C = 0 is +x, towards world +X as seen in the luminaire's plane (or +Y
/// when aimed along X) — the convention of LM-63 and EULUMDAT files for a luminaire hung
/// pointing down, kept when it is tilted.
pub fn luminaire_frame(position: [f64; 3], aim: Option<[f64; 3]>) -> [[f64; 3]; 3] {
    let unit = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / n)
    };
    let nadir = match aim {
        Some(a) => unit([a[0] - position[0], a[1] - position[1], a[2] - position[2]]),
        None => [0.0, 0.0, -1.0],
    };
    let z = nadir.map(|c| -c);
    let reference = if z[0].abs() > 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
    let along = reference[0] * z[0] + reference[1] * z[1] + reference[2] * z[2];
    let x = unit(std::array::from_fn(|k| reference[k] - z[k] * along));
    let y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
    [x, y, z]
}

// ------------------------------------------------------------------------------------------
// Loading
// ------------------------------------------------------------------------------------------

/// Read a file and dispatch on its extension (.ies / .ldt, case-insensitive); anything else refused naming the extension.
pub fn load(path: &std::path::Path) -> crate::Result<Photometry> {
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let parse: fn(&str, &Path) -> Result<Photometry> = match extension.as_deref() {
        Some("ies") => parse_ies,
        Some("ldt") => parse_ldt,
        Some(other) => {
            return Err(SceneError::invalid(
                path,
                "file extension",
                format!(
                    "'.{other}' is not a photometric format restauro reads; give an IES LM-63 \
                     file (.ies) or an EULUMDAT file (.ldt)"
                ),
            ));
        }
        None => {
            return Err(SceneError::invalid(
                path,
                "file extension",
                "the file name has no extension, so its format is unknown; name it .ies (IES \
                 LM-63) or .ldt (EULUMDAT)",
            ));
        }
    };
    let bytes = crate::assets::read_regular_file(
        path,
        MAX_FILE_BYTES,
        "a photometric file is a few hundred kB at most; check that this is the right file",
    )?;
    let text = decode_text(bytes);
    parse(&text, path)
}

/// UTF-8 if the bytes are UTF-8, else Latin-1 (each byte one character), which is what
/// EULUMDAT and older IES files written on Windows mostly are; the numbers are ASCII either way.
pub fn decode_text(bytes: Vec<u8>) -> String {
    match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    }
}

// ------------------------------------------------------------------------------------------
// Text scanning shared by both formats
// ------------------------------------------------------------------------------------------

/// The lines of a file, with `\r\n`, `\n` and a lone `\r` all ending a line and a leading
/// byte-order mark dropped.
fn split_lines(text: &str) -> Vec<&str> {
    let mut rest = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = Vec::new();
    while !rest.is_empty() {
        match rest.find(['\r', '\n']) {
            Some(i) => {
                lines.push(rest.get(..i).unwrap_or(""));
                let after = rest.get(i..).unwrap_or("");
                let skip = if after.starts_with("\r\n") { 2 } else { 1 };
                rest = after.get(skip..).unwrap_or("");
            }
            None => {
                lines.push(rest);
                break;
            }
        }
    }
    lines
}

/// One item of the numeric part of a file and where it starts (1-based line and column, in
/// characters).
#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: usize,
    column: usize,
}

/// The items of a file from a given line on, split at the format's separators.
#[derive(Clone, Copy)]
struct Tokens<'a> {
    lines: &'a [&'a str],
    /// Index of the current line.
    line: usize,
    /// Byte offset and character column reached in the current line.
    pos: usize,
    col: usize,
    separator: fn(char) -> bool,
}

impl<'a> Tokens<'a> {
    fn new(lines: &'a [&'a str], first_line: usize, separator: fn(char) -> bool) -> Self {
        Tokens { lines, line: first_line, pos: 0, col: 0, separator }
    }

    fn next_token(&mut self) -> Option<Token<'a>> {
        loop {
            let text: &'a str = self.lines.get(self.line)?;
            let rest = text.get(self.pos..).unwrap_or("");
            let mut skipped = 0;
            let mut start = None;
            for (i, c) in rest.char_indices() {
                if (self.separator)(c) {
                    skipped += 1;
                } else {
                    start = Some(i);
                    break;
                }
            }
            let Some(start) = start else {
                self.line += 1;
                self.pos = 0;
                self.col = 0;
                continue;
            };
            let tail = rest.get(start..).unwrap_or("");
            let mut len = tail.len();
            let mut chars = 0;
            for (i, c) in tail.char_indices() {
                if (self.separator)(c) {
                    len = i;
                    break;
                }
                chars += 1;
            }
            let token = Token {
                text: tail.get(..len).unwrap_or(""),
                line: self.line + 1,
                column: self.col + skipped + 1,
            };
            self.pos += start + len;
            self.col += skipped + chars;
            return Some(token);
        }
    }

    /// Where the next item starts (for messages about a group of values), without consuming it.
    fn next_token_position(&self) -> (usize, usize) {
        let mut probe = *self;
        probe.next_token().map_or_else(|| self.end(), |t| (t.line, t.column))
    }

    /// The position just after the last character of the file.
    fn end(&self) -> (usize, usize) {
        match self.lines.last() {
            Some(last) => (self.lines.len(), last.chars().count() + 1),
            None => (1, 1),
        }
    }
}

/// IES separators: LM-63-2002 §3.0 accepts a comma, spaces and line breaks; a DOS end-of-file
/// character (0x1A) left by old editors is treated as space.
fn ies_separator(c: char) -> bool {
    c.is_whitespace() || c == ',' || c == '\u{1a}'
}

/// EULUMDAT separators: white space only, since a comma may be a decimal comma.
fn ldt_separator(c: char) -> bool {
    c.is_whitespace() || c == '\u{1a}'
}

enum NumberProblem {
    NotANumber,
    NotFinite,
}

/// A number as written in a photometric file; with `decimal_comma`, one comma and no point is
/// read as a decimal comma.
fn parse_number(text: &str, decimal_comma: bool) -> std::result::Result<f64, NumberProblem> {
    let parsed = if decimal_comma && !text.contains('.') && text.matches(',').count() == 1 {
        text.replacen(',', ".", 1).parse::<f64>()
    } else {
        text.parse::<f64>()
    };
    match parsed {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(NumberProblem::NotFinite),
        Err(_) => Err(NumberProblem::NotANumber),
    }
}

/// `v` as a whole number, if it is one (counts and indicators are sometimes written `19.0`).
fn whole(v: f64) -> Option<u64> {
    (v >= 0.0 && v.fract() == 0.0 && v < u64::MAX as f64).then_some(v as u64)
}

/// Reads the numbers of a file in order, with positions for every message.
struct Cursor<'a> {
    path: &'a Path,
    tokens: Tokens<'a>,
    decimal_comma: bool,
}

impl<'a> Cursor<'a> {
    fn error_at(&self, token: &Token, problem: impl Into<String>) -> SceneError {
        SceneError::syntax(self.path, token.line, token.column, problem)
    }

    fn truncated(&self, what: &str) -> SceneError {
        let (line, column) = self.tokens.end();
        SceneError::syntax(
            self.path,
            line,
            column,
            format!(
                "the file ends before {what}: it is truncated; re-export or re-download the \
                 complete file"
            ),
        )
    }

    fn token(&mut self, what: &dyn Fn() -> String) -> Result<Token<'a>> {
        match self.tokens.next_token() {
            Some(t) => Ok(t),
            None => Err(self.truncated(&what())),
        }
    }

    fn number(&mut self, what: &dyn Fn() -> String) -> Result<(f64, Token<'a>)> {
        let token = self.token(what)?;
        match parse_number(token.text, self.decimal_comma) {
            Ok(v) => Ok((v, token)),
            Err(NumberProblem::NotANumber) => Err(self.error_at(
                &token,
                format!(
                    "expected a number for {}, found '{}'; a value is missing or misspelt at or \
                     before this point",
                    what(),
                    token.text
                ),
            )),
            Err(NumberProblem::NotFinite) => Err(self.error_at(
                &token,
                format!(
                    "{} is '{}', not a finite number; write a finite value",
                    what(),
                    token.text
                ),
            )),
        }
    }

    /// A multiplying factor: finite and greater than 0.
    fn factor(&mut self, what: &str) -> Result<(f64, Token<'a>)> {
        let (v, token) = self.number(&|| what.to_string())?;
        if v <= 0.0 {
            let kind = if v < 0.0 { "negative" } else { "zero" };
            return Err(self.error_at(
                &token,
                format!(
                    "{what} is {v}: a {kind} multiplier would give {} intensities; it must be a \
                     positive number (1 when there is nothing to scale)",
                    if v < 0.0 { "negative" } else { "no" }
                ),
            ));
        }
        Ok((v, token))
    }

    /// A count between `min` and [`MAX_ANGLES`].
    fn count(&mut self, what: &str, min: usize) -> Result<(usize, Token<'a>)> {
        let (v, token) = self.number(&|| what.to_string())?;
        let Some(n) = whole(v) else {
            return Err(self.error_at(
                &token,
                format!("{what} is '{}'; it must be a whole number", token.text),
            ));
        };
        if n > MAX_ANGLES as u64 {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!("{what} (line {}:{})", token.line, token.column),
                value: n,
                limit: MAX_ANGLES as u64,
                fix: LIMIT_FIX.into(),
            });
        }
        if (n as usize) < min {
            return Err(self.error_at(&token, format!("{what} is {n}; it must be at least {min}")));
        }
        Ok((n as usize, token))
    }

    /// `n` angles in degrees, strictly increasing, within `lo..=hi`.
    fn angles(&mut self, n: usize, what: &str, lo: f64, hi: f64) -> Result<Vec<f64>> {
        let mut out: Vec<f64> = Vec::with_capacity(n.min(MAX_ANGLES));
        for i in 0..n {
            let (v, token) = self.number(&|| format!("{what} {} of {n}", i + 1))?;
            if v < lo || v > hi {
                return Err(self.error_at(
                    &token,
                    format!(
                        "{what} {} of {n} is {v}°, outside {lo}..{hi}°; correct the angle or the \
                         angle count",
                        i + 1
                    ),
                ));
            }
            if let Some(&previous) = out.last()
                && v <= previous
            {
                return Err(self.error_at(
                    &token,
                    format!(
                        "{what} {} of {n} is {v}°, not greater than the previous one ({previous}°); \
                         angles must be listed in increasing order without repeats — fix the \
                         order, or the angle counts if values have shifted",
                        i + 1
                    ),
                ));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// The intensity table: one row of `gammas.len()` non-negative values per entry of
    /// `planes`, multiplied by `scale`. `counts` says where the counts came from, for messages.
    fn table(
        &mut self,
        planes: &[f64],
        gammas: &[f64],
        scale: f64,
        counts: &str,
    ) -> Result<Vec<Vec<f64>>> {
        let expected = planes.len() * gammas.len();
        let mut rows = Vec::with_capacity(planes.len());
        let mut found = 0usize;
        for &c in planes {
            let mut row = Vec::with_capacity(gammas.len());
            for &g in gammas {
                let Some(token) = self.tokens.next_token() else {
                    let (line, column) = self.tokens.end();
                    return Err(SceneError::syntax(
                        self.path,
                        line,
                        column,
                        format!(
                            "the file ends after {found} of the {expected} intensity values \
                             expected ({counts}): expected {expected}, found {found}; the file is \
                             truncated or its angle counts are wrong"
                        ),
                    ));
                };
                let v = match parse_number(token.text, self.decimal_comma) {
                    Ok(v) => v,
                    Err(NumberProblem::NotANumber) => {
                        return Err(self.error_at(
                            &token,
                            format!(
                                "expected intensity value {} of {expected} (C = {c}°, γ = {g}°), \
                                 found '{}'; a value is missing or misspelt",
                                found + 1,
                                token.text
                            ),
                        ));
                    }
                    Err(NumberProblem::NotFinite) => {
                        return Err(self.error_at(
                            &token,
                            format!(
                                "intensity at C = {c}°, γ = {g}° is '{}', not a finite number; \
                                 write a finite value",
                                token.text
                            ),
                        ));
                    }
                };
                if v < 0.0 {
                    return Err(self.error_at(
                        &token,
                        format!(
                            "intensity at C = {c}°, γ = {g}° is {v}, negative; a luminous \
                             intensity cannot be negative — correct the value (often a sign or \
                             column slip)"
                        ),
                    ));
                }
                row.push(v * scale);
                found += 1;
            }
            rows.push(row);
        }
        if let Some(first) = self.tokens.next_token() {
            let mut extra = 1usize;
            while self.tokens.next_token().is_some() {
                extra += 1;
            }
            return Err(self.error_at(
                &first,
                format!(
                    "too many intensity values ({counts}): expected {expected}, found {}; the \
                     first extra one is '{}' — fix the angle counts or remove the extra values",
                    expected + extra,
                    first.text
                ),
            ));
        }
        Ok(rows)
    }
}

/// Checks the size of a table before it is read.
fn check_table_size(path: &Path, planes: usize, per_plane: usize, what: &str) -> Result<()> {
    let values = (planes as u64).saturating_mul(per_plane as u64);
    if values > MAX_TABLE_VALUES {
        return Err(SceneError::Limit {
            path: path.to_path_buf(),
            what: format!("number of intensity values ({what})"),
            value: values,
            limit: MAX_TABLE_VALUES,
            fix: LIMIT_FIX.into(),
        });
    }
    Ok(())
}

/// A mirror image of a C angle under one of the symmetries of a web.
type Mirror = fn(f64) -> f64;

/// Mirror in the C0–C180 plane.
fn mirror_0_180(c: f64) -> f64 {
    360.0 - c
}

/// Mirror in the C90–C270 plane.
fn mirror_90_270(c: f64) -> f64 {
    180.0 - c
}

/// Both mirrors in turn: the diagonal image of quadrant symmetry.
fn mirror_both(c: f64) -> f64 {
    180.0 + c
}

/// The full circle from the stored planes and their mirror images: every image normalised to
/// 0..360, sorted, and an angle met twice (a plane on a mirror) kept once.
fn expand_planes(planes: Vec<(f64, Vec<f64>)>, mirrors: &[Mirror]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut images: Vec<(f64, usize)> = Vec::with_capacity(planes.len() * (mirrors.len() + 1));
    for (i, (c, _)) in planes.iter().enumerate() {
        images.push((normalise_c(*c), i));
        for mirror in mirrors {
            images.push((normalise_c(mirror(*c)), i));
        }
    }
    images.sort_by(|a, b| a.0.total_cmp(&b.0));
    images.dedup_by(|later, earlier| (later.0 - earlier.0).abs() < 1e-9);
    let c_deg = images.iter().map(|&(c, _)| c).collect();
    let candela = images
        .iter()
        .map(|&(_, i)| planes.get(i).map(|p| p.1.clone()).unwrap_or_default())
        .collect();
    (c_deg, candela)
}

fn near(a: f64, b: f64) -> bool {
    (a - b).abs() <= ANGLE_TOLERANCE
}

// ------------------------------------------------------------------------------------------
// IES LM-63
// ------------------------------------------------------------------------------------------

/// Which LM-63 edition a file says it follows; it decides what the second field after the
/// lamp line means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum IesVersion {
    /// No version line (LM-63-1986), or an `IESNA` line this reader does not know.
    Lm1986,
    Lm1991,
    Lm1995,
    Lm2002,
    Lm2019,
}

impl IesVersion {
    /// Whether the field after the ballast factor is the ballast-lamp photometric factor
    /// (multiplied in) rather than LM-63-2002's "future use" (ignored).
    fn has_ballast_lamp_factor(self) -> bool {
        matches!(self, IesVersion::Lm1986 | IesVersion::Lm1991 | IesVersion::Lm1995)
    }
}

/// The `TILT=INCLUDE` block: lamp-to-luminaire geometry, tilt angles and multiplying factors.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(not(test), allow(dead_code))] // the fields other than `factor` are read by the tests
struct Tilt {
    geometry: u64,
    angles: Vec<f64>,
    factors: Vec<f64>,
    /// The factor at a tilt of 0° (the luminaire as measured), applied to every value.
    factor: f64,
}

/// What [`parse_ies`] reads, beyond the [`Photometry`], for the tests to check.
#[derive(Clone, Debug)]
#[cfg_attr(not(test), allow(dead_code))] // read by the tests
struct IesFile {
    photometry: Photometry,
    version: IesVersion,
    tilt: Option<Tilt>,
    lamps: f64,
    /// −1 for absolute photometry.
    lumens_per_lamp: f64,
    /// The product of every multiplier applied to the file's numbers.
    scale: f64,
}

/// Parse IES LM-63 (1986/1991/1995/2002 — `IESNA:LM-63-1995`, `IESNA:LM-63-2002`, and files with no IESNA line), TILT=NONE, `TILT=INCLUDE` (the tilt block inline) and `TILT=<file>` (refuse: say the tilt file must be included inline); photometric type 1 (C) read; type 2 (B) and type 3 (A): convert B to C if you can do it correctly, else refuse with a clear message naming the type and suggesting re-export as type C — your choice, document it.
///
/// Types B and A are refused (see the module documentation for why).
pub fn parse_ies(text: &str, path: &std::path::Path) -> crate::Result<Photometry> {
    read_ies(text, path).map(|file| file.photometry)
}

fn ies_version(first_line: &str) -> IesVersion {
    let squeezed: String =
        first_line.chars().filter(|c| !c.is_whitespace()).collect::<String>().to_ascii_uppercase();
    if squeezed.starts_with("IESNA:LM-63-2002") {
        IesVersion::Lm2002
    } else if squeezed.starts_with("IESNA:LM-63-1995") {
        IesVersion::Lm1995
    } else if squeezed.starts_with("IESNA91") {
        IesVersion::Lm1991
    } else if squeezed.starts_with("IES:LM-63-2019") {
        IesVersion::Lm2019
    } else {
        IesVersion::Lm1986
    }
}

/// Whether a line is a version line at all (so it is not a label line of the description).
fn is_version_line(line: &str) -> bool {
    let t = line.trim_start().to_ascii_uppercase();
    t.starts_with("IESNA") || t.starts_with("IES:LM-63")
}

/// The value of a `TILT=` line, if `line` is one.
fn tilt_value(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let head = t.get(..4)?;
    if !head.eq_ignore_ascii_case("TILT") {
        return None;
    }
    let rest = t.get(4..)?.trim_start();
    rest.strip_prefix('=').map(str::trim)
}

/// `[KEY] value` of a keyword line (LM-63-1995 and later).
fn keyword(line: &str) -> Option<(String, &str)> {
    let rest = line.trim().strip_prefix('[')?;
    let end = rest.find(']')?;
    Some((rest.get(..end)?.trim().to_ascii_uppercase(), rest.get(end + 1..)?.trim()))
}

/// Manufacturer, catalogue, luminaire and lamp keywords (with their `[MORE]` continuations), or
/// every label line of a file without keywords (LM-63-1986).
fn ies_description(header: &[&str]) -> String {
    const KEPT: [&str; 5] = ["MANUFAC", "LUMCAT", "LUMINAIRE", "LAMPCAT", "LAMP"];
    let mut parts: Vec<String> = Vec::new();
    let mut any_keyword = false;
    let mut continuing = false;
    for line in header {
        let Some((key, value)) = keyword(line) else {
            continue;
        };
        any_keyword = true;
        if key == "MORE" {
            if continuing
                && !value.is_empty()
                && let Some(last) = parts.last_mut()
            {
                last.push(' ');
                last.push_str(value);
            }
            continue;
        }
        continuing = KEPT.contains(&key.as_str()) && !value.is_empty();
        if continuing {
            parts.push(format!("{key}: {value}"));
        }
    }
    if !any_keyword {
        parts =
            header.iter().map(|l| l.trim()).filter(|l| !l.is_empty()).map(String::from).collect();
    }
    parts.join("; ")
}

/// The lateral symmetry of a type C web, from its first and last horizontal angles
/// (LM-63-2002, horizontal angles for type C photometry).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Lateral {
    /// One horizontal angle: the same distribution in every plane.
    Rotational,
    /// 0–90: symmetric in each quadrant.
    Quadrant,
    /// 0–180: symmetric about the 0–180 plane.
    Bilateral0To180,
    /// 90–270: symmetric about the 90–270 plane (LM-63-2002).
    Bilateral90To270,
    /// 0 to more than 180: no symmetry.
    Full,
}

fn ies_lateral(horizontal: &[f64]) -> Option<Lateral> {
    let (&first, &last) = (horizontal.first()?, horizontal.last()?);
    if horizontal.len() == 1 {
        return Some(Lateral::Rotational);
    }
    if near(first, 0.0) {
        if near(last, 90.0) {
            Some(Lateral::Quadrant)
        } else if near(last, 180.0) {
            Some(Lateral::Bilateral0To180)
        } else if last > 180.0 && last <= 360.0 + ANGLE_TOLERANCE {
            Some(Lateral::Full)
        } else {
            None
        }
    } else if near(first, 90.0) && near(last, 270.0) {
        Some(Lateral::Bilateral90To270)
    } else {
        None
    }
}

fn read_ies(text: &str, path: &Path) -> Result<IesFile> {
    let lines = split_lines(text);
    let version = lines.first().map_or(IesVersion::Lm1986, |l| ies_version(l));
    let header_start = usize::from(lines.first().is_some_and(|l| is_version_line(l)));
    let Some(tilt_index) = lines.iter().skip(header_start).position(|l| tilt_value(l).is_some())
    else {
        return Err(SceneError::invalid(
            path,
            format!("TILT line (none in lines 1–{})", lines.len()),
            "no TILT= line found; LM-63 requires a line TILT=NONE, TILT=INCLUDE or \
             TILT=<file> after the label or keyword lines — add TILT=NONE if the lamp output \
             does not depend on the luminaire's tilt",
        ));
    };
    let tilt_index = tilt_index + header_start;
    let header = lines.get(header_start..tilt_index).unwrap_or(&[]);
    let tilt_line = lines.get(tilt_index).copied().unwrap_or("");
    let tilt_text = tilt_value(tilt_line).unwrap_or("");
    let tilt_column =
        tilt_line.find('=').map_or(1, |i| tilt_line.get(..i).map_or(1, |s| s.chars().count() + 2));

    let mut cursor = Cursor {
        path,
        tokens: Tokens::new(&lines, tilt_index + 1, ies_separator),
        decimal_comma: false,
    };

    let tilt = if tilt_text.eq_ignore_ascii_case("NONE") {
        None
    } else if tilt_text.eq_ignore_ascii_case("INCLUDE") {
        Some(read_tilt(&mut cursor)?)
    } else if tilt_text.is_empty() {
        return Err(SceneError::syntax(
            path,
            tilt_index + 1,
            tilt_column,
            "TILT= has no value; write TILT=NONE (or TILT=INCLUDE followed by the tilt table)",
        ));
    } else {
        return Err(SceneError::syntax(
            path,
            tilt_index + 1,
            tilt_column,
            format!(
                "TILT={tilt_text} refers to a separate tilt file, which restauro does not read; \
                 include the tilt data inline (TILT=INCLUDE followed by the lamp-to-luminaire \
                 geometry, the number of pairs, the angles and the factors), or write TILT=NONE \
                 if the lamp output does not depend on tilt"
            ),
        ));
    };

    // <# lamps> <lumens/lamp> <multiplier> <# vertical> <# horizontal> <type> <units> <w> <l> <h>
    let (lamps, _) = cursor.number(&|| "the number of lamps".to_string())?;
    let (lumens_per_lamp, lumens_token) = cursor.number(&|| "the lumens per lamp".to_string())?;
    if lumens_per_lamp < 0.0 && lumens_per_lamp != -1.0 {
        return Err(cursor.error_at(
            &lumens_token,
            format!(
                "lumens per lamp is {lumens_per_lamp}; LM-63 uses -1 for absolute photometry and \
                 the rated lamp lumens (positive) otherwise"
            ),
        ));
    }
    let (multiplier, _) = cursor.factor("the candela multiplier")?;
    let (n_vertical, vertical_token) = cursor.count("the number of vertical angles", 1)?;
    let (n_horizontal, _) = cursor.count("the number of horizontal angles", 1)?;
    let (photometric_type, type_token) = cursor.number(&|| "the photometric type".to_string())?;
    match whole(photometric_type) {
        Some(1) => {}
        Some(t @ (2 | 3)) => {
            let name = if t == 2 { "B" } else { "A" };
            return Err(cursor.error_at(
                &type_token,
                format!(
                    "photometric type {t} (type {name} photometry) is not supported: restauro \
                     reads type C webs (photometric type 1) only; re-export the file as type C \
                     photometry"
                ),
            ));
        }
        _ => {
            return Err(cursor.error_at(
                &type_token,
                format!(
                    "photometric type '{}' is unknown; LM-63 defines 1 (type C), 2 (type B) and 3 \
                     (type A) — check the field order of this line",
                    type_token.text
                ),
            ));
        }
    }
    for what in
        ["the units type", "the luminous width", "the luminous length", "the luminous height"]
    {
        cursor.number(&|| what.to_string())?;
    }
    // <ballast factor> <ballast-lamp photometric factor | future use> <input watts>
    let (ballast, _) = cursor.factor("the ballast factor")?;
    let lamp_factor = if version.has_ballast_lamp_factor() {
        cursor.factor("the ballast-lamp photometric factor")?.0
    } else {
        cursor.number(&|| "the 'future use' field after the ballast factor".to_string())?;
        1.0
    };
    cursor.number(&|| "the input watts".to_string())?;

    let counts = format!(
        "{n_horizontal} horizontal × {n_vertical} vertical angles, line {}",
        vertical_token.line
    );
    check_table_size(path, n_horizontal, n_vertical, &counts)?;
    let vertical = cursor.angles(n_vertical, "vertical angle", 0.0, 180.0)?;
    let horizontal_start = cursor.tokens.next_token_position();
    let horizontal = cursor.angles(n_horizontal, "horizontal angle", 0.0, 360.0)?;
    let Some(lateral) = ies_lateral(&horizontal) else {
        let (first, last) =
            (horizontal.first().copied().unwrap_or(0.0), horizontal.last().copied().unwrap_or(0.0));
        return Err(SceneError::invalid(
            path,
            format!("horizontal angles (from line {}:{})", horizontal_start.0, horizontal_start.1),
            format!(
                "the horizontal angles run from {first}° to {last}°, which is none of the type C \
                 symmetries of LM-63-2002: a single angle (rotational), 0–90 (quadrant), 0–180 \
                 (bilateral), 90–270 (bilateral) or 0 to more than 180 up to 360 (none); \
                 re-export the file with one of these ranges"
            ),
        ));
    };
    let tilt_factor = tilt.as_ref().map_or(1.0, |t| t.factor);
    let scale = multiplier * ballast * lamp_factor * tilt_factor;
    let table = cursor.table(&horizontal, &vertical, scale, &counts)?;

    let mut planes: Vec<(f64, Vec<f64>)> = horizontal.into_iter().zip(table).collect();
    let mirrors: &[Mirror] = match lateral {
        Lateral::Rotational | Lateral::Full => &[],
        Lateral::Quadrant => &[mirror_0_180, mirror_90_270, mirror_both],
        Lateral::Bilateral0To180 => &[mirror_0_180],
        Lateral::Bilateral90To270 => &[mirror_90_270],
    };
    if lateral == Lateral::Full && planes.last().is_some_and(|p| near(p.0, 360.0)) {
        // The closing plane is the 0° plane again.
        planes.pop();
    }
    let (c_deg, candela) = expand_planes(planes, mirrors);
    Ok(IesFile {
        photometry: Photometry {
            gamma_deg: vertical,
            c_deg,
            candela,
            description: ies_description(header),
        },
        version,
        tilt,
        lamps,
        lumens_per_lamp,
        scale,
    })
}

/// The `TILT=INCLUDE` block (LM-63-2002, TILT): geometry 1–3, the number of pairs, the angles
/// (increasing) and the multiplying factors (non-negative).
fn read_tilt(cursor: &mut Cursor) -> Result<Tilt> {
    let (geometry, token) =
        cursor.number(&|| "the lamp-to-luminaire geometry of TILT=INCLUDE".to_string())?;
    let geometry = match whole(geometry) {
        Some(g @ 1..=3) => g,
        _ => {
            return Err(cursor.error_at(
                &token,
                format!(
                    "lamp-to-luminaire geometry '{}' is unknown; LM-63-2002 defines 1, 2 and 3 — \
                     check that the tilt block follows TILT=INCLUDE directly",
                    token.text
                ),
            ));
        }
    };
    let (n, _) = cursor.count("the number of tilt angle and factor pairs", 1)?;
    let angles = cursor.angles(n, "tilt angle", -360.0, 360.0)?;
    let mut factors = Vec::with_capacity(n);
    for i in 0..n {
        let (v, token) = cursor.number(&|| format!("tilt multiplying factor {} of {n}", i + 1))?;
        if v < 0.0 {
            return Err(cursor.error_at(
                &token,
                format!(
                    "tilt multiplying factor {} of {n} is {v}, negative; a multiplying factor \
                     must be 0 or more",
                    i + 1
                ),
            ));
        }
        factors.push(v);
    }
    let factor = interpolate_table(&angles, &factors, 0.0);
    Ok(Tilt { geometry, angles, factors, factor })
}

/// Linear interpolation in a table with increasing `xs`; the end values outside it.
fn interpolate_table(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len().min(ys.len());
    let (Some(&x0), Some(&y0)) = (xs.first(), ys.first()) else {
        return 1.0;
    };
    if x <= x0 {
        return y0;
    }
    let i = xs.get(..n).unwrap_or(&[]).partition_point(|&a| a <= x);
    if i >= n {
        return ys.get(n.saturating_sub(1)).copied().unwrap_or(1.0);
    }
    let below = i.saturating_sub(1);
    match (xs.get(below), xs.get(i), ys.get(below), ys.get(i)) {
        (Some(&xa), Some(&xb), Some(&ya), Some(&yb)) if xb > xa => {
            let t = (x - xa) / (xb - xa);
            (1.0 - t) * ya + t * yb
        }
        (_, _, Some(&ya), _) => ya,
        _ => 1.0,
    }
}

// ------------------------------------------------------------------------------------------
// EULUMDAT
// ------------------------------------------------------------------------------------------

/// The EULUMDAT header fields 1–26 by line, for messages.
const LDT_FIELDS: [&str; 26] = [
    "company identification (field 1)",
    "type indicator Ityp (field 2)",
    "symmetry indicator Isym (field 3)",
    "number of C-planes Mc (field 4)",
    "distance between C-planes Dc (field 5)",
    "number of luminous intensities per C-plane Ng (field 6)",
    "distance between luminous intensities Dg (field 7)",
    "measurement report number (field 8)",
    "luminaire name (field 9)",
    "luminaire number (field 10)",
    "file name (field 11)",
    "date/user (field 12)",
    "length/diameter of luminaire (field 13)",
    "width of luminaire (field 14)",
    "height of luminaire (field 15)",
    "length/diameter of luminous area (field 16)",
    "width of luminous area (field 17)",
    "height of luminous area C0 (field 18)",
    "height of luminous area C90 (field 19)",
    "height of luminous area C180 (field 20)",
    "height of luminous area C270 (field 21)",
    "downward flux fraction DFF (field 22)",
    "light output ratio LORL (field 23)",
    "conversion factor for luminous intensities (field 24)",
    "tilt of luminaire during measurement (field 25)",
    "number of standard sets of lamps n (field 26)",
];

/// What [`parse_ldt`] reads, beyond the [`Photometry`], for the tests to check.
#[derive(Clone, Debug)]
#[cfg_attr(not(test), allow(dead_code))] // read by the tests
struct LdtFile {
    photometry: Photometry,
    isym: u64,
    /// Mc and Ng as declared (before symmetry expansion).
    mc: usize,
    ng: usize,
    /// Field 26a of the first lamp set (negative: absolute photometry).
    lamps: i64,
    /// Field 26c of the first lamp set.
    lamp_flux_lm: f64,
    conversion_factor: f64,
    dff_percent: f64,
    lor_percent: f64,
}

/// Parse EULUMDAT (.ldt): symmetry indicators 0–4, C-planes and γ angles, the intensity table in cd/klm scaled by the lamp flux of the first lamp set (times number of lamps; document how you treat the 'absolute photometry' case of a negative number of lamps), and expanded to the full circle per the symmetry.
///
/// As documented at the top of this module: field 26c is already the total flux of the set's
/// lamps, so it is not multiplied by the number of lamps again, and a negative number of lamps
/// (absolute photometry) scales the same way.
pub fn parse_ldt(text: &str, path: &std::path::Path) -> crate::Result<Photometry> {
    read_ldt(text, path).map(|file| file.photometry)
}

/// Reads the line-per-field part of an EULUMDAT file.
struct LdtLines<'a> {
    path: &'a Path,
    lines: &'a [&'a str],
}

impl<'a> LdtLines<'a> {
    /// Line `number` (1-based), which holds `what`.
    fn text(&self, number: usize, what: &str) -> Result<&'a str> {
        match number.checked_sub(1).and_then(|i| self.lines.get(i)) {
            Some(line) => Ok(line.trim()),
            None => {
                let last = self.lines.len();
                Err(SceneError::syntax(
                    self.path,
                    last.max(1),
                    self.lines.last().map_or(1, |l| l.chars().count() + 1),
                    format!(
                        "the file ends after line {last}, before line {number} ({what}): it is \
                         truncated; re-export or re-download the complete file"
                    ),
                ))
            }
        }
    }

    fn number(&self, number: usize, what: &str) -> Result<f64> {
        let text = self.text(number, what)?;
        let column = number
            .checked_sub(1)
            .and_then(|i| self.lines.get(i))
            .map_or(1, |l| l.chars().take_while(|c| c.is_whitespace()).count() + 1);
        match parse_number(text, true) {
            Ok(v) => Ok(v),
            Err(NumberProblem::NotANumber) => Err(SceneError::syntax(
                self.path,
                number,
                column,
                format!(
                    "{what} is '{text}', not a number; EULUMDAT has one field per line, so a line \
                     is probably missing or extra above this one"
                ),
            )),
            Err(NumberProblem::NotFinite) => Err(SceneError::syntax(
                self.path,
                number,
                column,
                format!("{what} is '{text}', not a finite number; write a finite value"),
            )),
        }
    }

    /// A whole number in `range` (inclusive), for indicators and counts.
    fn whole(&self, number: usize, what: &str, lo: i64, hi: i64) -> Result<i64> {
        let v = self.number(number, what)?;
        if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
            return Err(SceneError::syntax(
                self.path,
                number,
                1,
                format!("{what} is {v}; it must be a whole number from {lo} to {hi}"),
            ));
        }
        Ok(v as i64)
    }

    fn count(&self, number: usize, what: &str, limit: usize) -> Result<usize> {
        let v = self.number(number, what)?;
        let Some(n) = whole(v) else {
            return Err(SceneError::syntax(
                self.path,
                number,
                1,
                format!("{what} is {v}; it must be a whole number, 0 or more"),
            ));
        };
        if n > limit as u64 {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!("{what} (line {number})"),
                value: n,
                limit: limit as u64,
                fix: LIMIT_FIX.into(),
            });
        }
        Ok(n as usize)
    }
}

fn read_ldt(text: &str, path: &Path) -> Result<LdtFile> {
    let lines = split_lines(text);
    let header = LdtLines { path, lines: &lines };
    let field =
        |n: usize| n.checked_sub(1).and_then(|i| LDT_FIELDS.get(i)).copied().unwrap_or("a field");

    let company = header.text(1, field(1))?;
    header.whole(2, field(2), 0, 3)?;
    let isym = header.whole(3, field(3), 0, 4)? as u64;
    let mc = header.count(4, field(4), MAX_ANGLES)?;
    header.number(5, field(5))?;
    let ng = header.count(6, field(6), MAX_ANGLES)?;
    header.number(7, field(7))?;
    let report = header.text(8, field(8))?;
    let name = header.text(9, field(9))?;
    let number = header.text(10, field(10))?;
    header.text(11, field(11))?;
    let date = header.text(12, field(12))?;
    for n in 13..=21 {
        header.number(n, field(n))?;
    }
    let dff_percent = header.number(22, field(22))?;
    let lor_percent = header.number(23, field(23))?;
    let conversion_factor = header.number(24, field(24))?;
    if conversion_factor <= 0.0 {
        return Err(SceneError::syntax(
            path,
            24,
            1,
            format!(
                "{} is {conversion_factor}; it multiplies every intensity, so it must be a \
                 positive number (1.0 in most files)",
                field(24)
            ),
        ));
    }
    header.number(25, field(25))?;
    let sets = header.count(26, field(26), MAX_LAMP_SETS)?;
    if sets == 0 {
        return Err(SceneError::syntax(
            path,
            26,
            1,
            "the number of lamp sets (field 26) is 0, so there is no lamp flux to turn the cd/klm \
             table into candela; give at least one lamp set",
        ));
    }
    // Fields 26a–26f, each for every set before the next field.
    let lamp_line = |field_index: usize, set: usize| 27 + field_index * sets + set;
    let lamps = header.number(lamp_line(0, 0), "number of lamps of lamp set 1 (field 26a)")?;
    if lamps.fract() != 0.0 {
        return Err(SceneError::syntax(
            path,
            lamp_line(0, 0),
            1,
            format!("the number of lamps of lamp set 1 (field 26a) is {lamps}; it must be whole"),
        ));
    }
    let lamp_type = header.text(lamp_line(1, 0), "type of lamps of lamp set 1 (field 26b)")?;
    let flux_line = lamp_line(2, 0);
    let lamp_flux_lm = header.number(flux_line, "total luminous flux of lamp set 1 (field 26c)")?;
    if lamp_flux_lm <= 0.0 {
        return Err(SceneError::syntax(
            path,
            flux_line,
            1,
            format!(
                "the total luminous flux of lamp set 1 (field 26c) is {lamp_flux_lm} lm; the \
                 intensities are in cd per 1000 lm of it, so it must be a positive number of lumens"
            ),
        ));
    }
    // The rest of the lamp block and the direct ratios only have to be there.
    let ratios_start = 27 + 6 * sets;
    for n in flux_line + 1..ratios_start {
        header.text(n, "lamp data (fields 26a–26f)")?;
    }
    for (i, n) in (ratios_start..ratios_start + 10).enumerate() {
        let what = format!("direct ratio {} of 10 (field 27)", i + 1);
        if !header.text(n, &what)?.is_empty() {
            header.number(n, &what)?;
        }
    }

    if mc == 0 && isym != 1 {
        return Err(SceneError::syntax(
            path,
            4,
            1,
            format!(
                "{} is 0; only a rotationally symmetric file (Isym 1) may omit C-planes",
                field(4)
            ),
        ));
    }
    if ng == 0 {
        return Err(SceneError::syntax(
            path,
            6,
            1,
            format!("{} is 0; the file needs at least one γ angle", field(6)),
        ));
    }
    let divisor = match isym {
        2 => 2,
        3 | 4 => 4,
        _ => 1,
    };
    if mc % divisor != 0 {
        return Err(SceneError::syntax(
            path,
            4,
            1,
            format!(
                "Mc (field 4) is {mc}, but symmetry Isym {isym} needs Mc divisible by {divisor} \
                 (the stored C-planes are defined by Mc/{divisor}); check Mc and Isym"
            ),
        ));
    }
    // Field 30: the C-planes Mc1..Mc2 that are stored (indices into the Mc C-angles).
    let stored: Vec<usize> = match isym {
        0 => (0..mc).collect(),
        1 => vec![0],
        2 => (0..=mc / 2).collect(),
        3 => (0..=mc / 2).map(|j| (3 * mc / 4 + j) % mc).collect(),
        _ => (0..=mc / 4).collect(),
    };
    let counts = format!(
        "{} stored C-planes for Isym {isym} with Mc = {mc}, × Ng = {ng} γ angles",
        stored.len()
    );
    check_table_size(path, stored.len(), ng, &counts)?;

    let data_start = ratios_start + 10; // 1-based line of the first C-angle
    let mut cursor = Cursor {
        path,
        tokens: Tokens::new(&lines, data_start - 1, ldt_separator),
        decimal_comma: true,
    };
    let c_start = cursor.tokens.next_token_position();
    let c_angles = cursor.angles(mc, "C-angle (field 28)", 0.0, 360.0)?;
    let gammas = cursor.angles(ng, "γ angle (field 29)", 0.0, 180.0)?;

    let plane_angles: Vec<f64> = if isym == 1 {
        vec![0.0]
    } else {
        stored.iter().map(|&i| c_angles.get(i).copied().unwrap_or(0.0)).collect()
    };
    let allowed: fn(f64) -> bool = match isym {
        2 => |c| c <= 180.0 + ANGLE_TOLERANCE,
        3 => |c| c <= 90.0 + ANGLE_TOLERANCE || c >= 270.0 - ANGLE_TOLERANCE,
        4 => |c| c <= 90.0 + ANGLE_TOLERANCE,
        _ => |_| true,
    };
    if let Some(&bad) = plane_angles.iter().find(|&&c| !allowed(c)) {
        let range = match isym {
            2 => "C0 to C180",
            3 => "C270 through C0 to C90",
            _ => "C0 to C90",
        };
        return Err(SceneError::invalid(
            path,
            format!("C-angles (field 28, from line {}:{})", c_start.0, c_start.1),
            format!(
                "symmetry Isym {isym} stores the C-planes {range}, but the stored planes include \
                 C{bad}; the C-angles do not match Mc and Isym — check fields 3, 4 and 28"
            ),
        ));
    }
    let scale = conversion_factor * lamp_flux_lm / 1000.0;
    let table = cursor.table(&plane_angles, &gammas, scale, &counts)?;
    let planes: Vec<(f64, Vec<f64>)> = plane_angles.into_iter().zip(table).collect();
    let mirrors: &[Mirror] = match isym {
        2 => &[mirror_0_180],
        3 => &[mirror_90_270],
        4 => &[mirror_0_180, mirror_90_270, mirror_both],
        _ => &[],
    };
    let (c_deg, candela) = expand_planes(planes, mirrors);
    let description = [company, name, number, report, date, lamp_type]
        .iter()
        .filter(|s| !s.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join("; ");
    Ok(LdtFile {
        photometry: Photometry { gamma_deg: gammas, c_deg, candela, description },
        isym,
        mc,
        ng,
        lamps: lamps as i64,
        lamp_flux_lm,
        conversion_factor,
        dff_percent,
        lor_percent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_luminaire_frame_points_its_nadir_at_the_aim_with_c0_towards_east() {
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
        // Hung pointing down: the file's own frame, C = 0 east.
        let [x, y, z] = luminaire_frame([1.0, 2.0, 5.0], None);
        assert!(
            close(x, [1.0, 0.0, 0.0]) && close(y, [0.0, 1.0, 0.0]) && close(z, [0.0, 0.0, 1.0])
        );
        // Aimed north and level: the nadir (−z) points north, C = 0 still east, and C = 90°
        // (y = z × x, a right-handed frame) up.
        let [x, y, z] = luminaire_frame([0.0, 0.0, 1.0], Some([0.0, 10.0, 1.0]));
        assert!(close(z, [0.0, -1.0, 0.0]) && close(x, [1.0, 0.0, 0.0]), "{x:?} {z:?}");
        assert!(close(y, [0.0, 0.0, 1.0]), "{y:?}");
        // Aimed east: C = 0 falls back to north.
        let [x, _, z] = luminaire_frame([0.0, 0.0, 1.0], Some([3.0, 0.0, 1.0]));
        assert!(close(z, [-1.0, 0.0, 0.0]) && close(x, [0.0, 1.0, 0.0]), "{x:?} {z:?}");
    }
    use std::path::PathBuf;

    const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/photometric");
    const ASA: &str = "luxcore_ASA_15M_R2.ies";
    const SPEC: &str = "lidrs_iesna2002_spec_example_tilt_include.ies";
    const BEGA_ROUND: &str = "threejs_BEGA_50975.6K3_007cfb11e343e2f42e3b476be4ab684e.ies";
    const BEGA_24: &str = "threejs_BEGA_50899.2K3_06b4cfdc8805709e767b5e2e904be8ad.ies";
    const DT106: &str = "threejs_LightLab_DT106_absolute_1a936937a49c63374e6d4fbed9252b29.ies";
    const PROLICHT: &str = "lidrs_prolicht_E30-0019_example.ldt";
    const ISOTROPIC: &str = "isotropic_1000cd.ies";
    const LAMBERT: &str = "lambertian_cos_1000cd.ies";
    const ASYMMETRIC: &str = "asymmetric_24_planes.ies";

    /// The flux of the distribution the table defines, interpolated linearly in γ and in C (the
    /// C planes wrap round the circle; one plane is rotationally symmetric), computed in closed
    /// form from the table alone and not by `flux_lm`: over a band [γ₀, γ₁] where
    /// I = I₀ + s(γ − γ₀), ∫ I sin γ dγ = I₀(cos γ₀ − cos γ₁) + s(sin γ₁ − sin γ₀ − (γ₁ − γ₀) cos γ₁),
    /// and a linear interpolation round the circle averages as the trapezoid rule does.
    fn bilinear_flux_lm(p: &Photometry) -> f64 {
        let gammas: Vec<f64> = p.gamma_deg.iter().map(|g| g.to_radians()).collect();
        let plane_integral = |row: &[f64]| -> f64 {
            (1..gammas.len())
                .map(|k| {
                    let (g0, g1) = (gammas[k - 1], gammas[k]);
                    let slope = (row[k] - row[k - 1]) / (g1 - g0);
                    row[k - 1] * (g0.cos() - g1.cos())
                        + slope * (g1.sin() - g0.sin() - (g1 - g0) * g1.cos())
                })
                .sum()
        };
        let planes: Vec<f64> = p.candela.iter().map(|row| plane_integral(row)).collect();
        if planes.len() == 1 {
            return 2.0 * PI * planes[0];
        }
        let c = &p.c_deg;
        (0..planes.len())
            .map(|k| {
                let next = (k + 1) % planes.len();
                let width_deg = if next == 0 { 360.0 - c[k] + c[0] } else { c[next] - c[k] };
                width_deg.to_radians() * 0.5 * (planes[k] + planes[next])
            })
            .sum()
    }

    fn data(name: &str) -> PathBuf {
        Path::new(DATA).join(name)
    }

    fn text(name: &str) -> String {
        std::fs::read_to_string(data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    }

    fn ies(name: &str) -> IesFile {
        read_ies(&text(name), &data(name)).unwrap_or_else(|e| panic!("{e}"))
    }

    fn ldt(name: &str) -> LdtFile {
        read_ldt(&text(name), &data(name)).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The error of parsing `source` as IES, as text (the test fails if it parses).
    fn ies_error(source: &str) -> (SceneError, String) {
        match read_ies(source, Path::new("bad.ies")) {
            Ok(_) => panic!("parsed, but should have been refused:\n{source}"),
            Err(e) => {
                let message = e.to_string();
                (e, message)
            }
        }
    }

    fn ldt_error(source: &str) -> (SceneError, String) {
        match read_ldt(source, Path::new("bad.ldt")) {
            Ok(_) => panic!("parsed, but should have been refused"),
            Err(e) => {
                let message = e.to_string();
                (e, message)
            }
        }
    }

    fn assert_close(actual: f64, expected: f64, relative: f64) {
        let tolerance = relative * expected.abs().max(1e-300);
        assert!(
            (actual - expected).abs() <= tolerance,
            "{actual} differs from {expected} by more than {relative} relative"
        );
    }

    fn assert_contains(message: &str, parts: &[&str]) {
        for part in parts {
            assert!(message.contains(part), "message lacks '{part}': {message}");
        }
    }

    /// Replaces exactly one occurrence of `from` (the test data must contain it once).
    fn edit(source: &str, from: &str, to: &str) -> String {
        assert_eq!(source.matches(from).count(), 1, "'{from}' must occur once");
        source.replacen(from, to, 1)
    }

    // ---- ideal distributions written by hand ----------------------------------------------

    #[test]
    fn isotropic_source_is_1000_cd_everywhere_and_4_pi_klm() {
        let p = ies(ISOTROPIC).photometry;
        let directions = [
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, -3.0, 0.0],
            [1.0, 1.0, 1.0],
            [-0.3, 0.7, -0.2],
            [5.0, -2.0, 9.0],
            [1e-200, 1e-200, -1e-200],
            [1e200, -1e200, 1e200],
        ];
        for d in directions {
            assert_close(p.intensity_cd(d), 1000.0, 1e-12);
        }
        for (c, g) in [(0.0, 0.0), (17.0, 33.3), (359.9, 179.9), (-45.0, 90.0), (720.5, 180.0)] {
            assert_close(p.intensity_at(c, g), 1000.0, 1e-12);
        }
        assert_close(p.flux_lm(), 4.0 * PI * 1000.0, 1e-3);
        assert_eq!(p.peak_cd(), 1000.0);
    }

    #[test]
    fn lambertian_downlight_gives_pi_times_i0() {
        let p = ies(LAMBERT).photometry;
        // ∫ I0 cos γ dΩ over the lower hemisphere = 2π · I0 · ½ = π · I0.
        let flux = p.flux_lm();
        eprintln!("Lambertian I0 = 1000 cd at 2.5° steps: {flux} lm, π·I0 = {}", PI * 1000.0);
        assert_close(flux, PI * 1000.0, 1e-3);
        assert_eq!(p.intensity_at(0.0, 60.0), 500.0); // "500.000000" in the file
        let d60 = [60f64.to_radians().sin(), 0.0, -60f64.to_radians().cos()];
        assert_close(p.intensity_cd(d60), 500.0, 1e-9);
        assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 0.0);
    }

    /// The beam (50 % of the peak, as an equivalent cone): a Lambertian downlight I0 cos γ is
    /// at half its peak at γ = 60°, so its beam is 120°; an isotropic source fills the sphere.
    #[test]
    fn beam_angles_of_ideal_distributions() {
        let lambert = ies(LAMBERT).photometry.beam_angle_deg();
        assert!((lambert - 120.0).abs() < 0.5, "Lambertian beam {lambert}°");
        let sphere = ies(ISOTROPIC).photometry.beam_angle_deg();
        assert!((sphere - 360.0).abs() < 0.5, "isotropic beam {sphere}°");
    }

    #[test]
    fn flux_of_a_web_that_is_linear_in_gamma_is_exact() {
        // Plane k (C = 15k) holds 100(k+1) + γ/45° at γ = 0, 45, …, 180, which is linear in γ,
        // so ∫ I sin γ dγ = 2·100(k+1) + 4 exactly, each of the 24 sectors is 15° = π/12 wide
        // (the wrap 345°→360° included), and the flux is (π/12)·Σ(200(k+1) + 4) = 5008π.
        let p = ies(ASYMMETRIC).photometry;
        assert_close(p.flux_lm(), 5008.0 * PI, 1e-12);
    }

    // ---- interpolation ----------------------------------------------------------------------

    #[test]
    fn halfway_between_gamma_samples_is_the_mean() {
        let p = ies(ASYMMETRIC).photometry;
        // Plane C = 15 (k = 1): 200 at γ = 0, 201 at γ = 45.
        assert_eq!(p.intensity_at(15.0, 22.5), (200.0 + 201.0) / 2.0);
        let asa = ies(ASA).photometry;
        // ASA 15M, plane C = 0: 1666 cd at γ = 0, 1817 cd at γ = 2.5.
        assert_eq!(asa.intensity_at(0.0, 1.25), (1666.0 + 1817.0) / 2.0);
    }

    #[test]
    fn c_wraps_around_360() {
        let p = ies(ASYMMETRIC).photometry;
        assert_eq!(p.c_deg.len(), 24);
        // C = 359 lies 14/15 of the way from the 345° plane (2400 at γ = 0) to 0°/360° (100).
        let expected = (2400.0 + 14.0 * 100.0) / 15.0;
        assert_close(p.intensity_at(359.0, 0.0), expected, 1e-12);
        assert_close(p.intensity_at(-1.0, 0.0), expected, 1e-12);
        assert_close(p.intensity_at(719.0, 0.0), expected, 1e-12);
        // Halfway across the wrap at γ = 45: mean of 2401 and 101.
        assert_close(p.intensity_at(352.5, 45.0), 1251.0, 1e-12);
        // Real file: BEGA 50899 has planes 0..345 without a 360° plane, all 2160.3 at γ = 0.
        let bega = ies(BEGA_24).photometry;
        assert_close(bega.intensity_at(359.0, 0.0), 2160.3, 1e-12);
    }

    #[test]
    fn directions_map_to_type_c_angles() {
        let p = ies(ASYMMETRIC).photometry;
        // 100(k+1) + g with k = C/15 and g the γ index (γ = 90 → g = 2).
        assert_eq!(p.intensity_cd([1.0, 0.0, 0.0]), 102.0); // C 0, γ 90
        assert_eq!(p.intensity_cd([0.0, 2.0, 0.0]), 702.0); // C 90 (+Y)
        assert_eq!(p.intensity_cd([-1.0, 0.0, 0.0]), 1302.0); // C 180
        assert_eq!(p.intensity_cd([0.0, -1.0, 0.0]), 1902.0); // C 270
        assert_eq!(p.intensity_cd([0.0, 0.0, -4.0]), 100.0); // nadir, −Z
        assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 104.0); // zenith
        let c30 = [30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0];
        assert_close(p.intensity_cd(c30), 302.0, 1e-12);
        // 45° below the horizon in the C = 90 plane: γ = 45.
        assert_close(p.intensity_cd([0.0, 1.0, -1.0]), 701.0, 1e-12);
        assert_eq!(p.intensity_cd([0.0, 0.0, 0.0]), 0.0);
        assert_eq!(p.intensity_cd([f64::NAN, 1.0, 0.0]), 0.0);
        assert_eq!(p.intensity_cd([f64::INFINITY, 1.0, 0.0]), 0.0);
        assert_eq!(p.intensity_at(f64::NAN, 10.0), 0.0);
    }

    // ---- the real files ---------------------------------------------------------------------

    #[test]
    fn asa_15m_street_light() {
        let file = ies(ASA);
        let p = &file.photometry;
        assert_eq!(file.version, IesVersion::Lm2002);
        assert_eq!((file.lamps, file.lumens_per_lamp, file.scale), (1.0, 13000.0, 1.0));
        assert!(file.tilt.is_none());
        assert_contains(
            &p.description,
            &["MANUFAC: American Electric Lighting", "LUMCAT: ASA 15M R2"],
        );
        assert_eq!(p.gamma_deg.len(), 37);
        // 0–180 bilateral: 73 planes 0..180 and their 71 mirror images 182.5..357.5.
        assert_eq!(p.c_deg.len(), 144);
        assert_eq!(p.c_deg.last(), Some(&357.5));
        // Values in the file (multiplier, ballast factor and lamp factor all 1).
        assert_eq!(p.intensity_at(0.0, 0.0), 1666.0);
        assert_eq!(p.intensity_at(0.0, 2.5), 1817.0);
        assert_eq!(p.intensity_at(2.5, 5.0), 2019.0);
        assert_eq!(p.intensity_at(180.0, 2.5), 1548.0);
        assert_eq!(p.intensity_at(180.0, 87.5), 3.0);
        assert_eq!(p.intensity_at(177.5, 2.5), 1559.0);
        // The mirror images about the 0–180 plane.
        assert_eq!(p.intensity_at(357.5, 5.0), 2019.0);
        assert_eq!(p.intensity_at(182.5, 2.5), 1559.0);
        // Measured only up to γ = 90°: nothing above.
        assert_eq!(p.intensity_at(0.0, 90.5), 0.0);
        assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 0.0);
        let lamp_lumens = file.lamps * file.lumens_per_lamp;
        let flux = p.flux_lm();
        eprintln!(
            "ASA 15M R2: integrated {flux:.1} lm, lamp {lamp_lumens} lm, ratio {:.4}, peak {} cd",
            flux / lamp_lumens,
            p.peak_cd()
        );
        assert!(flux > 0.0 && flux < lamp_lumens * 1.01, "{flux} lm");
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    #[test]
    fn spec_example_reads_its_inline_tilt_table_and_quadrant_symmetry() {
        let file = ies(SPEC);
        let tilt = file.tilt.as_ref().expect("TILT=INCLUDE");
        assert_eq!(tilt.geometry, 1);
        let angles: Vec<f64> = (0..13).map(|i| 15.0 * f64::from(i)).collect();
        assert_eq!(tilt.angles, angles);
        let factors = [1.0, 0.95, 0.94, 0.90, 0.88, 0.87, 0.98, 0.87, 0.88, 0.90, 0.94, 0.95, 1.0];
        assert_eq!(tilt.factors, factors);
        assert_eq!(tilt.factor, 1.0);
        let p = &file.photometry;
        assert_contains(&p.description, &["MANUFAC: Aardvark lighting Inc.", "LAMP: 400 Watt"]);
        assert_eq!(p.gamma_deg, [0.0, 22.5, 45.0, 67.5, 90.0]);
        assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
        assert_eq!(p.intensity_at(0.0, 22.5), 50000.0);
        assert_eq!(p.intensity_at(45.0, 22.5), 35000.0);
        assert_eq!(p.intensity_at(90.0, 90.0), 1000.0);
        // Quadrant symmetry: 135 ↔ 45, 180 ↔ 0, 225 ↔ 45, 270 ↔ 90, 315 ↔ 45.
        assert_eq!(p.intensity_at(135.0, 22.5), 35000.0);
        assert_eq!(p.intensity_at(180.0, 22.5), 50000.0);
        assert_eq!(p.intensity_at(225.0, 45.0), 16000.0);
        assert_eq!(p.intensity_at(270.0, 90.0), 1000.0);
        assert_eq!(p.intensity_at(315.0, 67.5), 8000.0);
        let lamp = file.lamps * file.lumens_per_lamp;
        let flux = p.flux_lm();
        // A made-up example (100 000 cd at the nadir from a 50 000 lm lamp): its integrated
        // flux exceeds the lamp lumens, so it is checked against the table's own flux.
        eprintln!(
            "LM-63-2002 spec example: integrated {flux:.0} lm, lamp {lamp} lm, ratio {:.4}",
            flux / lamp
        );
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    #[test]
    fn tilt_factor_at_zero_is_applied_and_interpolated() {
        let source = text(SPEC);
        let halved = edit(&source, "1.0 .95 .94", "0.5 .95 .94");
        let p = read_ies(&halved, Path::new("halved.ies")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.photometry.intensity_at(0.0, 0.0), 50000.0);
        // A table from −10° (0.8) to 10° (1.0): 0.9 at 0°.
        let between = edit(
            &source,
            "13\n0 15 30 45 60 75 90 105 120 135 150 165 180\n\
             1.0 .95 .94 .90 .88 .87 .98 .87 .88 .90 .94 .95 1.0",
            "2\n-10 10\n0.8 1.0",
        );
        let p = read_ies(&between, Path::new("between.ies")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.tilt.as_ref().map(|t| t.factor), Some((0.5 * 0.8) + (0.5 * 1.0)));
        assert_close(p.photometry.intensity_at(0.0, 0.0), 90000.0, 1e-12);
    }

    #[test]
    fn bega_50975_rotationally_symmetric_absolute() {
        let file = ies(BEGA_ROUND);
        let p = &file.photometry;
        assert_eq!(file.version, IesVersion::Lm1995);
        assert_eq!(file.lumens_per_lamp, -1.0);
        assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (1, 73));
        assert_eq!(p.intensity_at(0.0, 0.0), 330.8);
        assert_eq!(p.intensity_at(0.0, 22.5), 302.1);
        assert_eq!(p.intensity_at(123.0, 22.5), 302.1);
        assert_eq!(p.intensity_at(250.0, 180.0), 0.0);
        let flux = p.flux_lm();
        // Absolute photometry: the luminaire's own flux, as its [LAMP] line gives it.
        eprintln!("BEGA 50975.6K3 (absolute): integrated {flux:.1} lm; [LAMP] says 321 lm");
        assert_close(flux, 321.0, 5e-3);
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    #[test]
    fn bega_50899_full_circle_without_closing_plane() {
        let file = ies(BEGA_24);
        let p = &file.photometry;
        assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (24, 19));
        assert_eq!(p.c_deg.last(), Some(&345.0));
        assert_eq!(p.intensity_at(0.0, 0.0), 2160.3);
        assert_eq!(p.intensity_at(345.0, 40.0), 284.6);
        assert_eq!(p.intensity_at(90.0, 90.0), 0.0);
        let flux = p.flux_lm();
        eprintln!("BEGA 50899.2K3 (absolute): integrated {flux:.1} lm; [LAMP] says 1221 lm");
        assert_close(flux, 1221.0, 5e-3);
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    #[test]
    fn dt106_candela_multiplier_is_applied() {
        let file = ies(DT106);
        let p = &file.photometry;
        assert_eq!(file.scale, 1.498);
        assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (1, 181));
        assert_eq!(p.intensity_at(0.0, 0.0), 9769.798 * 1.498);
        assert_eq!(p.intensity_at(0.0, 0.5), 9766.099 * 1.498);
        assert_eq!(p.intensity_at(200.0, 10.0), 3310.188 * 1.498);
        assert_eq!(p.intensity_at(0.0, 90.0), 0.0);
        assert_eq!(p.peak_cd(), 9769.798 * 1.498);
        let flux = p.flux_lm();
        // The report states no flux: the table's own, times the multiplier.
        eprintln!("DT106 (absolute, ×1.498): integrated {flux:.1} lm");
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    #[test]
    fn prolicht_eulumdat() {
        let file = ldt(PROLICHT);
        let p = &file.photometry;
        assert_eq!((file.isym, file.mc, file.ng), (0, 20, 37));
        assert_eq!((file.lamps, file.lamp_flux_lm, file.conversion_factor), (1, 5134.0, 1.0));
        assert_eq!((file.dff_percent, file.lor_percent), (100.0, 100.0));
        assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (20, 37));
        assert_eq!(p.c_deg.get(19), Some(&342.0));
        assert_contains(&p.description, &["Ingemann", "Prolicht E30-0019"]);
        // cd/klm × 5134 lm / 1000 (conversion factor 1.0).
        let klm = 1.0 * 5134.0 / 1000.0;
        assert_eq!(p.intensity_at(0.0, 0.0), 270.1222 * klm);
        assert_eq!(p.intensity_at(0.0, 5.0), 273.82946 * klm);
        assert_eq!(p.intensity_at(18.0, 15.0), 274.09588 * klm);
        assert_eq!(p.intensity_at(342.0, 90.0), 5.36604 * klm);
        assert_eq!(p.intensity_at(342.0, 180.0), 97.45574 * klm);
        // Wrap between C342 and C360 = C0 at γ = 0, both 270.1222.
        assert_close(p.intensity_at(351.0, 0.0), 270.1222 * klm, 1e-12);
        let flux = p.flux_lm();
        let declared = file.lamp_flux_lm * file.lor_percent / 100.0;
        let downward: f64 = {
            let lower = Photometry {
                gamma_deg: p.gamma_deg.iter().copied().filter(|&g| g <= 90.0).collect(),
                c_deg: p.c_deg.clone(),
                candela: p.candela.iter().map(|r| r.iter().take(19).copied().collect()).collect(),
                description: String::new(),
            };
            lower.flux_lm()
        };
        eprintln!(
            "Prolicht E30-0019: integrated {flux:.1} lm; lamp flux {} lm × LOR {} % = {declared} \
             lm; ratio {:.4}; downward {:.1} % (DFF says {} %)",
            file.lamp_flux_lm,
            file.lor_percent,
            flux / declared,
            100.0 * downward / flux,
            file.dff_percent
        );
        // The light output ratio of 100 % says the luminaire emits the lamp's whole flux.
        assert_close(flux, declared, 2e-3);
        assert_close(flux, bilinear_flux_lm(p), 1e-3);
    }

    // ---- symmetries -------------------------------------------------------------------------

    #[test]
    fn ies_bilateral_about_90_270() {
        let p = ies("bilateral_90_270.ies").photometry;
        assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
        // C ↔ 180 − C: 0 ↔ 180 (30), 45 ↔ 135 (20), 315 ↔ 225 (40).
        assert_eq!(p.intensity_at(0.0, 0.0), 30.0);
        assert_eq!(p.intensity_at(45.0, 90.0), 21.0);
        assert_eq!(p.intensity_at(315.0, 180.0), 42.0);
        assert_eq!(p.intensity_at(270.0, 0.0), 50.0);
        assert_eq!(p.intensity_at(22.5, 0.0), 25.0);
    }

    #[test]
    fn eulumdat_isym_3_stores_c270_through_c0_to_c90() {
        let file = ldt("ldt_isym3_c90_c270.ldt");
        let p = &file.photometry;
        assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
        // Stored C270 50.., C315 40.., C0 10.., C45 20.., C90 30.., × 2000 lm / 1000 (field
        // 26c is the total of the 2 lamps, not multiplied again).
        assert_eq!(p.intensity_at(270.0, 0.0), 100.0);
        assert_eq!(p.intensity_at(315.0, 0.0), 80.0);
        assert_eq!(p.intensity_at(0.0, 0.0), 20.0);
        assert_eq!(p.intensity_at(45.0, 0.0), 40.0);
        assert_eq!(p.intensity_at(90.0, 0.0), 60.0);
        // Mirrors C ↔ 180 − C: 135 ↔ 45, 180 ↔ 0, 225 ↔ 315.
        assert_eq!(p.intensity_at(135.0, 0.0), 40.0);
        assert_eq!(p.intensity_at(180.0, 90.0), 22.0);
        assert_eq!(p.intensity_at(225.0, 180.0), 84.0);
    }

    #[test]
    fn eulumdat_isym_4_and_2() {
        let p = ldt("ldt_isym4_quadrant.ldt").photometry;
        assert_eq!(p.c_deg.len(), 8);
        let expected = [20.0, 40.0, 60.0, 40.0, 20.0, 40.0, 60.0, 40.0];
        for (c, e) in p.c_deg.iter().zip(expected) {
            assert_eq!(p.intensity_at(*c, 0.0), e, "C {c}");
        }
        let p = ldt("ldt_isym2_c0_c180.ldt").photometry;
        assert_eq!(p.c_deg.len(), 8);
        let expected = [20.0, 40.0, 60.0, 80.0, 100.0, 80.0, 60.0, 40.0];
        for (c, e) in p.c_deg.iter().zip(expected) {
            assert_eq!(p.intensity_at(*c, 0.0), e, "C {c}");
        }
    }

    #[test]
    fn eulumdat_isym_1_with_negative_lamp_count() {
        let file = ldt("ldt_isym1_absolute.ldt");
        assert_eq!(file.lamps, -1);
        let p = &file.photometry;
        assert_eq!(p.c_deg, [0.0]);
        // 100, 50, 0 cd/klm × conversion factor 2 × 1000 lm / 1000.
        assert_eq!(p.intensity_at(0.0, 0.0), 200.0);
        assert_eq!(p.intensity_at(77.0, 90.0), 100.0);
        assert_eq!(p.intensity_at(300.0, 45.0), 150.0);
    }

    #[test]
    fn lm63_1986_and_its_ballast_lamp_factor() {
        let source = text("lm63_1986_no_version_line.ies");
        let file = read_ies(&source, Path::new("old.ies")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.version, IesVersion::Lm1986);
        assert_contains(&file.photometry.description, &["LM-63-1986 layout"]);
        // 2 × 0.5 × 0.9.
        assert_close(file.photometry.intensity_at(0.0, 0.0), 90.0, 1e-12);
        // Quadrant symmetry: 315 ↔ 45 (40 × 0.9), 270 ↔ 90 (30 × 0.9).
        assert_close(file.photometry.intensity_at(315.0, 45.0), 36.0, 1e-12);
        assert_close(file.photometry.intensity_at(270.0, 45.0), 27.0, 1e-12);
        // In an LM-63-2002 file the same field is "future use" and is not applied.
        let file = read_ies(&format!("IESNA:LM-63-2002\n{source}"), Path::new("new.ies"))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(file.photometry.intensity_at(0.0, 0.0), 100.0);
    }

    // ---- load -------------------------------------------------------------------------------

    #[test]
    fn load_dispatches_on_the_extension() {
        assert_eq!(
            load(&data(ISOTROPIC)).map(|p| p.peak_cd()).unwrap_or_else(|e| panic!("{e}")),
            1000.0
        );
        assert_eq!(
            load(&data(PROLICHT)).map(|p| p.c_deg.len()).unwrap_or_else(|e| panic!("{e}")),
            20
        );
        let upper =
            std::env::temp_dir().join(format!("restauro_photometric_{}.LDT", std::process::id()));
        std::fs::write(&upper, text("ldt_isym1_absolute.ldt")).unwrap_or_else(|e| panic!("{e}"));
        let loaded = load(&upper);
        let _ = std::fs::remove_file(&upper);
        assert_eq!(loaded.map(|p| p.peak_cd()).unwrap_or_else(|e| panic!("{e}")), 200.0);

        let message = load(Path::new("lamp.xyz")).map(|_| ()).unwrap_err().to_string();
        assert_contains(&message, &["lamp.xyz", "'.xyz'", ".ies", ".ldt"]);
        let message = load(Path::new("lamp")).map(|_| ()).unwrap_err().to_string();
        assert_contains(&message, &["no extension"]);
        assert!(matches!(load(Path::new("/nonexistent/lamp.ies")), Err(SceneError::Io { .. })));
        assert_eq!(decode_text(vec![b'A', 0xE9]), "Aé");
    }

    // ---- refusals ---------------------------------------------------------------------------

    #[test]
    fn refuses_a_candela_count_that_does_not_match_the_angles() {
        let source = text(ISOTROPIC);
        let (_, message) = ies_error(source.trim_end().strip_suffix(" 1000").unwrap_or(""));
        assert_contains(
            &message,
            &["bad.ies", "expected 13, found 12", "1 horizontal × 13 vertical"],
        );
        let (e, message) = ies_error(&format!("{source} 1000 7\n"));
        assert_contains(&message, &["expected 13, found 15", "'1000'"]);
        assert!(matches!(e, SceneError::Syntax { line: 12, column: 2, .. }), "{e:?}");
        let (_, message) = ldt_error(&format!("{}5\n", text("ldt_isym4_quadrant.ldt")));
        assert_contains(&message, &["bad.ldt", "expected 9, found 10"]);
        let (_, message) =
            ldt_error(text("ldt_isym4_quadrant.ldt").trim_end().strip_suffix("32").unwrap_or(""));
        assert_contains(&message, &["expected 9, found 8"]);
    }

    #[test]
    fn refuses_angles_not_increasing_or_out_of_range() {
        let source = text(ISOTROPIC);
        let (e, message) = ies_error(&edit(&source, "0 15 30 45", "0 15 45 30"));
        assert_contains(&message, &["bad.ies:9:9", "vertical angle 4 of 13 is 30°", "increasing"]);
        assert!(matches!(e, SceneError::Syntax { line: 9, column: 9, .. }));
        let (_, message) = ies_error(&edit(&source, "165 180", "165 190"));
        assert_contains(&message, &["vertical angle 13 of 13 is 190°", "outside 0..180"]);
        let (_, message) = ies_error(&edit(&source, "0 15 30 45", "-5 15 30 45"));
        assert_contains(&message, &["vertical angle 1 of 13 is -5°"]);
        let ldt_source = text("ldt_isym4_quadrant.ldt");
        let (_, message) =
            ldt_error(&edit(&ldt_source, "\n0\n90\n180\n10\n", "\n0\n190\n180\n10\n"));
        assert_contains(&message, &["γ angle (field 29) 2 of 3 is 190°", "outside 0..180"]);
        let (_, message) = ldt_error(&edit(&ldt_source, "\n45\n90\n135\n", "\n45\n40\n135\n"));
        assert_contains(&message, &["C-angle (field 28) 3 of 8 is 40°", "not greater"]);
        let (_, message) = ies_error(&edit(&text(ASYMMETRIC), "\n195 210", "\n150 210"));
        assert_contains(&message, &["bad.ies:11:1", "horizontal angle 14 of 24 is 150°", "(180°)"]);
    }

    #[test]
    fn refuses_horizontal_ranges_that_are_no_lm63_symmetry() {
        let source = text("bilateral_90_270.ies");
        let (e, message) = ies_error(&edit(&source, "90 135 180 225 270", "90 135 180 225 260"));
        assert!(matches!(e, SceneError::Invalid { .. }));
        assert_contains(
            &message,
            &["horizontal angles (from line 10:1)", "90° to 260°", "re-export"],
        );
    }

    #[test]
    fn refuses_negative_or_non_finite_intensities_and_multipliers() {
        let source = text(ISOTROPIC);
        let last_row = "1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000";
        let (_, message) = ies_error(&edit(
            &source,
            last_row,
            "1000 1000 -5 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000",
        ));
        assert_contains(&message, &["bad.ies:11:11", "C = 0°, γ = 30°", "-5, negative"]);
        let (_, message) = ies_error(&edit(
            &source,
            last_row,
            "1000 nan 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000",
        ));
        assert_contains(&message, &["'nan', not a finite number"]);
        let lamp_line = "1 -1 1 13 1 1 2 0 0 0";
        let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 -2 13 1 1 2 0 0 0"));
        assert_contains(
            &message,
            &["bad.ies:7:6", "candela multiplier is -2", "negative multiplier"],
        );
        let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 inf 13 1 1 2 0 0 0"));
        assert_contains(&message, &["candela multiplier is 'inf', not a finite number"]);
        let (_, message) = ies_error(&edit(&source, "\n1 1 0\n", "\n-0.5 1 0\n"));
        assert_contains(&message, &["ballast factor is -0.5"]);
        let (_, message) = ies_error(&edit(&source, lamp_line, "1 -7 1 13 1 1 2 0 0 0"));
        assert_contains(&message, &["lumens per lamp is -7", "-1 for absolute photometry"]);
        let (_, message) = ies_error(&edit(&text(SPEC), "1.0 .95 .94", "1.0 -.95 .94"));
        assert_contains(&message, &["tilt multiplying factor 2 of 13 is -0.95"]);
        let ldt_source = text("ldt_isym1_absolute.ldt");
        let (_, message) = ldt_error(&edit(&ldt_source, "\n100\n50\n0\n", "\n100\n-50\n0\n"));
        assert_contains(&message, &["bad.ldt:48:1", "γ = 90°", "-50, negative"]);
        let (_, message) = ldt_error(&edit(&ldt_source, "\n2.0\n", "\n-2.0\n"));
        assert_contains(&message, &["bad.ldt:24:1", "conversion factor", "-2"]);
        let (_, message) = ldt_error(&edit(&ldt_source, "\n1000\n", "\n0\n"));
        assert_contains(&message, &["bad.ldt:29:1", "field 26c", "is 0 lm"]);
    }

    #[test]
    fn refuses_a_missing_tilt_line_and_external_tilt_files() {
        let source = text(ISOTROPIC);
        let (e, message) = ies_error(&edit(&source, "TILT=NONE\n", ""));
        assert!(matches!(e, SceneError::Invalid { .. }));
        assert_contains(&message, &["bad.ies", "no TILT= line", "TILT=NONE"]);
        let (e, message) = ies_error(&edit(&source, "TILT=NONE", "TILT=aardvark.tlt"));
        assert_contains(&message, &["bad.ies:6:6", "TILT=aardvark.tlt", "inline", "TILT=INCLUDE"]);
        assert!(matches!(e, SceneError::Syntax { line: 6, .. }));
        let (_, message) = ies_error(&edit(&source, "TILT=NONE", "TILT="));
        assert_contains(&message, &["TILT= has no value"]);
        let (_, message) = ies_error(&edit(&text(SPEC), "TILT=INCLUDE\n1\n", "TILT=INCLUDE\n7\n"));
        assert_contains(&message, &["lamp-to-luminaire geometry '7'"]);
    }

    #[test]
    fn refuses_truncated_files() {
        let source = text(ASA);
        let cut = source.get(..source.len() / 2).unwrap_or("");
        let (_, message) = ies_error(cut);
        assert_contains(&message, &["expected 2701", "truncated", "73 horizontal × 37 vertical"]);
        let header_only = source.get(..source.find("TILT=NONE").unwrap_or(0) + 10).unwrap_or("");
        let (_, message) = ies_error(header_only);
        assert_contains(&message, &["ends before the number of lamps", "truncated"]);
        let (_, message) = ies_error(&edit(
            &text(ISOTROPIC),
            "0 15 30 45 60 75 90 105 120 135 150 165 180\n0\n1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000\n",
            "0 15 30\n",
        ));
        assert_contains(&message, &["ends before vertical angle 4 of 13"]);
        let ldt_source = text(PROLICHT);
        let (e, message) = ldt_error(&ldt_source.lines().take(20).collect::<Vec<_>>().join("\n"));
        assert_contains(
            &message,
            &["bad.ldt:20:", "before line 21", "C270 (field 21)", "truncated"],
        );
        assert!(matches!(e, SceneError::Syntax { line: 20, .. }));
        let (_, message) = ldt_error(&ldt_source.lines().take(500).collect::<Vec<_>>().join("\n"));
        assert_contains(&message, &["expected 740, found 401", "truncated"]);
        let (_, message) = ies_error("");
        assert_contains(&message, &["no TILT= line"]);
        let (_, message) = ldt_error("");
        assert_contains(&message, &["truncated"]);
    }

    #[test]
    fn refuses_unknown_and_unsupported_photometric_types() {
        let source = text(ISOTROPIC);
        let lamp_line = "1 -1 1 13 1 1 2 0 0 0";
        let (e, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 4 2 0 0 0"));
        assert_contains(&message, &["bad.ies:7:13", "photometric type '4' is unknown"]);
        assert!(matches!(e, SceneError::Syntax { line: 7, column: 13, .. }));
        let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 2 2 0 0 0"));
        assert_contains(&message, &["photometric type 2 (type B", "re-export the file as type C"]);
        let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 3 2 0 0 0"));
        assert_contains(&message, &["photometric type 3 (type A", "re-export the file as type C"]);
        let (_, message) =
            ldt_error(&edit(&text("ldt_isym4_quadrant.ldt"), "\n3\n4\n8\n", "\n3\n5\n8\n"));
        assert_contains(&message, &["bad.ldt:3:1", "symmetry indicator Isym", "is 5"]);
    }

    #[test]
    fn refuses_more_than_100000_angles() {
        let source = text(ISOTROPIC);
        let (e, message) =
            ies_error(&edit(&source, "1 -1 1 13 1 1 2 0 0 0", "1 -1 1 200000 1 1 2 0 0 0"));
        assert!(matches!(e, SceneError::Limit { value: 200_000, limit: 100_000, .. }), "{e:?}");
        assert_contains(
            &message,
            &["number of vertical angles (line 7:8) is 200000", "limit of 100000"],
        );
        let (e, _) =
            ies_error(&edit(&source, "1 -1 1 13 1 1 2 0 0 0", "1 -1 1 100000 100000 1 2 0 0 0"));
        assert!(matches!(e, SceneError::Limit { value: 10_000_000_000, .. }), "{e:?}");
        let (e, message) =
            ldt_error(&edit(&text("ldt_isym4_quadrant.ldt"), "\n4\n8\n45\n", "\n4\n800000\n45\n"));
        assert!(matches!(e, SceneError::Limit { value: 800_000, .. }), "{e:?}");
        assert_contains(&message, &["number of C-planes Mc"]);
    }

    #[test]
    fn refuses_text_where_a_number_belongs() {
        let (e, message) = ies_error(&edit(&text(ISOTROPIC), "\n1 1 0\n", "\n1 one 0\n"));
        assert_contains(&message, &["bad.ies:8:3", "'one'", "future use"]);
        assert!(matches!(e, SceneError::Syntax { line: 8, column: 3, .. }));
        let (_, message) = ldt_error(&edit(
            &text("ldt_isym4_quadrant.ldt"),
            "\n100\n100\n50\n",
            "\n100\nwide\n50\n",
        ));
        assert_contains(&message, &["bad.ldt:14:1", "width of luminaire (field 14) is 'wide'"]);
        let (_, message) =
            ldt_error(&edit(&text("ldt_isym3_c90_c270.ldt"), "\n3\n8\n45\n", "\n3\n6\n45\n"));
        assert_contains(&message, &["Mc (field 4) is 6", "divisible by 4"]);
    }

    #[test]
    fn accepts_decimal_commas_and_cr_line_ends_in_eulumdat() {
        let source =
            edit(&text("ldt_isym1_absolute.ldt"), "\n2.0\n", "\n2,0\n").replace('\n', "\r");
        let p = read_ldt(&source, Path::new("comma.ldt")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(p.photometry.intensity_at(0.0, 0.0), 200.0);
    }

    #[test]
    fn never_panics_on_truncated_or_mangled_input() {
        for name in [SPEC, ISOTROPIC, "bilateral_90_270.ies", "ldt_isym3_c90_c270.ldt"] {
            let source = text(name);
            for (end, _) in source.char_indices() {
                let prefix = source.get(..end).unwrap_or("");
                let _ = read_ies(prefix, Path::new("cut.ies"));
                let _ = read_ldt(prefix, Path::new("cut.ldt"));
            }
        }
        // Replace single characters with troublesome ones, deterministically.
        let source = text(SPEC);
        let replacements = ["", "-", "9e999", "0", "\n", "x", "é", ",", "180", "1e5", "NaN"];
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        for _ in 0..3000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let positions: Vec<usize> = source.char_indices().map(|(i, _)| i).collect();
            let at = positions.get((state % positions.len() as u64) as usize).copied().unwrap_or(0);
            let with = replacements.get((state >> 32) as usize % replacements.len()).unwrap_or(&"");
            let mut mangled = String::from(source.get(..at).unwrap_or(""));
            mangled.push_str(with);
            mangled.push_str(source.get(at + 1..).unwrap_or(""));
            if let Ok(file) = read_ies(&mangled, Path::new("mangled.ies")) {
                let p = file.photometry;
                let _ = (p.flux_lm(), p.peak_cd(), p.intensity_cd([0.3, -0.2, -1.0]));
            }
        }
        // A hand-built, inconsistent Photometry must not panic either.
        let odd = Photometry {
            gamma_deg: vec![0.0, 90.0, 45.0],
            c_deg: vec![10.0, 5.0, 400.0],
            candela: vec![vec![1.0], vec![]],
            description: String::new(),
        };
        for c in [-10.0, 0.0, 7.0, 200.0, 399.0] {
            for g in [0.0, 30.0, 60.0, 89.0] {
                let _ = odd.intensity_at(c, g);
            }
        }
        let _ = (odd.flux_lm(), odd.peak_cd());
        let empty = Photometry {
            gamma_deg: vec![],
            c_deg: vec![],
            candela: vec![],
            description: String::new(),
        };
        assert_eq!(
            (empty.flux_lm(), empty.peak_cd(), empty.intensity_at(0.0, 0.0)),
            (0.0, 0.0, 0.0)
        );
    }
}
