//! A VRML97 (ISO/IEC 14772-1:1997) importer: the static geometry of a `.wrl` world as one
//! triangle [`Mesh`], plus its `Viewpoint`s and notes on what it holds but does not draw.
//!
//! Why hand-written: restauro needs only the geometric core of VRML97, but needs it to never
//! panic, never recurse or allocate without bound, and to say exactly where a broken file is
//! broken.
//!
//! What is read (section numbers of ISO/IEC 14772-1:1997):
//! - the header `#VRML V2.0 utf8` (§5.2.1); VRML 1.0 and anything else is refused;
//! - the lexical rules of §5.1 and §5.5: `#` comments, commas as whitespace, strings with
//!   `\"` and `\\` escapes, decimal and `0x` hexadecimal numbers;
//! - `DEF`/`USE` (§4.6.2): a `USE` re-instantiates the node under the transforms of the place it
//!   is used; a name can be used only after its `DEF`;
//! - `PROTO` (§4.8): an instance is its body's first node, with each `IS` field given the
//!   instance's value or the declared default; the body's other nodes are read but not drawn
//!   (§4.8.3). Prototypes may use prototypes declared before them, and a PROTO declared in a
//!   body is known only inside it; `DEF` names in a body are its own, copied per instance. A
//!   prototype that contains itself, directly or through others, is refused;
//! - `EXTERNPROTO` (§4.9): resolved only when one of its urls is `"#Name"`, a PROTO of this
//!   file declared before the instance; other files are not read for PROTOs, so any other is noted and
//!   its instances are not drawn;
//! - `Transform` (§6.52), `Group` (§6.21), and, as plain groups, `Anchor` (§6.2), `Billboard`
//!   (§6.6, its screen alignment is ignored) and `Collision` (§6.8); `Switch` (§6.46) descends
//!   into `choice[whichChoice]`; `LOD` (§6.26) keeps every `level`, and each render shows
//!   the one its camera calls for (`crate::lod`);
//! - `Shape` (§6.41) with `Appearance { material Material { diffuseColor } }` (§6.3, §6.27)
//!   and as geometry: `IndexedFaceSet` (§6.23) with `Coordinate` (§6.12), `coordIndex`, `ccw`,
//!   `solid`, `convex` and `creaseAngle` (its `normal`, `color` and `texCoord` are not read:
//!   normals are always computed from `creaseAngle`, so every shape has them); `Box` (§6.7),
//!   `Cone` (§6.11), `Cylinder` (§6.14) and `Sphere` (§6.43), tessellated (32 segments around,
//!   16 × 32 for the sphere) with the exact normals of the surface; `ElevationGrid` (§6.17)
//!   and `Extrusion` (§6.18, with the spine-aligned cross-section plane of the standard),
//!   which become faces with normals from their `creaseAngle` like an IndexedFaceSet;
//! - `Viewpoint` (§6.53): position, orientation, fieldOfView and description, transformed to
//!   the file's root coordinate system;
//! - `Inline` (§6.25): the first of its urls that can be read is drawn in place, relative to
//!   the file that holds it, with DEF names and PROTOs of its own (`inline`); an Inline is
//!   noted instead when the file is read on its own ([`parse_limited`]).
//!
//! What is read but not drawn, each kind noted once (`file.wrl:LINE: …`, with a count) in
//! [`VrmlScene::notes`], which `scene check` lists: `Text` (§6.47), `IndexedLineSet` and
//! `PointSet` (§6.24, §6.36), lights (§6.16, §6.35, §6.45: restauro's lights are the scene's
//! `[[lights]]`), `Script` (§6.40), `Background` and `Fog`,
//! textures (§6.22, §6.28, §6.33), instances of an EXTERNPROTO that is not in the file, and
//! any node type restauro does not know. Nodes with nothing to show in a still image
//! (`WorldInfo`, `NavigationInfo`, sensors, interpolators, sounds) and `ROUTE`s (§4.10) are
//! skipped without a note. Unknown fields of known nodes are skipped.
//!
//! Output coordinates are the file's own (VRML is Y-up); the scene loader turns them Z-up.

use std::path::Path;

use crate::error::SceneError;
use crate::limits::Limits;
use crate::mesh::Mesh;

mod builder;
mod census;
mod extrusion;
mod face_set;
mod faces;
mod inline;
mod lexer;
mod math;
mod notes;
mod parser;
mod primitives;
mod proto;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_geometry;
#[cfg(test)]
mod tests_proto;

use builder::Builder;
use census::Census;
pub use inline::embed_inlines;
pub use inline::from_assets as inlines_from_assets;
use parser::Parser;

/// A camera of the file (§6.53), in the file's root coordinate system.
#[derive(Clone, Debug, PartialEq)]
pub struct Viewpoint {
    /// In the file's coordinates, in 64 bits (a georeferenced world's are in the millions).
    pub position: [f64; 3],
    /// Axis (unit length) and angle in radians, rotating the default view direction (−Z, with
    /// +Y up).
    pub orientation: ([f32; 3], f32),
    /// `fieldOfView` in radians (§6.53: the smaller of the two viewport angles).
    pub field_of_view: f32,
    pub description: String,
}

/// What a `.wrl` file holds for restauro: its triangles and its cameras.
#[derive(Clone, Debug, PartialEq)]
pub struct VrmlScene {
    pub mesh: Mesh,
    pub viewpoints: Vec<Viewpoint>,
    /// What the file holds but restauro does not draw (`file.wrl:LINE: …`), one per kind of
    /// node, in line order.
    pub notes: Vec<String>,
}

/// The deepest nesting of nodes accepted (nodes inside nodes, counting `USE` expansions), so
/// that neither parsing nor walking the scene can exhaust the stack.
pub const MAX_DEPTH: usize = 256;
// The triangles, node instances and polygon vertices one file may expand to, counting `USE`
// copies and PROTO expansions, are the scene's [`Limits`] (`max_triangles`, `max_instances`,
// `max_polygon_vertices`): they are counted before anything is built (see `Census`), so a file
// that stands for 2^40 instances is refused at once instead of walked.

/// A file an `Inline` names: its reference in the scene's assets, how messages name it, and
/// its text.
pub struct Inlined {
    pub reference: String,
    pub shown: std::path::PathBuf,
    pub text: String,
}

/// Where `Inline`d files come from: given the reference of the file that holds the Inline and
/// one of its urls, the file.
pub type InlineFn<'a> = dyn Fn(&str, &str) -> crate::Result<Inlined> + Sync + 'a;

/// Read the file at `path` and [`parse`] it.
pub fn load(path: &Path) -> crate::Result<VrmlScene> {
    let bytes = crate::assets::read_regular_file(
        path,
        crate::limits::Limits::default().max_file_bytes,
        crate::assets::MAX_FILE_FIX,
    )?;
    parse(&crate::assets::utf8_text(bytes, path)?, path)
}

/// Parse the text of a VRML97 file; `path` names the file in error messages.
pub fn parse(text: &str, path: &Path) -> crate::Result<VrmlScene> {
    parse_limited(text, path, &Limits::default())
}

/// [`parse`] within `limits` (triangles, node instances and polygon vertices, counting `USE`
/// copies).
pub fn parse_limited(text: &str, path: &Path, limits: &Limits) -> crate::Result<VrmlScene> {
    // Parsing, walking and dropping the node tree recurse once per nesting level (at most
    // MAX_DEPTH levels, a few frames each): more than a 2 MB thread stack holds in a debug
    // build, so the work runs on a thread whose stack is known to suffice.
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("vrml97".to_string())
            .stack_size(STACK_BYTES)
            .spawn_scoped(scope, || parse_here(text, path, "", limits, None));
        match worker {
            Ok(handle) => handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => parse_here(text, path, "", limits, None),
        }
    })
}

/// [`parse_limited`] drawing the files `Inline`s name (§6.25), read through `inline`; the
/// world's own reference is `reference` (the inlined files' urls are relative to it).
pub fn parse_with_inlines(
    text: &str,
    path: &Path,
    reference: &str,
    limits: &Limits,
    inline: &InlineFn<'_>,
) -> crate::Result<VrmlScene> {
    std::thread::scope(|scope| {
        let work = || parse_here(text, path, reference, limits, Some(inline));
        let worker = std::thread::Builder::new()
            .name("vrml97".to_string())
            .stack_size(STACK_BYTES)
            .spawn_scoped(scope, work);
        match worker {
            Ok(handle) => handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => work(),
        }
    })
}

/// The stack of the parsing thread (reserved, not committed, until used).
const STACK_BYTES: usize = 64 << 20;

fn parse_here(
    text: &str,
    path: &Path,
    reference: &str,
    limits: &Limits,
    inline: Option<&InlineFn<'_>>,
) -> crate::Result<VrmlScene> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    check_header(text, path)?;
    let mut parser = Parser::new(text, path, limits.max_instances)?;
    let roots = parser.parse_file()?;
    Census::new(path, limits).check(&roots)?;
    let mut builder = Builder::new(path, reference, limits, inline);
    for root in &roots {
        builder.walk(root, &math::IDENTITY, None, 1)?;
    }
    if builder.mesh.triangles.is_empty() {
        let skipped = builder.notes.summary();
        let skipped =
            if skipped.is_empty() { String::new() } else { format!(" (not drawn: {skipped})") };
        return Err(SceneError::invalid(
            path,
            "whole file",
            format!(
                "the file has no triangles to draw{skipped}; restauro draws the faces of \
                 IndexedFaceSet, Box, Cone, Cylinder, Sphere, ElevationGrid and Extrusion \
                 geometry, so export the model as one of those"
            ),
        ));
    }
    let notes = builder.notes.lines(path);
    Ok(VrmlScene { mesh: builder.mesh, viewpoints: builder.viewpoints, notes })
}

/// §5.2.1: a VRML97 file starts with `#VRML V2.0 utf8`.
pub(super) fn check_header(text: &str, path: &Path) -> crate::Result<()> {
    const HEADER: &str = "#VRML V2.0 utf8";
    if text.starts_with(HEADER) {
        return Ok(());
    }
    let first = text.lines().next().unwrap_or("");
    let first: String = first.chars().take(40).collect();
    let found = if first.starts_with("#VRML V1.0") {
        "a VRML 1.0 header".to_string()
    } else if first.is_empty() {
        "an empty first line".to_string()
    } else {
        format!("`{first}`")
    };
    Err(SceneError::syntax(
        path,
        1,
        1,
        format!(
            "expected the header `{HEADER}`, found {found}; only VRML97 (#VRML V2.0 utf8) is \
             read: convert the file to VRML97 (or export glTF or OBJ)"
        ),
    ))
}
