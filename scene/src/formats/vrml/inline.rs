//! `Inline` (§6.25): another VRML97 file drawn in place, under the transforms around the
//! Inline, its DEF names and PROTOs its own. Its urls are tried in order and the first that
//! can be read is drawn; a relative url is relative to the file that holds the Inline (a remote
//! file's by RFC 3986), and an `https://` url is fetched and pinned like any file of the scene
//! (restauro-assets's `remote`). A file that inlines itself, directly or through others, is refused.
//!
//! In a bundle each url drawn is replaced by the inlined file's hash (`blake3:<hex>.wrl`, see
//! [`embed_inlines`]), so the bundle alone holds the world.

use std::collections::{BTreeMap, HashSet};
use std::path::Path;
use std::rc::Rc;

use super::builder::{Builder, place};
use super::census::Census;
use super::lexer::Pos;
use super::math::Mat;
use super::parser::{Node, Parser, Value};
use super::{InlineFn, Inlined, check_header};
use crate::error::SceneError;
use crate::limits::Limits;

/// A file an Inline names, parsed.
pub(super) struct InlinedFile {
    reference: String,
    shown: Rc<Path>,
    roots: Vec<Rc<Node>>,
}

/// Parses an inlined file's text (its header, its nodes, its census within `limits`).
fn parse_inlined(inlined: &Inlined, limits: &Limits) -> crate::Result<Vec<Rc<Node>>> {
    let text = inlined.text.strip_prefix('\u{feff}').unwrap_or(&inlined.text);
    check_header(text, &inlined.shown)?;
    let roots = Parser::new(text, &inlined.shown, limits.max_instances)?.parse_file()?;
    Census::new(&inlined.shown, limits).check(&roots)?;
    Ok(roots)
}

/// The urls of an Inline, each with the position of its opening quote.
fn urls(node: &Node) -> (Vec<String>, Vec<Pos>) {
    match node.field("url").map(|f| &*f.value) {
        Some(Value::Strs(urls, quotes)) => (urls.clone(), quotes.clone()),
        _ => (Vec::new(), Vec::new()),
    }
}

impl Builder<'_> {
    /// Draws the first of the Inline's files that can be read.
    pub(super) fn inline(
        &mut self,
        node: &Node,
        m: &Mat,
        name: Option<&str>,
        depth: usize,
    ) -> crate::Result<()> {
        let (urls, _) = urls(node);
        if urls.is_empty() {
            return Err(self.invalid_field(node, "url", "an Inline needs the url of a file"));
        }
        let (file, _) = first_readable(&urls, |url| self.inlined_file(url))
            .map_err(|problem| self.invalid_field(node, "url", problem.to_string()))?;
        if let Some(problem) = cycle(&self.files, &file.reference) {
            return Err(self.invalid_field(node, "url", problem));
        }
        let outer = std::mem::replace(&mut self.path, file.shown.clone());
        self.files.push(file.reference.clone());
        self.notes.file = Some(file.shown.clone());
        let walked = self.walk_all(&file.roots, m, name, depth);
        self.files.pop();
        self.path = outer;
        self.notes.file = (self.files.len() > 1).then(|| self.path.clone());
        walked
    }

    /// The file `url` names from the file being walked: read and parsed once.
    fn inlined_file(&mut self, url: &str) -> crate::Result<Rc<InlinedFile>> {
        let base = self.files.last().cloned().unwrap_or_default();
        let key = (base, url.to_owned());
        if let Some(file) = self.inlined.get(&key) {
            return Ok(file.clone());
        }
        let source = self.inline.expect("inlines are walked only with a source");
        let inlined = source(&key.0, url)?;
        let roots = parse_inlined(&inlined, &self.limits)?;
        let file = Rc::new(InlinedFile {
            reference: inlined.reference,
            shown: Rc::from(inlined.shown.as_path()),
            roots,
        });
        self.inlined.insert(key, file.clone());
        Ok(file)
    }
}

/// The text of the world at `reference` with each Inline url that it draws replaced by the
/// hash reference `store` gives the inlined file's bytes (themselves embedded first), for a
/// bundle; the text is unchanged when it inlines nothing.
pub fn embed_inlines(
    text: &str,
    path: &Path,
    reference: &str,
    limits: &Limits,
    source: &InlineFn<'_>,
    store: &mut dyn FnMut(Vec<u8>) -> String,
) -> crate::Result<String> {
    let mut chain = vec![reference.to_owned()];
    embed(text, path, limits, source, store, &mut chain)
}

fn embed(
    text: &str,
    path: &Path,
    limits: &Limits,
    source: &InlineFn<'_>,
    store: &mut dyn FnMut(Vec<u8>) -> String,
    chain: &mut Vec<String>,
) -> crate::Result<String> {
    let body = text.strip_prefix('\u{feff}').unwrap_or(text);
    let roots = Parser::new(body, path, limits.max_instances)?.parse_file()?;
    let mut replacements: BTreeMap<(u32, u32), String> = BTreeMap::new();
    let mut seen = HashSet::new();
    for node in inline_nodes(&roots) {
        let (urls, quotes) = urls(&node);
        if urls.is_empty() || quotes.iter().any(|q| seen.contains(&(q.line, q.column))) {
            continue; // refused when drawn; or embedded already (a PROTO's body, used again)
        }
        let place = node.field("url").map_or_else(String::new, |f| place(f, &node));
        let base = chain.last().cloned().unwrap_or_default();
        // The urls are tried in order, as when the world is drawn.
        let (inlined, chosen) = first_readable(&urls, |url| source(&base, url))
            .map_err(|problem| SceneError::invalid(path, &place, problem.to_string()))?;
        let quote = quotes[chosen];
        seen.insert((quote.line, quote.column));
        if let Some(problem) = cycle(chain, &inlined.reference) {
            return Err(SceneError::invalid(path, place, problem));
        }
        chain.push(inlined.reference.clone());
        let inner = embed(&inlined.text, &inlined.shown, limits, source, store, chain);
        chain.pop();
        replacements.insert((quote.line, quote.column), store(inner?.into_bytes()));
    }
    if replacements.is_empty() {
        return Ok(text.to_owned());
    }
    Ok(splice_strings(body, &replacements))
}

/// None of an Inline's urls can be read: each url's refusal, in the order they were tried.
#[derive(Debug, thiserror::Error)]
#[error("no url can be read: {}", joined(.0))]
struct Unreadable(Vec<SceneError>);

fn joined(problems: &[SceneError]) -> String {
    problems.iter().map(ToString::to_string).collect::<Vec<_>>().join("; ")
}

/// The first of `urls` that `read` reads, with its index; else every url's problem.
fn first_readable<T>(
    urls: &[String],
    mut read: impl FnMut(&str) -> crate::Result<T>,
) -> Result<(T, usize), Unreadable> {
    let mut problems = Vec::new();
    for (i, url) in urls.iter().enumerate() {
        match read(url) {
            Ok(file) => return Ok((file, i)),
            Err(e) => problems.push(e),
        }
    }
    Err(Unreadable(problems))
}

/// The refusal of an inlined file already among the files being walked (`chain`, outermost
/// first): the chain from its first appearance back to it.
fn cycle(chain: &[String], reference: &str) -> Option<String> {
    let at = chain.iter().position(|f| f == reference)?;
    let back = [&chain[at..], std::slice::from_ref(&reference.to_owned())].concat();
    Some(format!("the file inlines itself: {}", back.join(" → ")))
}

/// Every Inline node of the tree (each node once, however often it is `USE`d).
fn inline_nodes(roots: &[Rc<Node>]) -> Vec<Rc<Node>> {
    let mut out = Vec::new();
    let mut seen = HashSet::new();
    let mut stack: Vec<Rc<Node>> = roots.to_vec();
    while let Some(node) = stack.pop() {
        if !seen.insert(Rc::as_ptr(&node) as usize) {
            continue;
        }
        if node.kind == "Inline" {
            out.push(node.clone());
        }
        for field in &node.fields {
            if let Value::Nodes(children) = &*field.value {
                stack.extend(children.iter().cloned());
            }
        }
    }
    out
}

/// `text` with the string literal whose opening quote is at each (line, column) (columns in
/// characters, as the lexer counts them) replaced by a literal of the new text.
fn splice_strings(text: &str, replacements: &BTreeMap<(u32, u32), String>) -> String {
    if replacements.is_empty() {
        return text.to_owned();
    }
    let mut out = String::with_capacity(text.len());
    let (mut line, mut column) = (1u32, 1u32);
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c == '"'
            && let Some(new) = replacements.get(&(line, column))
        {
            column += 1; // the opening quote
            // Skip the old literal to its closing quote (`\"` and `\\` are escapes, §5.1).
            let mut escaped = false;
            for c in chars.by_ref() {
                if c == '\n' {
                    line += 1;
                    column = 0;
                }
                column += 1;
                match (escaped, c) {
                    (false, '\\') => escaped = true,
                    (false, '"') => break,
                    _ => escaped = false,
                }
            }
            out.push('"');
            out.push_str(&new.replace('\\', "\\\\").replace('"', "\\\""));
            out.push('"');
            continue;
        }
        out.push(c);
        if c == '\n' {
            line += 1;
            column = 1;
        } else {
            column += 1;
        }
    }
    out
}

/// The files a VRML97 world's `Inline`s name, read through `assets`: a url is relative to the
/// file that holds the Inline. `place` is where the scene names the world, for messages.
pub fn from_assets<'a>(
    assets: &'a dyn crate::assets::Assets,
    place: &'a str,
) -> impl Fn(&str, &str) -> crate::Result<Inlined> + Sync + 'a {
    move |base: &str, url: &str| {
        let reference = crate::assets::sibling(base, url).map_err(|e| {
            SceneError::invalid(assets.display_path(base), format!("Inline `{url}`"), e.to_string())
        })?;
        let shown = assets.display_path(&reference);
        let text = crate::assets::utf8_text(assets.read(&reference, place)?, &shown)?;
        Ok(Inlined { reference, shown, text })
    }
}
