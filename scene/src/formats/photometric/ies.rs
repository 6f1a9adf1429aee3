//! IES LM-63 (1986, 1991, 1995, 2002; 2019 read like 2002): see the module above for what is
//! read and why.

use super::text::*;
use super::*;
use crate::{Result, SceneError};
use std::path::Path;

/// Which LM-63 edition a file says it follows; it decides what the second field after the
/// lamp line means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum IesVersion {
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
    pub(super) fn has_ballast_lamp_factor(self) -> bool {
        matches!(self, IesVersion::Lm1986 | IesVersion::Lm1991 | IesVersion::Lm1995)
    }
}

/// The `TILT=INCLUDE` block: lamp-to-luminaire geometry, tilt angles and multiplying factors.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(not(test), allow(dead_code))] // the fields other than `factor` are read by the tests
pub(super) struct Tilt {
    pub(super) geometry: u64,
    pub(super) angles: Vec<f64>,
    pub(super) factors: Vec<f64>,
    /// The factor at a tilt of 0° (the luminaire as measured), applied to every value.
    pub(super) factor: f64,
}

/// What [`parse_ies`] reads, beyond the [`Photometry`], for the tests to check.
#[derive(Clone, Debug)]
#[cfg_attr(not(test), allow(dead_code))] // read by the tests
pub(super) struct IesFile {
    pub(super) photometry: Photometry,
    pub(super) version: IesVersion,
    pub(super) tilt: Option<Tilt>,
    pub(super) lamps: f64,
    /// −1 for absolute photometry.
    pub(super) lumens_per_lamp: f64,
    /// The product of every multiplier applied to the file's numbers.
    pub(super) scale: f64,
}

/// Parse IES LM-63 (1986/1991/1995/2002 — `IESNA:LM-63-1995`, `IESNA:LM-63-2002`, and files with no IESNA line), TILT=NONE, `TILT=INCLUDE` (the tilt block inline) and `TILT=<file>` (refuse: say the tilt file must be included inline); photometric type 1 (C) read; type 2 (B) and type 3 (A): convert B to C if you can do it correctly, else refuse with a clear message naming the type and suggesting re-export as type C — your choice, document it.
///
/// Types B and A are refused (see the module documentation for why).
pub fn parse_ies(text: &str, path: &std::path::Path) -> crate::Result<Photometry> {
    read_ies(text, path).map(|file| file.photometry)
}

pub(super) fn ies_version(first_line: &str) -> IesVersion {
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
pub(super) fn is_version_line(line: &str) -> bool {
    let t = line.trim_start().to_ascii_uppercase();
    t.starts_with("IESNA") || t.starts_with("IES:LM-63")
}

/// The value of a `TILT=` line, if `line` is one.
pub(super) fn tilt_value(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let head = t.get(..4)?;
    if !head.eq_ignore_ascii_case("TILT") {
        return None;
    }
    let rest = t.get(4..)?.trim_start();
    rest.strip_prefix('=').map(str::trim)
}

/// `[KEY] value` of a keyword line (LM-63-1995 and later).
pub(super) fn keyword(line: &str) -> Option<(String, &str)> {
    let rest = line.trim().strip_prefix('[')?;
    let end = rest.find(']')?;
    Some((rest.get(..end)?.trim().to_ascii_uppercase(), rest.get(end + 1..)?.trim()))
}

/// Manufacturer, catalogue, luminaire and lamp keywords (with their `[MORE]` continuations), or
/// every label line of a file without keywords (LM-63-1986).
pub(super) fn ies_description(header: &[&str]) -> String {
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
pub(super) enum Lateral {
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

pub(super) fn ies_lateral(horizontal: &[f64]) -> Option<Lateral> {
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

/// Where the label lines end and the `TILT=` line is.
struct IesLabels<'a> {
    /// The label or keyword lines between the version line and the `TILT=` line.
    header: &'a [&'a str],
    /// Index of the `TILT=` line.
    tilt_index: usize,
}

/// The lamp line and the ballast line, as far as they matter for the candela.
struct IesLamp {
    lamps: f64,
    lumens_per_lamp: f64,
    multiplier: f64,
    n_vertical: usize,
    n_horizontal: usize,
    /// Line of the number of vertical angles, for messages.
    vertical_line: usize,
    ballast: f64,
    lamp_factor: f64,
}

/// The angles of a type C web and the symmetry they give.
struct IesAngles {
    vertical: Vec<f64>,
    horizontal: Vec<f64>,
    lateral: Lateral,
    counts: String,
}

/// The label or keyword lines, up to the `TILT=` line that ends them.
fn read_labels<'a>(lines: &'a [&'a str], path: &Path) -> Result<IesLabels<'a>> {
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
    Ok(IesLabels { header, tilt_index })
}

/// The `TILT=` line's value, and the tilt block after it for `TILT=INCLUDE`.
fn read_tilt_line(cursor: &mut Cursor, lines: &[&str], tilt_index: usize) -> Result<Option<Tilt>> {
    let path = cursor.path;
    let tilt_line = lines.get(tilt_index).copied().unwrap_or("");
    let tilt_text = tilt_value(tilt_line).unwrap_or("");
    let tilt_column =
        tilt_line.find('=').map_or(1, |i| tilt_line.get(..i).map_or(1, |s| s.chars().count() + 2));

    if tilt_text.eq_ignore_ascii_case("NONE") {
        Ok(None)
    } else if tilt_text.eq_ignore_ascii_case("INCLUDE") {
        Ok(Some(read_tilt(cursor)?))
    } else if tilt_text.is_empty() {
        Err(SceneError::syntax(
            path,
            tilt_index + 1,
            tilt_column,
            "TILT= has no value; write TILT=NONE (or TILT=INCLUDE followed by the tilt table)",
        ))
    } else {
        Err(SceneError::syntax(
            path,
            tilt_index + 1,
            tilt_column,
            format!(
                "TILT={tilt_text} refers to a separate tilt file, which restauro does not read; \
                 include the tilt data inline (TILT=INCLUDE followed by the lamp-to-luminaire \
                 geometry, the number of pairs, the angles and the factors), or write TILT=NONE \
                 if the lamp output does not depend on tilt"
            ),
        ))
    }
}

/// The photometric type: type C (1) is read, B (2) and A (3) are refused.
fn check_photometric_type(
    cursor: &Cursor,
    photometric_type: f64,
    type_token: &Token,
) -> Result<()> {
    match whole(photometric_type) {
        Some(1) => Ok(()),
        Some(t @ (2 | 3)) => {
            let name = if t == 2 { "B" } else { "A" };
            Err(cursor.error_at(
                type_token,
                format!(
                    "photometric type {t} (type {name} photometry) is not supported: restauro \
                     reads type C webs (photometric type 1) only; re-export the file as type C \
                     photometry"
                ),
            ))
        }
        _ => Err(cursor.error_at(
            type_token,
            format!(
                "photometric type '{}' is unknown; LM-63 defines 1 (type C), 2 (type B) and 3 \
                 (type A) — check the field order of this line",
                type_token.text
            ),
        )),
    }
}

/// The lamp line and the ballast line after the tilt.
fn read_lamp_lines(cursor: &mut Cursor, version: IesVersion) -> Result<IesLamp> {
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
    check_photometric_type(cursor, photometric_type, &type_token)?;
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
    Ok(IesLamp {
        lamps,
        lumens_per_lamp,
        multiplier,
        n_vertical,
        n_horizontal,
        vertical_line: vertical_token.line,
        ballast,
        lamp_factor,
    })
}

/// The vertical and horizontal angles, and the lateral symmetry the horizontal ones give.
fn read_ies_angles(cursor: &mut Cursor, lamp: &IesLamp) -> Result<IesAngles> {
    let path = cursor.path;
    let (n_vertical, n_horizontal) = (lamp.n_vertical, lamp.n_horizontal);
    let counts = format!(
        "{n_horizontal} horizontal × {n_vertical} vertical angles, line {}",
        lamp.vertical_line
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
    Ok(IesAngles { vertical, horizontal, lateral, counts })
}

pub(super) fn read_ies(text: &str, path: &Path) -> Result<IesFile> {
    let lines = split_lines(text);
    let version = lines.first().map_or(IesVersion::Lm1986, |l| ies_version(l));
    let labels = read_labels(&lines, path)?;

    let mut cursor = Cursor {
        path,
        tokens: Tokens::new(&lines, labels.tilt_index + 1, ies_separator),
        decimal_comma: false,
    };

    let tilt = read_tilt_line(&mut cursor, &lines, labels.tilt_index)?;
    let lamp = read_lamp_lines(&mut cursor, version)?;
    let IesAngles { vertical, horizontal, lateral, counts } = read_ies_angles(&mut cursor, &lamp)?;
    let tilt_factor = tilt.as_ref().map_or(1.0, |t| t.factor);
    let scale = lamp.multiplier * lamp.ballast * lamp.lamp_factor * tilt_factor;
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
            description: ies_description(labels.header),
        },
        version,
        tilt,
        lamps: lamp.lamps,
        lumens_per_lamp: lamp.lumens_per_lamp,
        scale,
    })
}

/// The `TILT=INCLUDE` block (LM-63-2002, TILT): geometry 1–3, the number of pairs, the angles
/// (increasing) and the multiplying factors (non-negative).
pub(super) fn read_tilt(cursor: &mut Cursor) -> Result<Tilt> {
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
pub(super) fn interpolate_table(xs: &[f64], ys: &[f64], x: f64) -> f64 {
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
