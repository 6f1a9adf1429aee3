//! The text both formats are written in: lines, numbers (a decimal comma allowed where
//! EULUMDAT is written under European locales), tokens with their line and column for
//! messages, and the symmetries that expand a measured quarter or half to the full circle.

use super::*;
use crate::{Result, SceneError};
use std::path::Path;

/// The lines of a file, with `\r\n`, `\n` and a lone `\r` all ending a line and a leading
/// byte-order mark dropped.
pub(super) fn split_lines(text: &str) -> Vec<&str> {
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
pub(super) struct Token<'a> {
    pub(super) text: &'a str,
    pub(super) line: usize,
    pub(super) column: usize,
}

/// The items of a file from a given line on, split at the format's separators.
#[derive(Clone, Copy)]
pub(super) struct Tokens<'a> {
    pub(super) lines: &'a [&'a str],
    /// Index of the current line.
    pub(super) line: usize,
    /// Byte offset and character column reached in the current line.
    pub(super) pos: usize,
    pub(super) col: usize,
    pub(super) separator: fn(char) -> bool,
}

impl<'a> Tokens<'a> {
    pub(super) fn new(
        lines: &'a [&'a str],
        first_line: usize,
        separator: fn(char) -> bool,
    ) -> Self {
        Tokens { lines, line: first_line, pos: 0, col: 0, separator }
    }

    pub(super) fn next_token(&mut self) -> Option<Token<'a>> {
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
    pub(super) fn next_token_position(&self) -> (usize, usize) {
        let mut probe = *self;
        probe.next_token().map_or_else(|| self.end(), |t| (t.line, t.column))
    }

    /// The position just after the last character of the file.
    pub(super) fn end(&self) -> (usize, usize) {
        match self.lines.last() {
            Some(last) => (self.lines.len(), last.chars().count() + 1),
            None => (1, 1),
        }
    }
}

/// IES separators: LM-63-2002 §3.0 accepts a comma, spaces and line breaks; a DOS end-of-file
/// character (0x1A) left by old editors is treated as space.
pub(super) fn ies_separator(c: char) -> bool {
    c.is_whitespace() || c == ',' || c == '\u{1a}'
}

/// EULUMDAT separators: white space only, since a comma may be a decimal comma.
pub(super) fn ldt_separator(c: char) -> bool {
    c.is_whitespace() || c == '\u{1a}'
}

pub(super) enum NumberProblem {
    NotANumber,
    NotFinite,
}

/// A number as written in a photometric file; with `decimal_comma`, one comma and no point is
/// read as a decimal comma.
pub(super) fn parse_number(
    text: &str,
    decimal_comma: bool,
) -> std::result::Result<f64, NumberProblem> {
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
pub(super) fn whole(v: f64) -> Option<u64> {
    (v >= 0.0 && v.fract() == 0.0 && v < u64::MAX as f64).then_some(v as u64)
}

/// Reads the numbers of a file in order, with positions for every message.
pub(super) struct Cursor<'a> {
    pub(super) path: &'a Path,
    pub(super) tokens: Tokens<'a>,
    pub(super) decimal_comma: bool,
}

impl<'a> Cursor<'a> {
    pub(super) fn error_at(&self, token: &Token, problem: impl Into<String>) -> SceneError {
        SceneError::syntax(self.path, token.line, token.column, problem)
    }

    pub(super) fn truncated(&self, what: &str) -> SceneError {
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

    pub(super) fn token(&mut self, what: &dyn Fn() -> String) -> Result<Token<'a>> {
        match self.tokens.next_token() {
            Some(t) => Ok(t),
            None => Err(self.truncated(&what())),
        }
    }

    pub(super) fn number(&mut self, what: &dyn Fn() -> String) -> Result<(f64, Token<'a>)> {
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
    pub(super) fn factor(&mut self, what: &str) -> Result<(f64, Token<'a>)> {
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
    pub(super) fn count(&mut self, what: &str, min: usize) -> Result<(usize, Token<'a>)> {
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
    pub(super) fn angles(&mut self, n: usize, what: &str, lo: f64, hi: f64) -> Result<Vec<f64>> {
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
    pub(super) fn table(
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
pub(super) fn check_table_size(
    path: &Path,
    planes: usize,
    per_plane: usize,
    what: &str,
) -> Result<()> {
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
pub(super) type Mirror = fn(f64) -> f64;

/// Mirror in the C0–C180 plane.
pub(super) fn mirror_0_180(c: f64) -> f64 {
    360.0 - c
}

/// Mirror in the C90–C270 plane.
pub(super) fn mirror_90_270(c: f64) -> f64 {
    180.0 - c
}

/// Both mirrors in turn: the diagonal image of quadrant symmetry.
pub(super) fn mirror_both(c: f64) -> f64 {
    180.0 + c
}

/// The full circle from the stored planes and their mirror images: every image normalised to
/// 0..360, sorted, and an angle met twice (a plane on a mirror) kept once.
pub(super) fn expand_planes(
    planes: Vec<(f64, Vec<f64>)>,
    mirrors: &[Mirror],
) -> (Vec<f64>, Vec<Vec<f64>>) {
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

pub(super) fn near(a: f64, b: f64) -> bool {
    (a - b).abs() <= ANGLE_TOLERANCE
}
