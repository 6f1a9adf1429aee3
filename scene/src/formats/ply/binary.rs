//! Binary PLY bodies decoded straight into the columns a mesh needs, one pass over the bytes
//! and no allocation per element: a scan of millions of triangles reads in seconds and in
//! little more memory than its mesh. The body's layout has been checked before (by
//! [`crate::formats::ply::layout::check_body`]: every element and list fits in the file); a byte the
//! checks missed reads as the end of the body, never as a panic.

use crate::formats::ply::Columns;
use crate::formats::ply::layout::{Encoding, Header, Kind, Scalar};

/// Where an element's wanted values sit among its properties.
#[derive(Default)]
struct Wanted {
    /// Property indices of x, y, z and of nx, ny, nz.
    position: [Option<usize>; 3],
    normal: [Option<usize>; 3],
    /// Property indices of red, green, blue, and their full scale.
    colour: Option<([usize; 3], f64)>,
    /// The property index of the face's vertex list.
    list: Option<usize>,
}

fn wanted(e: &crate::formats::ply::layout::Element) -> Wanted {
    let mut w = Wanted::default();
    if e.name == "vertex" {
        w.position = ["x", "y", "z"].map(|k| e.scalar(k));
        w.normal = ["nx", "ny", "nz"].map(|k| e.scalar(k));
        w.colour = e.colour().map(|(at, _, full)| (at, full));
    }
    if e.name == "face" {
        w.list = e.face_list();
    }
    w
}

/// The columns of a binary body (either byte order).
pub(crate) fn decode(header: &Header, bytes: &[u8]) -> Columns {
    let big = header.encoding == Encoding::BigEndian;
    let mut c = Columns { starts: vec![0], ..Columns::default() };
    let mut normals = Vec::new();
    let mut colours = Vec::new();
    let mut at = header.body;
    let mut values: Vec<f64> = Vec::new();
    'body: for e in &header.elements {
        let w = wanted(e);
        let keep_normals = w.normal.iter().all(Option::is_some);
        values.resize(e.properties.len(), 0.0);
        for _ in 0..e.count {
            for (i, p) in e.properties.iter().enumerate() {
                match p.kind {
                    Kind::Scalar(s) => {
                        let Some(b) = bytes.get(at..at + s.size()) else { break 'body };
                        values[i] = s.value(b, big);
                        at += s.size();
                    }
                    Kind::List(count, item) => {
                        let Some(n) =
                            bytes.get(at..at + count.size()).and_then(|b| count.count(b, big))
                        else {
                            break 'body;
                        };
                        at += count.size();
                        let Some(end) = (n as usize).checked_mul(item.size()).map(|s| at + s)
                        else {
                            break 'body;
                        };
                        let Some(items) = bytes.get(at..end) else { break 'body };
                        if w.list == Some(i) {
                            let whole = |b: &[u8]| index_value(item, b, big);
                            c.indices.extend(items.chunks_exact(item.size()).map(whole));
                        }
                        at = end;
                    }
                }
            }
            if let [Some(x), Some(y), Some(z)] = w.position {
                c.positions.push([values[x], values[y], values[z]]);
                if let ([Some(a), Some(b), Some(d)], true) = (w.normal, keep_normals) {
                    normals.push([values[a], values[b], values[d]]);
                }
                if let Some(([r, g, b], full)) = w.colour {
                    colours.push([values[r] / full, values[g] / full, values[b] / full]);
                }
            }
            if w.list.is_some() {
                c.starts.push(c.indices.len());
            }
        }
    }
    if !normals.is_empty() && normals.len() == c.positions.len() {
        c.normals = Some(normals);
    }
    if !colours.is_empty() && colours.len() == c.positions.len() {
        c.colours = Some(colours);
    }
    c
}

/// A list item as a whole number (vertex lists hold integer types only).
fn index_value(item: Scalar, b: &[u8], big: bool) -> i64 {
    item.value(b, big) as i64
}
