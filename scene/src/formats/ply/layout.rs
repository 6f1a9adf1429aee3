//! The layout of a PLY file, checked before ply-rs reads it.
//!
//! Why: ply-rs (0.1) trusts its input. A header count that does not fit 64 bits panics in its
//! grammar (`parse().unwrap()`); an element without properties and a huge count loops for ever,
//! pushing empty elements; a negative binary list count becomes a huge `usize`; and its errors
//! are `Debug` dumps of its parser state (`ParseError { location: LineCol { … } }`) or bare I/O
//! words (`failed to fill whole buffer`) without the element they concern. So the header is
//! read here by ply-rs's own grammar (the PLY format of Turk's 1994 description, as ply-rs
//! accepts it), and the body is walked element by element, property by property, exactly as
//! ply-rs will read it — one line per element for ASCII, the declared sizes for binary — so
//! that anything it would refuse or choke on is refused here first, with the line or the byte
//! offset, the element and the fix.

use crate::error::{Result, SceneError};
use crate::limits::Limits;
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    Ascii,
    BigEndian,
    LittleEndian,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
    Char,
    UChar,
    Short,
    UShort,
    Int,
    UInt,
    Float,
    Double,
}

impl Scalar {
    /// ply-rs's names for the types, in its grammar's order.
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::Char,
            "uchar" | "uint8" => Scalar::UChar,
            "short" | "int16" => Scalar::Short,
            "ushort" | "uint16" => Scalar::UShort,
            "int" | "int32" => Scalar::Int,
            "uint" | "uint32" => Scalar::UInt,
            "float" | "float32" => Scalar::Float,
            "double" | "float64" => Scalar::Double,
            _ => return None,
        })
    }

    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::Char | Scalar::UChar => 1,
            Scalar::Short | Scalar::UShort => 2,
            Scalar::Int | Scalar::UInt | Scalar::Float => 4,
            Scalar::Double => 8,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::Char => "char (−128 to 127)",
            Scalar::UChar => "uchar (0 to 255)",
            Scalar::Short => "short (−32768 to 32767)",
            Scalar::UShort => "ushort (0 to 65535)",
            Scalar::Int => "int (32-bit)",
            Scalar::UInt => "uint (32-bit, not negative)",
            Scalar::Float => "float",
            Scalar::Double => "double",
        }
    }

    /// Whether an ASCII token reads as this type, as ply-rs reads it (Rust's `FromStr`).
    fn reads(self, token: &str) -> bool {
        match self {
            Scalar::Char => token.parse::<i8>().is_ok(),
            Scalar::UChar => token.parse::<u8>().is_ok(),
            Scalar::Short => token.parse::<i16>().is_ok(),
            Scalar::UShort => token.parse::<u16>().is_ok(),
            Scalar::Int => token.parse::<i32>().is_ok(),
            Scalar::UInt => token.parse::<u32>().is_ok(),
            Scalar::Float => token.parse::<f32>().is_ok(),
            Scalar::Double => token.parse::<f64>().is_ok(),
        }
    }

    /// A binary value of this type at the start of `b` (which holds at least its size), as a
    /// number.
    pub(crate) fn value(self, b: &[u8], big: bool) -> f64 {
        let mut raw = [0u8; 8];
        raw[..self.size()].copy_from_slice(&b[..self.size()]);
        if big {
            raw[..self.size()].reverse();
        }
        // Little-endian from here on.
        let [b0, b1, b2, b3, ..] = raw;
        match self {
            Scalar::Char => f64::from(b0 as i8),
            Scalar::UChar => f64::from(b0),
            Scalar::Short => f64::from(i16::from_le_bytes([b0, b1])),
            Scalar::UShort => f64::from(u16::from_le_bytes([b0, b1])),
            Scalar::Int => f64::from(i32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::UInt => f64::from(u32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::Float => f64::from(f32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::Double => f64::from_le_bytes(raw),
        }
    }

    /// The value that stands for full intensity in a colour of this type: the type's largest
    /// for whole numbers, 1 for floating point (as PLY writers use them).
    pub(crate) fn full_scale(self) -> f64 {
        match self {
            Scalar::Char => 127.0,
            Scalar::UChar => 255.0,
            Scalar::Short => 32767.0,
            Scalar::UShort => 65535.0,
            Scalar::Int => f64::from(i32::MAX),
            Scalar::UInt => f64::from(u32::MAX),
            Scalar::Float | Scalar::Double => 1.0,
        }
    }

    /// Whether the type holds whole numbers (a list of vertex indices must).
    pub(crate) fn is_integer(self) -> bool {
        !matches!(self, Scalar::Float | Scalar::Double)
    }

    /// A binary list count as ply-rs converts it (`as usize`), `None` when it is negative.
    pub(crate) fn count(self, b: &[u8], big: bool) -> Option<u64> {
        let two = |b: &[u8]| if big { [b[0], b[1]] } else { [b[1], b[0]] };
        let four = |b: &[u8]| if big { [b[0], b[1], b[2], b[3]] } else { [b[3], b[2], b[1], b[0]] };
        // Big-endian order of the bytes, whatever the file's.
        let v: i64 = match self {
            Scalar::Char => i64::from(b[0] as i8),
            Scalar::UChar => i64::from(b[0]),
            Scalar::Short => i64::from(i16::from_be_bytes(two(b))),
            Scalar::UShort => i64::from(u16::from_be_bytes(two(b))),
            Scalar::Int => i64::from(i32::from_be_bytes(four(b))),
            Scalar::UInt => i64::from(u32::from_be_bytes(four(b))),
            Scalar::Float | Scalar::Double => return None,
        };
        u64::try_from(v).ok()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Scalar(Scalar),
    /// The count's type and the items' type.
    List(Scalar, Scalar),
}

#[derive(Clone, Debug)]
pub(crate) struct Property {
    pub(crate) name: String,
    pub(crate) kind: Kind,
}

#[derive(Clone, Debug)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) count: u64,
    pub(crate) properties: Vec<Property>,
    /// The header line that declares it.
    line: usize,
}

impl Element {
    /// The index of the scalar property `name`, if the element has one.
    pub(crate) fn scalar(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
    }

    /// A vertex's colour: the indices of its three channels and their names (`red`, `green`,
    /// `blue`, or the older `diffuse_red`, … of the Stanford scans), and the value of full
    /// intensity in their type; `None` unless all three are there, of one type.
    pub(crate) fn colour(&self) -> Option<([usize; 3], [&'static str; 3], f64)> {
        const NAMES: [[&str; 3]; 2] =
            [["red", "green", "blue"], ["diffuse_red", "diffuse_green", "diffuse_blue"]];
        NAMES.into_iter().find_map(|names| {
            let [r, g, b] = names.map(|n| self.scalar(n));
            let at = [r?, g?, b?];
            let kinds = at.map(|i| self.properties[i].kind);
            let Kind::Scalar(kind) = kinds[0] else { return None };
            kinds.iter().all(|k| *k == kinds[0]).then_some((at, names, kind.full_scale()))
        })
    }

    /// The index of a face's list of vertex indices (of a whole-number type), if it has one.
    pub(crate) fn face_list(&self) -> Option<usize> {
        self.properties.iter().position(|p| {
            is_face_list(self, p) && matches!(p.kind, Kind::List(_, item) if item.is_integer())
        })
    }
}

/// What the header says.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<Element>,
    /// The byte offset of the body, and the number of header lines before it.
    pub(crate) body: usize,
    lines: usize,
}

/// The lines of `bytes` from `start` as ply-rs's `read_line` takes them: each up to and
/// including its `\n` (the last one may lack it), with the offset where it starts.
fn lines_from(bytes: &[u8], start: usize) -> impl Iterator<Item = (usize, &[u8])> {
    let mut at = start;
    std::iter::from_fn(move || {
        if at >= bytes.len() {
            return None;
        }
        let end = bytes[at..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |i| at + i + 1);
        let line = (at, &bytes[at..end]);
        at = end;
        Some(line)
    })
}

/// A line without its line break (`\r\n`, `\n` or `\r`, one of them, as ply-rs's grammar
/// allows).
fn content(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r\n")
        .or_else(|| line.strip_suffix(b"\n"))
        .or_else(|| line.strip_suffix(b"\r"))
        .unwrap_or(line)
}

fn is_space(b: u8) -> bool {
    b == b' ' || b == b'\t'
}

/// ply-rs's `ident`: a letter or `_`, then letters, digits, `_` or `-`.
fn is_ident(word: &str) -> bool {
    let mut chars = word.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// ply-rs's `uint` (digits only), as a count that fits 64 bits.
fn uint(word: &str) -> Option<u64> {
    if word.is_empty() || !word.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    word.parse().ok()
}

/// One header line after the first, split into its words, for the readers of each keyword.
struct HeaderLine<'a> {
    path: &'a Path,
    /// 1-based line number.
    number: usize,
    text: &'a str,
    words: Vec<&'a str>,
}

impl HeaderLine<'_> {
    fn error(&self, problem: String) -> SceneError {
        SceneError::syntax(self.path, self.number, 1, problem)
    }
}

/// What the header has declared so far.
#[derive(Default)]
struct HeaderSoFar {
    encoding: Option<Encoding>,
    elements: Vec<Element>,
}

/// A header line's text, which must be UTF-8.
fn header_text<'a>(path: &Path, number: usize, raw: &'a [u8]) -> Result<&'a str> {
    std::str::from_utf8(content(raw)).map_err(|_| {
        SceneError::syntax(
            path,
            number,
            1,
            "the header line is not text (not UTF-8); a PLY file starts with a text header \
             (`ply`, `format …`, `element …`, `property …`, `end_header`)",
        )
    })
}

/// The first line, which must be `ply`.
fn check_magic(path: &Path, text: &str) -> Result<()> {
    if text.trim_end_matches([' ', '\t']) != "ply" {
        return Err(SceneError::syntax(
            path,
            1,
            1,
            "the file does not start with the line `ply`; it is not a PLY file",
        ));
    }
    Ok(())
}

/// A later line: no carriage return inside, no leading space, then its words.
fn header_line<'a>(path: &'a Path, number: usize, text: &'a str) -> Result<HeaderLine<'a>> {
    let at_line = |problem: &str| SceneError::syntax(path, number, 1, problem);
    if text.contains('\r') {
        return Err(at_line(
            "a carriage return inside a header line; end header lines with a line break",
        ));
    }
    if text.starts_with([' ', '\t']) {
        return Err(at_line("a header line may not start with a space; remove it"));
    }
    let words: Vec<&str> = text.split([' ', '\t']).filter(|w| !w.is_empty()).collect();
    Ok(HeaderLine { path, number, text, words })
}

/// `format <encoding> <version>`.
fn read_format(line: &HeaderLine, so_far: &mut HeaderSoFar) -> Result<()> {
    let words = &line.words;
    let e = match words.get(1).copied() {
        Some("ascii") => Encoding::Ascii,
        Some("binary_big_endian") => Encoding::BigEndian,
        Some("binary_little_endian") => Encoding::LittleEndian,
        _ => {
            return Err(line.error(
                "the format must be `ascii`, `binary_little_endian` or \
                 `binary_big_endian`"
                    .into(),
            ));
        }
    };
    let version_ok = words.len() == 3
        && words[2].split_once('.').is_some_and(|(a, b)| {
            uint(a).is_some_and(|a| a <= u64::from(u16::MAX))
                && uint(b).is_some_and(|b| b <= u64::from(u8::MAX))
        });
    if !version_ok {
        return Err(line.error(
            "the format line ends with a version like 1.0; write `format <encoding> 1.0`".into(),
        ));
    }
    if so_far.encoding.is_some_and(|previous| previous != e) {
        return Err(line.error("a second `format` line contradicts the first; keep one".into()));
    }
    so_far.encoding = Some(e);
    Ok(())
}

/// `element <name> <count>`.
fn read_element(line: &HeaderLine, so_far: &mut HeaderSoFar) -> Result<()> {
    let words = &line.words;
    let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
        return Err(line.error("write an element as `element <name> <count>`".into()));
    };
    if !is_ident(name) {
        return Err(
            line.error(format!("`{name}` is not an element name (letters, digits, _ and -)"))
        );
    }
    let Some(count) = uint(count) else {
        return Err(line.error(format!(
            "the count `{count}` of element `{name}` is not a whole number below 2^64"
        )));
    };
    if so_far.elements.iter().any(|e| e.name == *name) {
        return Err(line.error(format!("element `{name}` is declared twice; keep one")));
    }
    so_far.elements.push(Element {
        name: (*name).to_owned(),
        count,
        properties: Vec::new(),
        line: line.number,
    });
    Ok(())
}

/// The type of a `property` line: a scalar or a list.
fn property_kind(line: &HeaderLine) -> Result<Kind> {
    let words = &line.words;
    Ok(match words.get(1).copied() {
        Some("list") if words.len() == 5 => {
            match (Scalar::parse(words[2]), Scalar::parse(words[3])) {
                (Some(Scalar::Float | Scalar::Double), _) => {
                    return Err(line.error(format!(
                        "the count of list `{}` is a {}; a list count is an integer type (uchar, ushort, uint, …)",
                        words[4], words[2]
                    )));
                }
                (Some(c), Some(t)) => Kind::List(c, t),
                _ => return Err(line.error("a list property is `property list <count type> <item type> <name>`, with types like uchar, int or float".into())),
            }
        }
        Some(t) if words.len() == 3 => match Scalar::parse(t) {
            Some(s) => Kind::Scalar(s),
            None => return Err(line.error(format!("`{t}` is not a PLY type; use char, uchar, short, ushort, int, uint, float or double"))),
        },
        _ => return Err(line.error("write a property as `property <type> <name>` or `property list <count type> <item type> <name>`".into())),
    })
}

/// `property <type> <name>` or `property list <count type> <item type> <name>`, of the last
/// element.
fn read_property(line: &HeaderLine, so_far: &mut HeaderSoFar) -> Result<()> {
    let kind = property_kind(line)?;
    let name = line.words.last().copied().unwrap_or("");
    if !is_ident(name) {
        return Err(
            line.error(format!("`{name}` is not a property name (letters, digits, _ and -)"))
        );
    }
    let Some(element) = so_far.elements.last_mut() else {
        return Err(line.error(format!(
            "property `{name}` comes before any `element` line; declare the element first"
        )));
    };
    if element.properties.iter().any(|p| p.name == name) {
        return Err(line.error(format!(
            "property `{name}` of element `{}` is declared twice; keep one",
            element.name
        )));
    }
    element.properties.push(Property { name: name.to_owned(), kind });
    Ok(())
}

/// `end_header`: the header is complete if it had a `format` line.
fn end_header(line: &HeaderLine, so_far: HeaderSoFar, body: usize) -> Result<Header> {
    let Some(encoding) = so_far.encoding else {
        return Err(line.error(
            "the header has no `format` line; add `format ascii 1.0` or \
             `format binary_little_endian 1.0` after `ply`"
                .into(),
        ));
    };
    Ok(Header { encoding, elements: so_far.elements, body, lines: line.number })
}

/// A line of no keyword ply-rs knows.
fn unknown_line(line: &HeaderLine) -> SceneError {
    let shown: String = line.text.chars().take(40).collect();
    line.error(format!(
        "`{shown}` is not a PLY header line (`format`, `comment`, `obj_info`, \
         `element`, `property` or `end_header`)"
    ))
}

/// Read the header by ply-rs's grammar; anything it would refuse (or panic on) is refused
/// with its line.
pub(crate) fn read_header(bytes: &[u8], path: &Path) -> Result<Header> {
    let mut so_far = HeaderSoFar::default();
    let mut number = 0;
    for (at, raw) in lines_from(bytes, 0) {
        number += 1;
        let text = header_text(path, number, raw)?;
        // A last line cut short is a truncated file, whatever its words.
        if !raw.ends_with(b"\n") && !text.starts_with("end_header") {
            break;
        }
        if number == 1 {
            check_magic(path, text)?;
            continue;
        }
        let line = header_line(path, number, text)?;
        let first = line.words.first().copied().unwrap_or("");
        match first {
            "comment" | "obj_info"
                if text.len() == first.len() || is_space(text.as_bytes()[first.len()]) => {}
            "end_header" if line.words.len() == 1 => {
                return end_header(&line, so_far, at + raw.len());
            }
            "format" => read_format(&line, &mut so_far)?,
            "element" => read_element(&line, &mut so_far)?,
            "property" => read_property(&line, &mut so_far)?,
            "ply" => {
                return Err(line.error("a second `ply` line inside the header; remove it".into()));
            }
            _ => return Err(unknown_line(&line)),
        }
    }
    Err(SceneError::invalid(
        path,
        "header",
        if number == 0 {
            "the file is empty; a PLY file starts with the line `ply`".to_owned()
        } else {
            format!(
                "the header ends (after {number} lines) without an `end_header` line; the file \
                 is truncated or not PLY"
            )
        },
    ))
}

/// Whether an ASCII token is a number of ply-rs's grammar: `[-+]?digits(.digits)?(e[-+]?digits)?`.
fn is_number(token: &str) -> bool {
    let b = token.as_bytes();
    let mut i = 0;
    let digits = |i: &mut usize| {
        let start = *i;
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
        *i > start
    };
    if i < b.len() && (b[i] == b'-' || b[i] == b'+') {
        i += 1;
    }
    if !digits(&mut i) {
        return false;
    }
    if i < b.len() && b[i] == b'.' {
        i += 1;
        if !digits(&mut i) {
            return false;
        }
    }
    if i < b.len() && b[i] == b'e' {
        i += 1;
        if i < b.len() && (b[i] == b'-' || b[i] == b'+') {
            i += 1;
        }
        if !digits(&mut i) {
            return false;
        }
    }
    i == b.len()
}

/// Whether `element`'s `property` is the face list restauro triangulates.
pub(crate) fn is_face_list(element: &Element, property: &Property) -> bool {
    element.name == "face" && (property.name == "vertex_indices" || property.name == "vertex_index")
}

/// Check the header's counts and the body against each other and against `limits`, reading
/// the body exactly as ply-rs will.
pub(crate) fn check_body(
    header: &Header,
    bytes: &[u8],
    path: &Path,
    limits: &Limits,
) -> Result<()> {
    for e in &header.elements {
        if e.properties.is_empty() && e.count > 0 {
            return Err(SceneError::syntax(
                path,
                e.line,
                1,
                format!(
                    "element `{}` has no properties but a count of {}; declare its properties \
                     or remove it",
                    e.name, e.count
                ),
            ));
        }
        if e.name == "face" && e.count > limits.max_triangles {
            return Err(SceneError::Limit {
                path: path.to_owned(),
                what: format!("the number of faces (header line {})", e.line),
                value: e.count,
                limit: limits.max_triangles,
                fix: "simplify the mesh, or raise the limit with --max-triangles".into(),
            });
        }
    }
    match header.encoding {
        Encoding::Ascii => check_ascii(header, bytes, path, limits),
        Encoding::BigEndian => check_binary(header, bytes, path, limits, true),
        Encoding::LittleEndian => check_binary(header, bytes, path, limits, false),
    }
}

fn polygon_limit(path: &Path, place: String, count: u64, limits: &Limits) -> Result<()> {
    if count > limits.max_polygon_vertices {
        return Err(SceneError::Limit {
            path: path.to_owned(),
            what: format!("the number of vertices of {place}"),
            value: count,
            limit: limits.max_polygon_vertices,
            fix: "split the polygon into smaller faces, or raise the limit with \
                  --max-polygon-vertices"
                .into(),
        });
    }
    Ok(())
}

fn check_ascii(header: &Header, bytes: &[u8], path: &Path, limits: &Limits) -> Result<()> {
    let mut lines = lines_from(bytes, header.body);
    let mut number = header.lines;
    for e in &header.elements {
        for k in 0..e.count {
            number += 1;
            let place = format!("element `{}` {k}", e.name);
            let Some((_, raw)) = lines.next() else {
                return Err(SceneError::invalid(
                    path,
                    format!("line {number} ({place})"),
                    format!(
                        "the file ends here, but the header declares {} `{}` elements; the file \
                         is truncated or the header's count is wrong",
                        e.count, e.name
                    ),
                ));
            };
            let at = |problem: String| {
                SceneError::invalid(path, format!("line {number} ({place})"), problem)
            };
            let text = content(raw);
            let mut tokens = Vec::new();
            for token in text.split(|&b| is_space(b)).filter(|t| !t.is_empty()) {
                match std::str::from_utf8(token) {
                    Ok(t) if is_number(t) => tokens.push(t),
                    _ => {
                        let shown: String =
                            String::from_utf8_lossy(token).chars().take(30).collect();
                        return Err(at(format!(
                            "`{shown}` is not a number as PLY writes them (digits, an optional \
                             sign, decimals and a lower-case e exponent, e.g. -1.5e-3); fix the \
                             value"
                        )));
                    }
                }
            }
            let mut next = tokens.into_iter();
            for p in &e.properties {
                let missing = || {
                    at(format!(
                        "the line ends before property `{}`; each `{}` line holds every property \
                         the header declares, in order",
                        p.name, e.name
                    ))
                };
                let bad = |t: &str, s: Scalar| {
                    at(format!("`{t}` is not a valid {} for property `{}`", s.name(), p.name))
                };
                match p.kind {
                    Kind::Scalar(s) => {
                        let t = next.next().ok_or_else(missing)?;
                        if !s.reads(t) {
                            return Err(bad(t, s));
                        }
                    }
                    Kind::List(c, s) => {
                        let t = next.next().ok_or_else(missing)?;
                        // ply-rs reads every list count as a `usize`, whatever its type.
                        let Ok(n) = t.parse::<u64>() else {
                            return Err(at(format!(
                                "the list count `{t}` of property `{}` is not a whole number ≥ 0",
                                p.name
                            )));
                        };
                        if !c.reads(t) {
                            return Err(bad(t, c));
                        }
                        if is_face_list(e, p) {
                            polygon_limit(path, format!("face {k} (line {number})"), n, limits)?;
                        }
                        for i in 0..n {
                            let Some(t) = next.next() else {
                                return Err(at(format!(
                                    "property `{}` lists {n} values but the line ends after {i}",
                                    p.name
                                )));
                            };
                            if !s.reads(t) {
                                return Err(bad(t, s));
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

fn check_binary(
    header: &Header,
    bytes: &[u8],
    path: &Path,
    limits: &Limits,
    big: bool,
) -> Result<()> {
    let mut at = header.body;
    for e in &header.elements {
        // Every element takes at least one byte (none without properties is left), so a count
        // beyond the bytes left is refused at once rather than walked.
        let left = (bytes.len() - at) as u64;
        if e.count > left {
            return Err(SceneError::invalid(
                path,
                format!("element `{}` (header line {})", e.name, e.line),
                format!(
                    "the header declares {} elements but only {left} bytes follow; the count is \
                     wrong or the file is truncated",
                    e.count
                ),
            ));
        }
        for k in 0..e.count {
            for p in &e.properties {
                let start = at;
                let place =
                    || format!("byte {start} (element `{}` {k}, property `{}`)", e.name, p.name);
                let ends = || {
                    SceneError::invalid(
                        path,
                        place(),
                        format!(
                            "the file ends inside element `{}` {k} of {}; it is truncated or the \
                             header's counts or types are wrong",
                            e.name, e.count
                        ),
                    )
                };
                let next = match p.kind {
                    Kind::Scalar(s) => start.checked_add(s.size()),
                    Kind::List(c, s) => {
                        let count_bytes = bytes.get(start..start + c.size()).ok_or_else(ends)?;
                        let Some(n) = c.count(count_bytes, big) else {
                            return Err(SceneError::invalid(
                                path,
                                place(),
                                "the list count is negative; the file is damaged or its header's \
                                 types are wrong",
                            ));
                        };
                        if is_face_list(e, p) {
                            polygon_limit(path, format!("face {k} (byte {start})"), n, limits)?;
                        }
                        n.checked_mul(s.size() as u64)
                            .and_then(|size| usize::try_from(size).ok())
                            .and_then(|size| (start + c.size()).checked_add(size))
                    }
                };
                at = next.filter(|&end| end <= bytes.len()).ok_or_else(ends)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_follow_the_ply_rs_grammar() {
        for ok in ["0", "-1", "+2", "1.5", "1e5", "-1.25e-3"] {
            assert!(is_number(ok), "{ok}");
        }
        for bad in ["", "1.", ".5", "1E5", "nan", "inf", "1e", "--1", "1-2", "0x10"] {
            assert!(!is_number(bad), "{bad}");
        }
    }
}
