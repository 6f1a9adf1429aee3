//! EULUMDAT (`.ldt`): see the module above for the fields and how they become candela.

use super::text::*;
use super::*;
use crate::{Result, SceneError};
use std::path::Path;

/// The EULUMDAT header fields 1–26 by line, for messages.
pub(super) const LDT_FIELDS: [&str; 26] = [
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
pub(super) struct LdtFile {
    pub(super) photometry: Photometry,
    pub(super) isym: u64,
    /// Mc and Ng as declared (before symmetry expansion).
    pub(super) mc: usize,
    pub(super) ng: usize,
    /// Field 26a of the first lamp set (negative: absolute photometry).
    pub(super) lamps: i64,
    /// Field 26c of the first lamp set.
    pub(super) lamp_flux_lm: f64,
    pub(super) conversion_factor: f64,
    pub(super) dff_percent: f64,
    pub(super) lor_percent: f64,
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
pub(super) struct LdtLines<'a> {
    pub(super) path: &'a Path,
    pub(super) lines: &'a [&'a str],
}

impl<'a> LdtLines<'a> {
    /// Line `number` (1-based), which holds `what`.
    pub(super) fn text(&self, number: usize, what: &str) -> Result<&'a str> {
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

    pub(super) fn number(&self, number: usize, what: &str) -> Result<f64> {
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
    pub(super) fn whole(&self, number: usize, what: &str, lo: i64, hi: i64) -> Result<i64> {
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

    pub(super) fn count(&self, number: usize, what: &str, limit: usize) -> Result<usize> {
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

/// Field `n` (1-based) of [`LDT_FIELDS`], for messages.
fn field(n: usize) -> &'static str {
    n.checked_sub(1).and_then(|i| LDT_FIELDS.get(i)).copied().unwrap_or("a field")
}

/// The header fields 1–26 that the rest of the file is read with.
struct LdtHeader<'a> {
    company: &'a str,
    isym: u64,
    mc: usize,
    ng: usize,
    report: &'a str,
    name: &'a str,
    number: &'a str,
    date: &'a str,
    dff_percent: f64,
    lor_percent: f64,
    conversion_factor: f64,
    /// Field 26, checked to be at least 1.
    sets: usize,
}

/// Field 26a–26c of the first lamp set, and where the direct ratios start.
struct LdtLamps<'a> {
    lamps: f64,
    lamp_type: &'a str,
    lamp_flux_lm: f64,
    /// 1-based line of the first direct ratio (field 27).
    ratios_start: usize,
}

/// Which C-planes the file stores, by the symmetry, and the table size for messages.
struct LdtPlanes {
    /// Field 30: the C-planes Mc1..Mc2 that are stored (indices into the Mc C-angles).
    stored: Vec<usize>,
    counts: String,
}

/// Fields 1–26, one per line.
fn read_ldt_header<'a>(header: &LdtLines<'a>) -> Result<LdtHeader<'a>> {
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
            header.path,
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
            header.path,
            26,
            1,
            "the number of lamp sets (field 26) is 0, so there is no lamp flux to turn the cd/klm \
             table into candela; give at least one lamp set",
        ));
    }
    Ok(LdtHeader {
        company,
        isym,
        mc,
        ng,
        report,
        name,
        number,
        date,
        dff_percent,
        lor_percent,
        conversion_factor,
        sets,
    })
}

/// The lamp sets (fields 26a–26f) and the direct ratios (field 27).
fn read_lamp_sets<'a>(header: &LdtLines<'a>, sets: usize) -> Result<LdtLamps<'a>> {
    let path = header.path;
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
    Ok(LdtLamps { lamps, lamp_type, lamp_flux_lm, ratios_start })
}

/// Checks Mc and Ng against the symmetry and picks the stored C-planes.
fn check_planes(path: &Path, h: &LdtHeader) -> Result<LdtPlanes> {
    let (isym, mc, ng) = (h.isym, h.mc, h.ng);
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
    Ok(LdtPlanes { stored, counts })
}

/// The angles of the stored C-planes, checked against the range the symmetry stores;
/// `c_start` is where the C-angles begin, for the message.
fn stored_plane_angles(
    path: &Path,
    isym: u64,
    planes: &LdtPlanes,
    c_angles: &[f64],
    c_start: (usize, usize),
) -> Result<Vec<f64>> {
    let plane_angles: Vec<f64> = if isym == 1 {
        vec![0.0]
    } else {
        planes.stored.iter().map(|&i| c_angles.get(i).copied().unwrap_or(0.0)).collect()
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
    Ok(plane_angles)
}

pub(super) fn read_ldt(text: &str, path: &Path) -> Result<LdtFile> {
    let lines = split_lines(text);
    let header = LdtLines { path, lines: &lines };
    let h = read_ldt_header(&header)?;
    let lamp = read_lamp_sets(&header, h.sets)?;
    let planes = check_planes(path, &h)?;
    let (isym, mc, ng) = (h.isym, h.mc, h.ng);

    let data_start = lamp.ratios_start + 10; // 1-based line of the first C-angle
    let mut cursor = Cursor {
        path,
        tokens: Tokens::new(&lines, data_start - 1, ldt_separator),
        decimal_comma: true,
    };
    let c_start = cursor.tokens.next_token_position();
    let c_angles = cursor.angles(mc, "C-angle (field 28)", 0.0, 360.0)?;
    let gammas = cursor.angles(ng, "γ angle (field 29)", 0.0, 180.0)?;
    let plane_angles = stored_plane_angles(path, isym, &planes, &c_angles, c_start)?;

    let scale = h.conversion_factor * lamp.lamp_flux_lm / 1000.0;
    let table = cursor.table(&plane_angles, &gammas, scale, &planes.counts)?;
    let planes: Vec<(f64, Vec<f64>)> = plane_angles.into_iter().zip(table).collect();
    let mirrors: &[Mirror] = match isym {
        2 => &[mirror_0_180],
        3 => &[mirror_90_270],
        4 => &[mirror_0_180, mirror_90_270, mirror_both],
        _ => &[],
    };
    let (c_deg, candela) = expand_planes(planes, mirrors);
    let description = [h.company, h.name, h.number, h.report, h.date, lamp.lamp_type]
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
        lamps: lamp.lamps as i64,
        lamp_flux_lm: lamp.lamp_flux_lm,
        conversion_factor: h.conversion_factor,
        dff_percent: h.dff_percent,
        lor_percent: h.lor_percent,
    })
}
