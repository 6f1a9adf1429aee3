//! The scene file as text: read from disk (a regular file, within the size limit, UTF-8), its
//! nesting bounded before the TOML parser recurses into it, parsed, and its format checked.
//! These come first because nothing else can be checked until the file is a `SceneFile`.

use super::{Limits, LoadedScene, load};
use crate::assets::FolderAssets;
use crate::error::{Result, SceneError};
use crate::scene_file::{self, SceneFile};
use std::path::Path;

/// The deepest nesting of arrays and inline tables a scene file may have. A scene needs three
/// (`mix = [{ … }]` inside a table); the TOML parser and serde recurse once per level, so a few
/// hundred kilobytes of `[[[[…` would overflow the stack of the thread that reads it (a worker's
/// thread has 2 MiB) and abort the process, which no error can report.
pub const MAX_TOML_NESTING: usize = 32;

/// Refuse nesting deeper than [`MAX_TOML_NESTING`] before the TOML parser sees it: brackets and
/// braces are counted outside strings and comments, a closer closing only the opener it matches
/// (the fuzz harness found unclosed inline tables with stray `]` between them overflowing the
/// parser, so a stray closer must not hide an opener).
fn check_nesting(text: &str, path: &Path) -> Result<()> {
    let (mut line, mut column) = (1usize, 0usize);
    let mut open: Vec<char> = Vec::new();
    let mut chars = text.chars().peekable();
    // The closing quote of the string being read, and whether it is a multi-line one.
    let mut string: Option<(char, bool)> = None;
    let mut comment = false;
    while let Some(c) = chars.next() {
        column += 1;
        if c == '\n' {
            line += 1;
            column = 0;
            comment = false;
            if string.is_some_and(|(_, multi)| !multi) {
                string = None; // an unterminated string; the parser will say so
            }
            continue;
        }
        if comment {
            continue;
        }
        let triple = |chars: &mut std::iter::Peekable<std::str::Chars>, q: char| {
            let mut ahead = chars.clone();
            if ahead.next() == Some(q) && ahead.next() == Some(q) {
                chars.next();
                chars.next();
                true
            } else {
                false
            }
        };
        match string {
            Some((q, multi)) => {
                if c == '\\' && q == '"' {
                    chars.next(); // an escaped character, whatever it is
                } else if c == q && (!multi || triple(&mut chars, q)) {
                    string = None;
                }
            }
            None => match c {
                '#' => comment = true,
                '"' | '\'' => string = Some((c, triple(&mut chars, c))),
                '[' | '{' => {
                    open.push(c);
                    if open.len() > MAX_TOML_NESTING {
                        return Err(SceneError::syntax(
                            path,
                            line,
                            column,
                            format!(
                                "arrays and inline tables nested more than {MAX_TOML_NESTING} \
                                 deep (or left open); a scene needs three at most, so this file \
                                 is damaged or not a scene"
                            ),
                        ));
                    }
                }
                ']' | '}' if open.last() == Some(&if c == ']' { '[' } else { '{' }) => {
                    open.pop();
                }
                _ => {}
            },
        }
    }
    Ok(())
}

/// Parse the text of a scene file. TOML errors carry their line and column.
pub fn parse_scene(text: &str, path: &Path) -> Result<SceneFile> {
    check_nesting(text, path)?;
    let parsed = crate::guard::catch(|| toml::from_str::<SceneFile>(text))
        .map_err(|_| SceneError::invalid(path, "TOML", crate::guard::gave_up("TOML")))?;
    let file: SceneFile = parsed.map_err(|e| {
        let (line, column) = e
            .span()
            .map(|s| {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
                (line, column)
            })
            .unwrap_or((0, 0));
        SceneError::syntax(path, line, column, plain_message(e.message()))
    })?;
    if file.format != scene_file::FORMAT {
        return Err(SceneError::invalid(
            path,
            "format",
            format!(
                "format = {}, but this restauro reads format {}",
                file.format,
                scene_file::FORMAT
            ),
        ));
    }
    Ok(file)
}

/// The TOML reader's message in the user's words where serde's would name a Rust type: a
/// spectrum that is none of the four forms (an unknown or misspelt key in its inline table).
fn plain_message(message: &str) -> String {
    if message.contains("untagged enum SpectrumSource") {
        return "a spectrum is a shipped name (\"travertine_tufa_solid__eco_ward73\"), \
                { file = \"…csv\", extrapolate = true|false }, { illuminant = \"D65\" } or \
                { mix = [{ spectrum = \"…\", weight = … }, …] }, with no other keys: check the \
                keys of this table"
            .to_owned();
    }
    message.to_owned()
}

/// Load and check the scene file at `path` with the files of its folder; files named by URL
/// are refused (restauro-assets's `load_scene` fetches them, and reads archives too).
pub fn load_folder(path: &Path, limits: &Limits) -> Result<LoadedScene> {
    let (file, assets) = open_folder(path, limits)?;
    load(file, &assets, limits)
}

/// The scene file at `path` and the files of its folder, as [`load_folder`] and
/// [`crate::bundle::bundle_folder`] read them: the file parsed, its files named by URL refused
/// ([`crate::pins::check_pins`]).
pub fn open_folder(path: &Path, limits: &Limits) -> Result<(SceneFile, FolderAssets)> {
    let file = read_scene_file(path, limits)?;
    crate::pins::check_pins(path, &file.pins)?;
    Ok((file, FolderAssets::new(path, limits.max_file_bytes)?))
}

/// Read and parse the scene file at `path`: a regular file (not a FIFO or a device, which would
/// block or never end), within the file size limit, UTF-8.
pub fn read_scene_file(path: &Path, limits: &Limits) -> Result<SceneFile> {
    let bytes =
        crate::assets::read_regular_file(path, limits.max_file_bytes, crate::assets::MAX_FILE_FIX)?;
    let text = crate::assets::utf8_text(bytes, path)?;
    parse_scene(&text, path)
}
