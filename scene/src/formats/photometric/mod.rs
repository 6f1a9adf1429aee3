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

mod eulumdat;
mod ies;
mod text;

pub use eulumdat::parse_ldt;
pub use ies::parse_ies;

#[cfg(test)]
mod tests;
