//! A VRML97 (ISO/IEC 14772-1:1997) importer: the static geometry of a `.wrl` world as one
//! triangle [`Mesh`], plus its `Viewpoint`s.
//!
//! Why hand-written: restauro needs only the geometric core of VRML97 (the scene graph of
//! `Transform`/`Group`/`Shape`/`IndexedFaceSet`), but needs it to never panic, never recurse
//! or allocate without bound, and to say exactly where a broken file is broken.
//!
//! What is read (section numbers of ISO/IEC 14772-1:1997):
//! - the header `#VRML V2.0 utf8` (§5.2.1); VRML 1.0 and anything else is refused;
//! - the lexical rules of §5.1 and §5.5: `#` comments, commas as whitespace, strings with
//!   `\"` and `\\` escapes, decimal and `0x` hexadecimal numbers;
//! - `DEF`/`USE` (§4.6.2): a `USE` re-instantiates the node under the transforms of the place it
//!   is used; a name can be used only after its `DEF`;
//! - `Transform` (§6.52), `Group` (§6.21), and, as plain groups, `Anchor` (§6.2), `Billboard`
//!   (§6.6, its screen alignment is ignored) and `Collision` (§6.8); `Switch` (§6.46) descends
//!   into `choice[whichChoice]` and `LOD` (§6.26) into its first (most detailed) `level`;
//! - `Shape` (§6.41) with `Appearance { material Material { diffuseColor } }` (§6.3, §6.27)
//!   and `IndexedFaceSet` geometry (§6.23) with `Coordinate` (§6.12), `coordIndex`, `ccw`,
//!   `solid`, `convex` and `creaseAngle`; other geometry (`Box`, `Sphere`, `IndexedLineSet`, …)
//!   is skipped, as are an `IndexedFaceSet`'s `normal`, `color` and `texCoord` fields: normals
//!   are always computed from `creaseAngle` (§6.23), so every shape has them;
//! - `Viewpoint` (§6.53): position, orientation, fieldOfView and description, transformed to
//!   the file's root coordinate system.
//!
//! Every other node (`WorldInfo`, `NavigationInfo`, `Background`, lights, `Inline`, sensors,
//! interpolators, `Script`, …) is parsed only to skip it: its `DEF`s still count, but nothing
//! inside it is drawn (`Inline` files are not fetched). Unknown fields of known nodes are
//! skipped the same way. `PROTO` and `EXTERNPROTO` (§4.8, §4.9) are refused, since expanding
//! them is a language of its own; `ROUTE`s (§4.10) are skipped, since restauro renders one
//! still instant.
//!
//! Output coordinates are the file's own (VRML is Y-up); the scene loader turns them Z-up.

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use crate::error::SceneError;
use crate::load::Limits;
use crate::mesh::{Group, Mesh};

/// A camera of the file (§6.53), in the file's root coordinate system.
#[derive(Clone, Debug, PartialEq)]
pub struct Viewpoint {
    pub position: [f32; 3],
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
}

/// The deepest nesting of nodes accepted (nodes inside nodes, counting `USE` expansions), so
/// that neither parsing nor walking the scene can exhaust the stack.
pub const MAX_DEPTH: usize = 256;
// The triangles, node instances and polygon vertices one file may expand to, counting `USE`
// copies, are the scene's [`Limits`] (`max_triangles`, `max_instances`,
// `max_polygon_vertices`): they are counted before anything is built (see `Census`), so a file
// that stands for 2^40 instances is refused at once instead of walked.
/// Polygons with more vertices than this are fanned even when `convex FALSE`: ear clipping is
/// quadratic to cubic in the vertex count.
const MAX_EAR_CLIP_VERTICES: usize = 512;
/// Vertices shared by more faces than this get faceted normals: smoothing compares every pair
/// of faces around a vertex.
const MAX_SMOOTHED_FACES: usize = 256;

/// Read the file at `path` and [`parse`] it.
pub fn load(path: &Path) -> crate::Result<VrmlScene> {
    let bytes = crate::assets::read_regular_file(
        path,
        crate::load::Limits::default().max_file_bytes,
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
            .spawn_scoped(scope, || parse_here(text, path, limits));
        match worker {
            Ok(handle) => handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => parse_here(text, path, limits),
        }
    })
}

/// The stack of the parsing thread (reserved, not committed, until used).
const STACK_BYTES: usize = 64 << 20;

fn parse_here(text: &str, path: &Path, limits: &Limits) -> crate::Result<VrmlScene> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    check_header(text, path)?;
    let mut parser = Parser::new(text, path)?;
    let roots = parser.parse_file()?;
    Census::new(path).check(&roots, limits)?;
    let mut builder = Builder::new(path, limits);
    for root in &roots {
        builder.walk(root, &IDENTITY, None, 1)?;
    }
    if builder.mesh.triangles.is_empty() {
        return Err(SceneError::invalid(
            path,
            "whole file",
            "the file has no IndexedFaceSet triangles; restauro draws only IndexedFaceSet \
             geometry (Box, Sphere, Cone, Cylinder, ElevationGrid and Extrusion are skipped), so \
             export the model as indexed faces",
        ));
    }
    Ok(VrmlScene { mesh: builder.mesh, viewpoints: builder.viewpoints })
}

/// §5.2.1: a VRML97 file starts with `#VRML V2.0 utf8`.
fn check_header(text: &str, path: &Path) -> crate::Result<()> {
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

// ---------------------------------------------------------------------------------------------
// Tokens (§5.1)

/// A line and column (1-based, columns counted in characters).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Pos {
    line: u32,
    column: u32,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Word(String),
    Num(f64),
    Str(String),
    Open,
    Close,
    OpenList,
    CloseList,
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    pos: Pos,
}

/// How a token reads in "expected …, found …" messages.
fn describe(token: Option<&Token>) -> String {
    match token.map(|t| &t.tok) {
        None => "the end of the file".to_string(),
        Some(Tok::Word(w)) => format!("`{w}`"),
        Some(Tok::Num(n)) => format!("the number {n}"),
        Some(Tok::Str(s)) => {
            let s: String = s.chars().take(30).collect();
            format!("the string \"{s}\"")
        }
        Some(Tok::Open) => "`{`".to_string(),
        Some(Tok::Close) => "`}`".to_string(),
        Some(Tok::OpenList) => "`[`".to_string(),
        Some(Tok::CloseList) => "`]`".to_string(),
    }
}

/// §5.1: whitespace is space, tab, line feed, carriage return and comma.
fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\r' | ',')
}

/// Characters that end a word or number (§5.5 excludes them from identifiers).
fn is_delimiter(c: char) -> bool {
    is_space(c) || matches!(c, '{' | '}' | '[' | ']' | '"' | '#' | '\'' | '\\')
}

/// Splits the text into tokens one at a time (so a large file is never held twice), keeping
/// each token's line and column.
struct Lexer<'a> {
    chars: std::iter::Peekable<std::str::Chars<'a>>,
    line: u32,
    column: u32,
    path: &'a Path,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        Lexer { chars: text.chars().peekable(), line: 1, column: 1, path }
    }

    fn pos(&self) -> Pos {
        Pos { line: self.line, column: self.column }
    }

    /// One character, keeping the position.
    fn bump(&mut self) -> Option<char> {
        let c = self.chars.next();
        if c == Some('\n') {
            self.line = self.line.saturating_add(1);
            self.column = 1;
        } else if c.is_some() {
            self.column = self.column.saturating_add(1);
        }
        c
    }

    fn error(&self, pos: Pos, problem: impl Into<String>) -> SceneError {
        SceneError::syntax(self.path, pos.line as usize, pos.column as usize, problem)
    }

    /// The next token, or `None` at the end of the text.
    fn next_token(&mut self) -> crate::Result<Option<Token>> {
        while let Some(&c) = self.chars.peek() {
            let pos = self.pos();
            if is_space(c) {
                self.bump();
                continue;
            }
            if c == '#' {
                while self.chars.peek().is_some_and(|&c| c != '\n' && c != '\r') {
                    self.bump();
                }
                continue;
            }
            let single = match c {
                '{' => Some(Tok::Open),
                '}' => Some(Tok::Close),
                '[' => Some(Tok::OpenList),
                ']' => Some(Tok::CloseList),
                _ => None,
            };
            if let Some(tok) = single {
                self.bump();
                return Ok(Some(Token { tok, pos }));
            }
            if c == '"' {
                return self.string(pos).map(Some);
            }
            let mut word = String::new();
            while let Some(&c) = self.chars.peek() {
                if is_delimiter(c) {
                    break;
                }
                word.push(c);
                self.bump();
            }
            if word.is_empty() {
                // A lone `'` or `\`: not part of any VRML97 token.
                return Err(self.error(
                    pos,
                    format!("expected a node, field or value, found the character `{c}`"),
                ));
            }
            let tok = if c.is_ascii_digit() || matches!(c, '+' | '-' | '.') {
                match parse_number(&word) {
                    Some(n) => Tok::Num(n),
                    None => {
                        return Err(self.error(pos, format!("expected a number, found `{word}`")));
                    }
                }
            } else {
                Tok::Word(word)
            };
            return Ok(Some(Token { tok, pos }));
        }
        Ok(None)
    }

    /// §5.1: a string in double quotes, where `\"` and `\\` stand for `"` and `\`.
    fn string(&mut self, pos: Pos) -> crate::Result<Token> {
        self.bump();
        let mut s = String::new();
        loop {
            match self.bump() {
                None => {
                    return Err(self.error(
                        pos,
                        "expected a closing `\"` for the string that starts here, found the end \
                         of the file; close the string",
                    ));
                }
                Some('"') => return Ok(Token { tok: Tok::Str(s), pos }),
                Some('\\') => match self.bump() {
                    Some(e @ ('"' | '\\')) => s.push(e),
                    Some(other) => {
                        s.push('\\');
                        s.push(other);
                    }
                    None => {}
                },
                Some(other) => s.push(other),
            }
        }
    }
}

/// A number as §5.3 writes them: decimal floats and integers, and `0x` hexadecimal integers.
/// Overflow gives an infinity, refused where the number is used.
fn parse_number(word: &str) -> Option<f64> {
    let (negative, digits) = match word.as_bytes().first() {
        Some(b'-') => (true, &word[1..]),
        Some(b'+') => (false, &word[1..]),
        _ => (false, word),
    };
    if let Some(hex) = digits.strip_prefix("0x").or_else(|| digits.strip_prefix("0X")) {
        if hex.is_empty() || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        let value = i64::from_str_radix(hex, 16).ok()? as f64;
        return Some(if negative { -value } else { value });
    }
    if !word.chars().all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E')) {
        return None;
    }
    word.parse::<f64>().ok()
}

// ---------------------------------------------------------------------------------------------
// Syntax tree (§4.4, §5): nodes with their fields, whatever the node type.

/// A parsed node. Fields are kept by name; which ones mean something is decided while walking.
#[derive(Debug)]
struct Node {
    kind: String,
    def: Option<String>,
    pos: Pos,
    fields: Vec<Field>,
    /// For `Shape` nodes, their number in file order (from 1), which names unnamed shapes.
    ordinal: usize,
}

#[derive(Debug)]
struct Field {
    name: String,
    pos: Pos,
    value: Value,
}

/// A field value, as far as its syntax tells (§5.2, §5.3): the node's type is not consulted.
#[derive(Debug)]
enum Value {
    /// Numbers (SFFloat, SFVec3f, MFInt32, …), each with its position.
    Nums(Vec<f64>, Vec<Pos>),
    Strs(Vec<String>),
    /// SFNode / MFNode; `NULL` is an empty list. `USE`d nodes are shared.
    Nodes(Vec<Rc<Node>>),
    /// `TRUE`, `FALSE` or another bare word.
    Word(String),
    /// A list of words or of mixed items, which nothing here reads.
    Other,
}

impl Node {
    fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().rev().find(|f| f.name == name)
    }

    fn nodes(&self, name: &str) -> &[Rc<Node>] {
        match self.field(name).map(|f| &f.value) {
            Some(Value::Nodes(nodes)) => nodes,
            _ => &[],
        }
    }

    fn first_node(&self, name: &str) -> Option<&Rc<Node>> {
        self.nodes(name).first()
    }
}

// ---------------------------------------------------------------------------------------------
// Parser

struct Parser<'a> {
    lexer: Lexer<'a>,
    /// The next token and the one after it (the grammar needs one token of look-ahead past
    /// the next, to tell a node `Type {` from a bare word).
    current: Option<Token>,
    ahead: Option<Token>,
    path: &'a Path,
    /// §4.6.2: the node a name was last `DEF`d to.
    defs: HashMap<String, Rc<Node>>,
    shapes: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str, path: &'a Path) -> crate::Result<Self> {
        let mut lexer = Lexer::new(text, path);
        let current = lexer.next_token()?;
        let ahead = lexer.next_token()?;
        Ok(Parser { lexer, current, ahead, path, defs: HashMap::new(), shapes: 0 })
    }

    fn peek(&self) -> Option<&Token> {
        self.current.as_ref()
    }

    fn peek_second(&self) -> Option<&Token> {
        self.ahead.as_ref()
    }

    /// Moves past the next token.
    fn advance(&mut self) -> crate::Result<()> {
        self.current = self.ahead.take();
        if self.current.is_some() {
            self.ahead = self.lexer.next_token()?;
        }
        Ok(())
    }

    /// The position of the next token, or of the end of the file.
    fn here(&self) -> Pos {
        match self.peek() {
            Some(t) => t.pos,
            None => self.lexer.pos(),
        }
    }

    fn error(&self, pos: Pos, problem: impl Into<String>) -> SceneError {
        SceneError::syntax(self.path, pos.line as usize, pos.column as usize, problem)
    }

    /// "expected X, found <next token>".
    fn expected(&self, what: &str) -> SceneError {
        self.error(self.here(), format!("expected {what}, found {}", describe(self.peek())))
    }

    fn expect_word(&mut self, what: &str) -> crate::Result<(String, Pos)> {
        match self.peek() {
            Some(Token { tok: Tok::Word(w), pos }) => {
                let out = (w.clone(), *pos);
                self.advance()?;
                Ok(out)
            }
            _ => Err(self.expected(what)),
        }
    }

    fn expect(&mut self, tok: Tok, what: &str) -> crate::Result<()> {
        if self.peek().map(|t| &t.tok) == Some(&tok) {
            self.advance()?;
            Ok(())
        } else {
            Err(self.expected(what))
        }
    }

    /// §4.4: a file is a sequence of nodes, prototypes and routes.
    fn parse_file(&mut self) -> crate::Result<Vec<Rc<Node>>> {
        let mut roots = Vec::new();
        while let Some(token) = self.peek() {
            match token.tok.clone() {
                Tok::Word(w) if self.statement_keyword(&w)? => {}
                Tok::Word(_) => roots.push(self.parse_node(1)?),
                _ => return Err(self.expected("a node")),
            }
        }
        Ok(roots)
    }

    /// Handles `ROUTE` (skipped), `PROTO` and `EXTERNPROTO` (refused); false for other words.
    fn statement_keyword(&mut self, word: &str) -> crate::Result<bool> {
        match word {
            "ROUTE" => {
                // §4.10: ROUTE node.eventOut TO node.eventIn (identifiers here keep their dot).
                self.advance()?;
                self.expect_word("the source `node.eventOut` of the ROUTE")?;
                match self.peek() {
                    Some(Token { tok: Tok::Word(w), .. }) if w == "TO" => self.advance()?,
                    _ => return Err(self.expected("`TO` in the ROUTE")),
                }
                self.expect_word("the target `node.eventIn` of the ROUTE")?;
                Ok(true)
            }
            "PROTO" | "EXTERNPROTO" => Err(self.error(
                self.here(),
                format!(
                    "{word} is not supported: restauro reads VRML97 without prototypes; expand \
                     the prototypes into plain nodes (most exporters have an option for it)"
                ),
            )),
            _ => Ok(false),
        }
    }

    fn check_depth(&self, depth: usize) -> crate::Result<()> {
        if depth > MAX_DEPTH {
            let pos = self.here();
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!("the nesting depth of nodes at {}:{}", pos.line, pos.column),
                value: depth as u64,
                limit: MAX_DEPTH as u64,
                fix: "flatten the scene graph (fewer nested Transforms and Groups)".to_string(),
            });
        }
        Ok(())
    }

    /// A node statement (§4.6.2): `DEF name Type { … }`, `USE name` or `Type { … }`.
    fn parse_node(&mut self, depth: usize) -> crate::Result<Rc<Node>> {
        self.check_depth(depth)?;
        if let Some(Token { tok: Tok::Word(w), .. }) = self.peek() {
            let w = w.clone();
            if matches!(w.as_str(), "PROTO" | "EXTERNPROTO") {
                self.statement_keyword(&w)?;
            }
            if matches!(w.as_str(), "ROUTE" | "NULL" | "TRUE" | "FALSE" | "IS") {
                return Err(self.expected("a node"));
            }
        }
        let (word, pos) = self.expect_word("a node")?;
        match word.as_str() {
            "USE" => {
                let (name, name_pos) = self.expect_word("the name after USE")?;
                match self.defs.get(&name) {
                    Some(node) => Ok(node.clone()),
                    None => Err(self.error(
                        name_pos,
                        format!(
                            "USE `{name}`: no node was DEF'd with that name before this point; \
                             add `DEF {name}` to the node meant (before its first USE; names are \
                             case-sensitive)"
                        ),
                    )),
                }
            }
            "DEF" => {
                let (name, _) = self.expect_word("the name after DEF")?;
                let (kind, kind_pos) = self.expect_word("the node type after the DEF name")?;
                let node = self.parse_body(kind, Some(name.clone()), kind_pos, depth)?;
                self.defs.insert(name, node.clone());
                Ok(node)
            }
            _ => self.parse_body(word, None, pos, depth),
        }
    }

    /// `{ field value … }` after a node type.
    fn parse_body(
        &mut self,
        kind: String,
        def: Option<String>,
        pos: Pos,
        depth: usize,
    ) -> crate::Result<Rc<Node>> {
        self.expect(Tok::Open, &format!("`{{` after the node type `{kind}`"))?;
        let mut fields = Vec::new();
        loop {
            match self.peek() {
                Some(Token { tok: Tok::Close, .. }) => {
                    self.advance()?;
                    break;
                }
                Some(Token { tok: Tok::Word(w), .. }) => {
                    let w = w.clone();
                    if self.statement_keyword(&w)? {
                        continue;
                    }
                    let (name, field_pos) = self.expect_word("a field name")?;
                    if matches!(name.as_str(), "eventIn" | "eventOut" | "field" | "exposedField") {
                        // §6.40: a Script's interface declaration: kind, type, name[, value].
                        self.expect_word("a field type")?;
                        self.expect_word("a field name")?;
                        if matches!(name.as_str(), "field" | "exposedField") {
                            self.parse_value(&name, depth)?;
                        }
                        continue;
                    }
                    if self.peek().map(|t| &t.tok) == Some(&Tok::Word("IS".to_string())) {
                        return Err(self.error(
                            field_pos,
                            "IS belongs in a PROTO, which restauro does not read; expand the \
                             prototypes into plain nodes",
                        ));
                    }
                    let value = self.parse_value(&name, depth)?;
                    fields.push(Field { name, pos: field_pos, value });
                }
                _ => {
                    return Err(self.expected(&format!(
                        "a field name or the `}}` that closes `{kind}` (opened at {}:{})",
                        pos.line, pos.column
                    )));
                }
            }
        }
        let ordinal = if kind == "Shape" {
            self.shapes += 1;
            self.shapes
        } else {
            0
        };
        Ok(Rc::new(Node { kind, def, pos, fields, ordinal }))
    }

    /// Whether the next tokens start a node: `DEF`, `USE`, or a type followed by `{`.
    fn at_node(&self) -> bool {
        match self.peek().map(|t| &t.tok) {
            Some(Tok::Word(w)) if w == "DEF" || w == "USE" => true,
            Some(Tok::Word(_)) => self.peek_second().map(|t| &t.tok) == Some(&Tok::Open),
            _ => false,
        }
    }

    /// A field value of any type (§5): one value, a run of numbers, a bracketed list or nodes.
    fn parse_value(&mut self, field: &str, depth: usize) -> crate::Result<Value> {
        if self.at_node() {
            return Ok(Value::Nodes(vec![self.parse_node(depth + 1)?]));
        }
        let Some(token) = self.peek() else {
            return Err(self.expected(&format!("a value for the field `{field}`")));
        };
        match &token.tok {
            Tok::Num(_) => {
                let (mut nums, mut places) = (Vec::new(), Vec::new());
                while let Some(Token { tok: Tok::Num(n), pos }) = self.peek() {
                    nums.push(*n);
                    places.push(*pos);
                    self.advance()?;
                }
                Ok(Value::Nums(nums, places))
            }
            Tok::Str(s) => {
                let s = s.clone();
                self.advance()?;
                Ok(Value::Strs(vec![s]))
            }
            Tok::Word(w) if w == "NULL" => {
                self.advance()?;
                Ok(Value::Nodes(Vec::new()))
            }
            Tok::Word(w) => {
                let w = w.clone();
                self.advance()?;
                Ok(Value::Word(w))
            }
            Tok::OpenList => {
                let open = token.pos;
                self.advance()?;
                self.parse_list(field, open, depth)
            }
            _ => Err(self.expected(&format!("a value for the field `{field}`"))),
        }
    }

    /// `[ … ]` (§5.2): numbers, strings, nodes or words.
    fn parse_list(&mut self, field: &str, open: Pos, depth: usize) -> crate::Result<Value> {
        let (mut nums, mut places) = (Vec::new(), Vec::new());
        let mut strs = Vec::new();
        let mut nodes = Vec::new();
        let mut words = false;
        loop {
            if self.at_node() {
                nodes.push(self.parse_node(depth + 1)?);
                continue;
            }
            match self.peek().map(|t| (&t.tok, t.pos)) {
                Some((Tok::CloseList, _)) => {
                    self.advance()?;
                    break;
                }
                Some((Tok::Num(n), pos)) => {
                    nums.push(*n);
                    places.push(pos);
                    self.advance()?;
                }
                Some((Tok::Str(s), _)) => {
                    strs.push(s.clone());
                    self.advance()?;
                }
                Some((Tok::Word(w), _)) => {
                    if matches!(w.as_str(), "PROTO" | "EXTERNPROTO") {
                        let w = w.clone();
                        self.statement_keyword(&w)?;
                    }
                    words = true;
                    self.advance()?;
                }
                _ => {
                    return Err(self.expected(&format!(
                        "a value or the `]` that closes the list of `{field}` (opened at {}:{})",
                        open.line, open.column
                    )));
                }
            }
        }
        let kinds = [!nums.is_empty(), !strs.is_empty(), !nodes.is_empty(), words];
        Ok(match kinds.iter().filter(|&&k| k).count() {
            0 => Value::Nums(nums, places),
            1 if !nodes.is_empty() => Value::Nodes(nodes),
            1 if !strs.is_empty() => Value::Strs(strs),
            1 if !nums.is_empty() => Value::Nums(nums, places),
            _ => Value::Other,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Matrices: 4×4, row-major, acting on column vectors, in f64 so deep hierarchies stay exact.

type Mat = [[f64; 4]; 4];
type V3 = [f64; 3];

const IDENTITY: Mat =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

fn mul(a: &Mat, b: &Mat) -> Mat {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

fn translation(t: V3) -> Mat {
    let mut m = IDENTITY;
    for k in 0..3 {
        m[k][3] = t[k];
    }
    m
}

fn scaling(s: V3) -> Mat {
    let mut m = IDENTITY;
    for k in 0..3 {
        m[k][k] = s[k];
    }
    m
}

/// The rotation of `angle` radians about `axis` (right-handed, §4.4.5's SFRotation); a zero
/// axis is no rotation.
fn rotation(axis: V3, angle: f64) -> Mat {
    let len = dot(axis, axis).sqrt();
    if len == 0.0 || !len.is_finite() {
        return IDENTITY;
    }
    let [x, y, z] = axis.map(|a| a / len);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn apply_point(m: &Mat, p: V3) -> V3 {
    std::array::from_fn(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3])
}

fn apply_linear(m: &[[f64; 3]; 3], v: V3) -> V3 {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

fn linear(m: &Mat) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[i][j]))
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    dot(m[0], cross(m[1], m[2]))
}

/// The cofactor matrix, `det · (M⁻¹)ᵀ`: it carries normals through `M` even when `M` is
/// singular, and differs from the inverse transpose only by the factor `det`.
fn cofactor(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
        })
    })
}

/// Whether a number is finite as a 32-bit float, which the mesh stores.
fn fits_f32(x: f64) -> bool {
    x.is_finite() && x.abs() <= f32::MAX as f64
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn normalized(v: V3) -> Option<V3> {
    let len = dot(v, v).sqrt();
    (len > 0.0 && len.is_finite()).then(|| v.map(|x| x / len))
}

/// The rotation nearest a linear map, by Gram–Schmidt on its columns (exact for rotations
/// times uniform scales, the usual case; good enough for a camera otherwise).
fn rotation_part(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let column = |j: usize| [m[0][j], m[1][j], m[2][j]];
    let Some(x) = normalized(column(0)) else { return linear(&IDENTITY) };
    let y = sub(column(1), x.map(|c| c * dot(x, column(1))));
    let Some(y) = normalized(y) else { return linear(&IDENTITY) };
    let z = cross(x, y);
    std::array::from_fn(|i| [x[i], y[i], z[i]])
}

/// A rotation matrix as an axis and angle (via a unit quaternion, stable near 0 and π).
fn axis_angle(r: &[[f64; 3]; 3]) -> (V3, f64) {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s]
    };
    let v = [q[1], q[2], q[3]];
    let len = dot(v, v).sqrt();
    if len.is_nan() || len <= 1e-12 || !q[0].is_finite() {
        return ([0.0, 0.0, 1.0], 0.0);
    }
    (v.map(|c| c / len), 2.0 * len.atan2(q[0]))
}

// ---------------------------------------------------------------------------------------------
// Walking the scene graph

/// Turns the parsed nodes into the mesh, instance by instance.
struct Builder<'a> {
    path: &'a Path,
    mesh: Mesh,
    viewpoints: Vec<Viewpoint>,
    instances: u64,
    max_triangles: u64,
    max_instances: u64,
    max_polygon_vertices: u64,
    /// The triangulation of each IndexedFaceSet node walked, by node address (the nodes live
    /// as long as the builder).
    cache: HashMap<usize, Rc<Local>>,
}

/// A field's place and name, for messages: "12:5 translation of Transform `arch`".
fn place(field: &Field, node: &Node) -> String {
    let of = match &node.def {
        Some(name) => format!("{} `{name}`", node.kind),
        None => format!("{} at {}:{}", node.kind, node.pos.line, node.pos.column),
    };
    format!("{}:{}: `{}` of {of}", field.pos.line, field.pos.column, field.name)
}

impl Builder<'_> {
    fn new<'a>(path: &'a Path, limits: &Limits) -> Builder<'a> {
        Builder {
            path,
            mesh: Mesh { normals: Some(Vec::new()), ..Mesh::default() },
            viewpoints: Vec::new(),
            instances: 0,
            max_triangles: limits.max_triangles,
            max_instances: limits.max_instances,
            max_polygon_vertices: limits.max_polygon_vertices,
            cache: HashMap::new(),
        }
    }

    /// A field of exactly `N` finite numbers (f32 range), or `default` when absent.
    fn numbers<const N: usize>(
        &self,
        node: &Node,
        name: &str,
        default: [f64; N],
    ) -> crate::Result<[f64; N]> {
        let Some(field) = node.field(name) else { return Ok(default) };
        let nums: &[f64] = match &field.value {
            Value::Nums(nums, _) => nums,
            _ => &[],
        };
        if nums.len() != N {
            return Err(SceneError::invalid(
                self.path,
                place(field, node),
                format!(
                    "expected {N} number{}, found {}",
                    if N == 1 { "" } else { "s" },
                    nums.len()
                ),
            ));
        }
        let mut out = [0.0; N];
        for (o, &n) in out.iter_mut().zip(nums) {
            if !fits_f32(n) {
                return Err(SceneError::invalid(
                    self.path,
                    place(field, node),
                    format!(
                        "{n} is not a finite number restauro can hold (32-bit float); fix the value"
                    ),
                ));
            }
            *o = n;
        }
        Ok(out)
    }

    /// A `TRUE`/`FALSE` field, or `default` when absent.
    fn boolean(&self, node: &Node, name: &str, default: bool) -> crate::Result<bool> {
        let Some(field) = node.field(name) else { return Ok(default) };
        match &field.value {
            Value::Word(w) if w == "TRUE" => Ok(true),
            Value::Word(w) if w == "FALSE" => Ok(false),
            _ => Err(SceneError::invalid(self.path, place(field, node), "expected TRUE or FALSE")),
        }
    }

    /// One node instance under the matrix `m`; `name` is the nearest `DEF` name of an
    /// enclosing group, which names the shapes below it.
    fn walk(
        &mut self,
        node: &Node,
        m: &Mat,
        name: Option<&str>,
        depth: usize,
    ) -> crate::Result<()> {
        if depth > MAX_DEPTH {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!(
                    "the nesting depth of nodes (with USE copies) at {}:{}",
                    node.pos.line, node.pos.column
                ),
                value: depth as u64,
                limit: MAX_DEPTH as u64,
                fix: "flatten the scene graph (fewer nested Transforms, Groups and USEs)"
                    .to_string(),
            });
        }
        // The census has counted these already; this is the backstop.
        self.instances += 1;
        if self.instances > self.max_instances {
            return Err(instances_limit(self.path, self.instances, self.max_instances));
        }
        let group_name = node.def.as_deref().or(name);
        match node.kind.as_str() {
            "Transform" => {
                let local = self.transform(node)?;
                let m = mul(m, &local);
                self.walk_all(node.nodes("children"), &m, group_name, depth)
            }
            "Group" | "Anchor" | "Billboard" | "Collision" => {
                self.walk_all(node.nodes("children"), m, group_name, depth)
            }
            "Switch" => {
                let [which] = self.numbers(node, "whichChoice", [-1.0])?;
                let choices = node.nodes("choice");
                match (which >= 0.0).then(|| choices.get(which as usize)).flatten() {
                    Some(child) => self.walk(child, m, group_name, depth + 1),
                    None => Ok(()),
                }
            }
            "LOD" => match node.nodes("level").first() {
                Some(child) => self.walk(child, m, group_name, depth + 1),
                None => Ok(()),
            },
            "Shape" => self.shape(node, m, group_name),
            "Viewpoint" => self.viewpoint(node, m),
            _ => Ok(()),
        }
    }

    fn walk_all(
        &mut self,
        nodes: &[Rc<Node>],
        m: &Mat,
        name: Option<&str>,
        depth: usize,
    ) -> crate::Result<()> {
        for child in nodes {
            self.walk(child, m, name, depth + 1)?;
        }
        Ok(())
    }

    /// §6.52: `T · C · R · SR · S · SR⁻¹ · C⁻¹`.
    fn transform(&self, node: &Node) -> crate::Result<Mat> {
        let t = self.numbers(node, "translation", [0.0; 3])?;
        let [rx, ry, rz, ra] = self.numbers(node, "rotation", [0.0, 0.0, 1.0, 0.0])?;
        let s = self.numbers(node, "scale", [1.0; 3])?;
        let [sx, sy, sz, sa] = self.numbers(node, "scaleOrientation", [0.0, 0.0, 1.0, 0.0])?;
        let c = self.numbers(node, "center", [0.0; 3])?;
        let mut m = translation(t);
        for factor in [
            translation(c),
            rotation([rx, ry, rz], ra),
            rotation([sx, sy, sz], sa),
            scaling(s),
            rotation([sx, sy, sz], -sa),
            translation(c.map(|x| -x)),
        ] {
            m = mul(&m, &factor);
        }
        Ok(m)
    }

    /// §6.53, carried to the root: position by the matrix, orientation by its rotation part.
    fn viewpoint(&mut self, node: &Node, m: &Mat) -> crate::Result<()> {
        let position = self.numbers(node, "position", [0.0, 0.0, 10.0])?;
        let [x, y, z, a] = self.numbers(node, "orientation", [0.0, 0.0, 1.0, 0.0])?;
        let [fov] = self.numbers(node, "fieldOfView", [std::f64::consts::FRAC_PI_4])?; // §6.53: 0.785398
        let description = match node.field("description").map(|f| &f.value) {
            Some(Value::Strs(s)) => s.first().cloned().unwrap_or_default(),
            _ => String::new(),
        };
        let world = rotation_part(&linear(m));
        let local = linear(&rotation([x, y, z], a));
        let combined: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| world[i][k] * local[k][j]).sum())
        });
        let (axis, angle) = axis_angle(&combined);
        let p = apply_point(m, position);
        if !p.iter().all(|&c| fits_f32(c)) {
            return Err(SceneError::invalid(
                self.path,
                format!("{}:{}: Viewpoint", node.pos.line, node.pos.column),
                "its position is not finite once transformed; fix the enclosing Transforms",
            ));
        }
        self.viewpoints.push(Viewpoint {
            position: p.map(|c| c as f32),
            orientation: (axis.map(|c| c as f32), angle as f32),
            field_of_view: fov as f32,
            description,
        });
        Ok(())
    }
}

const TRIANGLES_FIX: &str = "simplify the model or split it into several files, or raise the \
                             limit with --max-triangles";

fn instances_limit(path: &Path, value: u64, limit: u64) -> SceneError {
    SceneError::Limit {
        path: path.to_path_buf(),
        what: "the number of node instances (counting USE copies)".to_string(),
        value,
        limit,
        fix: "use fewer nested USEs of large groups, or raise the limit with --max-instances"
            .to_string(),
    }
}

/// How much a node expands to, counting every `USE` copy, worked out once per node (a `USE`
/// shares the node it names): the instances the walk will visit and an upper bound on the
/// triangles it will make (a face of n corners makes at most n − 2). A few hundred bytes of
/// `DEF`/`USE` can stand for 2^40 instances; counting first refuses such a file at once, where
/// walking it would take hours.
struct Census<'a> {
    path: &'a Path,
    counted: HashMap<usize, (u64, u64)>,
}

impl<'a> Census<'a> {
    fn new(path: &'a Path) -> Self {
        Self { path, counted: HashMap::new() }
    }

    fn check(&mut self, roots: &[Rc<Node>], limits: &Limits) -> crate::Result<()> {
        let (mut instances, mut triangles) = (0u64, 0u64);
        for root in roots {
            let (i, t) = self.count(root, 1)?;
            instances = instances.saturating_add(i);
            triangles = triangles.saturating_add(t);
        }
        if instances > limits.max_instances {
            return Err(instances_limit(self.path, instances, limits.max_instances));
        }
        if triangles > limits.max_triangles {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: "the number of triangles (counting USE copies)".to_string(),
                value: triangles,
                limit: limits.max_triangles,
                fix: TRIANGLES_FIX.to_string(),
            });
        }
        Ok(())
    }

    /// Instances and triangles of one node and what the walk descends into below it.
    fn count(&mut self, node: &Rc<Node>, depth: usize) -> crate::Result<(u64, u64)> {
        let key = Rc::as_ptr(node) as usize;
        if let Some(&counted) = self.counted.get(&key) {
            return Ok(counted);
        }
        if depth > MAX_DEPTH {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!(
                    "the nesting depth of nodes (with USE copies) at {}:{}",
                    node.pos.line, node.pos.column
                ),
                value: depth as u64,
                limit: MAX_DEPTH as u64,
                fix: "flatten the scene graph (fewer nested Transforms, Groups and USEs)"
                    .to_string(),
            });
        }
        let below: Vec<Rc<Node>> = match node.kind.as_str() {
            "Transform" | "Group" | "Anchor" | "Billboard" | "Collision" => {
                node.nodes("children").to_vec()
            }
            // Whichever choice is drawn, at most all of them.
            "Switch" => node.nodes("choice").to_vec(),
            "LOD" => node.nodes("level").first().cloned().into_iter().collect(),
            _ => Vec::new(),
        };
        let (mut instances, mut triangles) = (1u64, 0u64);
        if node.kind == "Shape"
            && let Some(geometry) = node.first_node("geometry")
            && geometry.kind == "IndexedFaceSet"
            && let Some(Value::Nums(index, _)) = geometry.field("coordIndex").map(|f| &f.value)
        {
            let ends = index.iter().filter(|&&n| n == -1.0).count() as u64;
            let corners = index.len() as u64 - ends;
            triangles = corners.saturating_sub(2 * ends);
        }
        for child in &below {
            let (i, t) = self.count(child, depth + 1)?;
            instances = instances.saturating_add(i);
            triangles = triangles.saturating_add(t);
        }
        self.counted.insert(key, (instances, triangles));
        Ok((instances, triangles))
    }
}

/// An IndexedFaceSet triangulated in its own coordinates (what every `USE` of it shares).
struct Local {
    /// Point and unit normal of each vertex.
    vertices: Vec<(V3, V3)>,
    /// Counter-clockwise triangles, as indices into `vertices`.
    triangles: Vec<[u32; 3]>,
    /// `solid FALSE`.
    double_sided: bool,
}

/// An `IndexedFaceSet`'s faces, ready to triangulate: point indices of every face, flat.
struct Faces {
    /// Point indices, face after face, in counter-clockwise order.
    corners: Vec<u32>,
    /// `(start, len)` of each face in `corners`.
    spans: Vec<(usize, usize)>,
}

impl Builder<'_> {
    /// §6.41: a Shape's appearance names and colours its group; its geometry is drawn if it
    /// is an IndexedFaceSet.
    fn shape(&mut self, node: &Node, m: &Mat, name: Option<&str>) -> crate::Result<()> {
        let name = match name {
            Some(name) => name.to_string(),
            None => format!("shape{}", node.ordinal),
        };
        let material = node
            .first_node("appearance")
            .filter(|a| a.kind == "Appearance")
            .and_then(|a| a.first_node("material"))
            .filter(|m| m.kind == "Material");
        let colour = match material {
            Some(material) if material.field("diffuseColor").is_some() => {
                Some(self.numbers(material, "diffuseColor", [0.8; 3])?.map(|c| c as f32))
            }
            _ => None,
        };
        match node.first_node("geometry") {
            Some(geometry) if geometry.kind == "IndexedFaceSet" => {
                self.face_set(geometry, m, &name, colour)
            }
            _ => Ok(()),
        }
    }

    /// §6.23: an IndexedFaceSet, triangulated, with normals from `creaseAngle`, appended to
    /// the mesh under `m`.
    fn face_set(
        &mut self,
        node: &Rc<Node>,
        m: &Mat,
        name: &str,
        colour: Option<[f32; 3]>,
    ) -> crate::Result<()> {
        let local = self.local_geometry(node, name)?;
        let group = self.mesh.group_index(Group {
            name: name.to_string(),
            colour,
            double_sided: local.double_sided,
        });
        if let Some(g) = self.mesh.groups.get_mut(group as usize) {
            g.double_sided |= local.double_sided;
            if g.colour.is_none() {
                g.colour = colour;
            }
        }
        let linear_m = linear(m);
        let det = det3(&linear_m);
        if det == 0.0 || !det.is_finite() {
            return Ok(()); // a zero scale flattens the whole shape to nothing
        }
        let total = self.mesh.triangles.len() as u64 + local.triangles.len() as u64;
        if total > self.max_triangles {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!("the number of triangles (counting USE copies) with shape `{name}`"),
                value: total,
                limit: self.max_triangles,
                fix: TRIANGLES_FIX.to_string(),
            });
        }
        let end = self.mesh.positions.len() as u64 + local.vertices.len() as u64;
        if end > u32::MAX as u64 {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: "the number of vertices".to_string(),
                value: end,
                limit: u32::MAX as u64,
                fix: "simplify the model or split it into several files".to_string(),
            });
        }
        let base = self.mesh.positions.len() as u32;
        // Normals go through the inverse transpose; the cofactor matrix is that times det,
        // and the sign keeps them pointing out of the front.
        let normal_m = cofactor(&linear_m).map(|row| row.map(|x| x * det.signum()));
        self.mesh.positions.reserve(local.vertices.len());
        for &(p, n) in &local.vertices {
            let p = apply_point(m, p);
            if !p.iter().all(|&c| fits_f32(c)) {
                return Err(SceneError::invalid(
                    self.path,
                    format!(
                        "{}:{}: IndexedFaceSet of shape `{name}`",
                        node.pos.line, node.pos.column
                    ),
                    "a point is not finite once transformed; fix the enclosing Transforms' values",
                ));
            }
            let n = normalized(apply_linear(&normal_m, n)).unwrap_or(n);
            self.mesh.positions.push(p.map(|c| c as f32));
            if let Some(normals) = &mut self.mesh.normals {
                normals.push(n.map(|c| c as f32));
            }
        }
        for &[a, b, c] in &local.triangles {
            // A mirror (negative determinant) turns counter-clockwise faces clockwise.
            let tri = if det < 0.0 { [a, c, b] } else { [a, b, c] };
            self.mesh.triangles.push(tri.map(|v| v + base));
            self.mesh.triangle_group.push(group);
        }
        Ok(())
    }

    /// An IndexedFaceSet in its own coordinates: triangles with counter-clockwise fronts and
    /// per-vertex normals. Worked out once per node, however many times it is `USE`d.
    fn local_geometry(&mut self, node: &Rc<Node>, name: &str) -> crate::Result<Rc<Local>> {
        let key = Rc::as_ptr(node) as usize;
        if let Some(local) = self.cache.get(&key) {
            return Ok(local.clone());
        }
        let ccw = self.boolean(node, "ccw", true)?;
        let solid = self.boolean(node, "solid", true)?;
        let convex = self.boolean(node, "convex", true)?;
        let [crease] = self.numbers(node, "creaseAngle", [0.0])?;
        let points = self.points(node)?;
        let faces = self.faces(node, points.len(), name, ccw)?;

        // Face normals, area-weighted (Newell's method: exact for planar polygons).
        let area_normals: Vec<V3> = faces
            .spans
            .iter()
            .map(|&(start, len)| newell(&faces.corners[start..start + len], &points))
            .collect();
        let unit_normals: Vec<Option<V3>> = area_normals.iter().map(|&n| normalized(n)).collect();

        // Faces around each point (compressed rows), for smoothing.
        let mut first = vec![0usize; points.len() + 1];
        for &p in &faces.corners {
            first[p as usize + 1] += 1;
        }
        for i in 0..points.len() {
            first[i + 1] += first[i];
        }
        let mut fill = first.clone();
        let mut around = vec![0u32; faces.corners.len()];
        for (f, &(start, len)) in faces.spans.iter().enumerate() {
            for &p in &faces.corners[start..start + len] {
                around[fill[p as usize]] = f as u32;
                fill[p as usize] += 1;
            }
        }

        let cos_crease = crease.cos();
        let mut local = Local { vertices: Vec::new(), triangles: Vec::new(), double_sided: !solid };
        let mut vertex_of: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
        let mut fan = Vec::new();
        for (f, &(start, len)) in faces.spans.iter().enumerate() {
            let face = &faces.corners[start..start + len];
            let Some(face_normal) = unit_normals[f] else { continue };
            fan.clear();
            triangulate(face, &points, face_normal, convex, &mut fan);
            for &[a, b, c] in &fan {
                let (pa, pb, pc) = (face[a], face[b], face[c]);
                let area = cross(
                    sub(points[pb as usize], points[pa as usize]),
                    sub(points[pc as usize], points[pa as usize]),
                );
                if dot(area, area).is_nan() || dot(area, area) <= 0.0 {
                    continue; // zero-area triangles draw nothing
                }
                if local.triangles.len() as u64 >= self.max_triangles {
                    return Err(SceneError::Limit {
                        path: self.path.to_path_buf(),
                        what: format!("the number of triangles of shape `{name}`"),
                        value: self.max_triangles + 1,
                        limit: self.max_triangles,
                        fix: TRIANGLES_FIX.to_string(),
                    });
                }
                let mut tri = [0u32; 3];
                for (slot, p) in tri.iter_mut().zip([pa, pb, pc]) {
                    let normal = if crease > 0.0 {
                        smooth_normal(
                            f,
                            p,
                            &first,
                            &around,
                            &area_normals,
                            &unit_normals,
                            cos_crease,
                        )
                        .unwrap_or(face_normal)
                    } else {
                        face_normal
                    };
                    let key = (p, normal.map(|c| (c as f32).to_bits()));
                    *slot = match vertex_of.get(&key) {
                        Some(&v) => v,
                        None => {
                            let v = local.vertices.len() as u32;
                            local.vertices.push((points[p as usize], normal));
                            vertex_of.insert(key, v);
                            v
                        }
                    };
                }
                local.triangles.push(tri);
            }
        }
        let local = Rc::new(local);
        self.cache.insert(key, local.clone());
        Ok(local)
    }

    /// §6.12: the points of the `coord` Coordinate node, each finite.
    fn points(&self, node: &Node) -> crate::Result<Vec<V3>> {
        let Some(coord) = node.first_node("coord") else { return Ok(Vec::new()) };
        let Some(field) = coord.field("point") else { return Ok(Vec::new()) };
        let (nums, places): (&[f64], &[Pos]) = match &field.value {
            Value::Nums(nums, places) => (nums, places),
            _ => (&[], &[]),
        };
        if nums.len() % 3 != 0 {
            return Err(SceneError::invalid(
                self.path,
                place(field, coord),
                format!(
                    "{} numbers is not a whole number of points (3 numbers each); add or remove \
                     numbers so each point has x, y and z",
                    nums.len()
                ),
            ));
        }
        for (i, &n) in nums.iter().enumerate() {
            if !fits_f32(n) {
                let at = places.get(i).copied().unwrap_or(field.pos);
                return Err(SceneError::syntax(
                    self.path,
                    at.line as usize,
                    at.column as usize,
                    format!(
                        "coordinate {} of point {} of the Coordinate is not a finite number \
                         ({n}); fix the coordinate",
                        i % 3,
                        i / 3
                    ),
                ));
            }
        }
        Ok(nums.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// §6.23: `coordIndex`, faces separated by −1 (the last may lack it), each index a point.
    fn faces(&self, node: &Node, count: usize, name: &str, ccw: bool) -> crate::Result<Faces> {
        let mut faces = Faces { corners: Vec::new(), spans: Vec::new() };
        let Some(field) = node.field("coordIndex") else { return Ok(faces) };
        let (nums, places): (&[f64], &[Pos]) = match &field.value {
            Value::Nums(nums, places) => (nums, places),
            _ => (&[], &[]),
        };
        let mut start = 0usize;
        let mut face_start_pos = places.first().copied().unwrap_or(field.pos);
        let at = |i: usize| places.get(i).copied().unwrap_or(field.pos);
        for (i, &n) in nums.iter().enumerate() {
            let end_of_face = n == -1.0;
            if !end_of_face {
                if n.fract() != 0.0 || n < 0.0 || n >= count as f64 {
                    let pos = at(i);
                    return Err(SceneError::syntax(
                        self.path,
                        pos.line as usize,
                        pos.column as usize,
                        format!(
                            "coordIndex {n} (entry {i} of shape `{name}`) is out of range: the \
                             Coordinate has {count} points, so indices run from 0 to {} (−1 ends \
                             a face); fix the index or add the point",
                            count as i64 - 1
                        ),
                    ));
                }
                faces.corners.push(n as u32);
            }
            if (faces.corners.len() - start) as u64 > self.max_polygon_vertices {
                let pos = face_start_pos;
                return Err(SceneError::Limit {
                    path: self.path.to_path_buf(),
                    what: format!(
                        "the number of vertices of face {} of shape `{name}` at {}:{}",
                        faces.spans.len(),
                        pos.line,
                        pos.column
                    ),
                    value: (faces.corners.len() - start) as u64,
                    limit: self.max_polygon_vertices,
                    fix: "split the polygon into smaller faces, or raise the limit with \
                          --max-polygon-vertices"
                        .to_string(),
                });
            }
            if end_of_face || i + 1 == nums.len() {
                let len = faces.corners.len() - start;
                if len < 3 {
                    return Err(SceneError::syntax(
                        self.path,
                        face_start_pos.line as usize,
                        face_start_pos.column as usize,
                        format!(
                            "face {} of shape `{name}` has {len} vert{} but a face needs at least \
                             3; remove the face or add vertices",
                            faces.spans.len(),
                            if len == 1 { "ex" } else { "ices" }
                        ),
                    ));
                }
                if !ccw {
                    faces.corners[start..].reverse();
                }
                faces.spans.push((start, len));
                start = faces.corners.len();
                face_start_pos = at(i + 1);
            }
        }
        Ok(faces)
    }
}

/// The area-weighted normal of a polygon (Newell's method): twice its area, perpendicular.
fn newell(face: &[u32], points: &[V3]) -> V3 {
    let mut n = [0.0; 3];
    for (k, &i) in face.iter().enumerate() {
        let a = points[i as usize];
        let b = points[face[(k + 1) % face.len()] as usize];
        n = add(
            n,
            [
                (a[1] - b[1]) * (a[2] + b[2]),
                (a[2] - b[2]) * (a[0] + b[0]),
                (a[0] - b[0]) * (a[1] + b[1]),
            ],
        );
    }
    n
}

/// §6.23 creaseAngle: the normal at point `p` of face `f` averages (weighted by area) the
/// faces around `p` whose normals are within the crease angle of `f`'s.
fn smooth_normal(
    f: usize,
    p: u32,
    first: &[usize],
    around: &[u32],
    area_normals: &[V3],
    unit_normals: &[Option<V3>],
    cos_crease: f64,
) -> Option<V3> {
    let own = unit_normals.get(f).copied().flatten()?;
    let faces = around.get(*first.get(p as usize)?..*first.get(p as usize + 1)?)?;
    if faces.len() > MAX_SMOOTHED_FACES {
        return None;
    }
    let mut sum = [0.0; 3];
    let mut seen_self = false;
    for (k, &g) in faces.iter().enumerate() {
        if k > 0 && faces[k - 1] == g {
            continue; // a face that visits the point twice counts once (its entries are adjacent)
        }
        let Some(unit) = unit_normals.get(g as usize).copied().flatten() else { continue };
        if g as usize == f || dot(own, unit) > cos_crease {
            seen_self |= g as usize == f;
            sum = add(sum, area_normals[g as usize]);
        }
    }
    if !seen_self {
        sum = add(sum, area_normals[f]);
    }
    normalized(sum)
}

/// Triangles (as corner numbers of `face`) covering the polygon: a fan for convex faces, ear
/// clipping in the polygon's dominant plane for `convex FALSE` (a fan when that fails).
fn triangulate(face: &[u32], points: &[V3], normal: V3, convex: bool, out: &mut Vec<[usize; 3]>) {
    let n = face.len();
    if n == 3 || convex || n > MAX_EAR_CLIP_VERTICES {
        out.extend((1..n - 1).map(|k| [0, k, k + 1]));
        return;
    }
    // Drop the normal's largest axis; order the other two so the polygon turns
    // counter-clockwise in the plane.
    let axis =
        (0..3).fold(0, |best, k| if normal[k].abs() > normal[best].abs() { k } else { best });
    let (mut u, mut v) = ((axis + 1) % 3, (axis + 2) % 3);
    if normal[axis] < 0.0 {
        std::mem::swap(&mut u, &mut v);
    }
    let flat: Vec<[f64; 2]> =
        face.iter().map(|&i| [points[i as usize][u], points[i as usize][v]]).collect();
    let turn = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let mut left: Vec<usize> = (0..n).collect();
    let mut k = 0;
    let mut misses = 0;
    while left.len() > 3 {
        let m = left.len();
        let (ia, ib, ic) = (left[(k + m - 1) % m], left[k % m], left[(k + 1) % m]);
        let (a, b, c) = (flat[ia], flat[ib], flat[ic]);
        let is_ear = turn(a, b, c) > 0.0
            && !left.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let p = flat[j];
                if p == a || p == b || p == c {
                    return false;
                }
                turn(a, b, p) >= 0.0 && turn(b, c, p) >= 0.0 && turn(c, a, p) >= 0.0
            });
        if is_ear {
            out.push([ia, ib, ic]);
            left.remove(k % m);
            misses = 0;
            k %= m - 1;
        } else {
            misses += 1;
            k = (k + 1) % m;
            if misses >= m {
                // No ear: a self-intersecting or degenerate polygon. Fan what is left.
                out.extend((1..m - 1).map(|j| [left[0], left[j], left[j + 1]]));
                return;
            }
        }
    }
    out.push([left[0], left[1], left[2]]);
}

#[cfg(test)]
mod tests {
    use super::*;

    const PATH: &str = "t.wrl";

    fn ok(text: &str) -> VrmlScene {
        match parse(text, Path::new(PATH)) {
            Ok(scene) => {
                check_consistent(&scene.mesh);
                scene
            }
            Err(e) => panic!("unexpected error: {e}"),
        }
    }

    fn err(text: &str) -> String {
        match parse(text, Path::new(PATH)) {
            Ok(_) => panic!("expected an error for:\n{text}"),
            Err(e) => e.to_string(),
        }
    }

    fn assert_has(message: &str, words: &[&str]) {
        for w in words {
            assert!(message.contains(w), "`{w}` missing from: {message}");
        }
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-4
    }

    fn close3(a: [f32; 3], b: [f32; 3]) -> bool {
        (0..3).all(|k| close(a[k], b[k]))
    }

    fn d(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }

    fn x(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    }

    /// Twice the area vector of a triangle of the mesh.
    fn area_vector(mesh: &Mesh, t: [u32; 3]) -> [f32; 3] {
        let p = t.map(|i| mesh.positions[i as usize]);
        x(d(p[1], p[0]), d(p[2], p[0]))
    }

    /// One normal per position, unit length, on the front side of every triangle.
    fn check_consistent(mesh: &Mesh) {
        let normals = mesh.normals.as_ref().expect("normals");
        assert_eq!(normals.len(), mesh.positions.len());
        assert_eq!(mesh.triangles.len(), mesh.triangle_group.len());
        for n in normals {
            assert!(close(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0), "{n:?}");
        }
        for &t in &mesh.triangles {
            let a = area_vector(mesh, t);
            for i in t {
                let n = normals[i as usize];
                assert!(a[0] * n[0] + a[1] * n[1] + a[2] * n[2] > 0.0, "back-facing {t:?}");
            }
        }
    }

    const NESTED: &str = r#"#VRML V2.0 utf8
# Two levels of Transforms; the tile is used twice.
DEF outer Transform {
  translation 10 0 0
  rotation 0 0 1 1.5707963268
  scale 2 2 2
  children [
    DEF inner Transform {
      translation 0 1 0
      rotation 0 1 0 3.1415926536
      scale 1 3 1
      children [
        DEF tile Shape {
          appearance Appearance { material Material { diffuseColor 1 0 0 } }
          geometry IndexedFaceSet {
            coord Coordinate { point [0 0 0, 1 0 0, 1 1 0, 0 1 0] }
            coordIndex [0 1 2 3 -1]
          }
        }
      ]
    }
    Transform {
      translation 0 0 5
      children [
        USE tile
        Shape {
          appearance Appearance { material Material { diffuseColor 0 0 1 } }
          geometry IndexedFaceSet {
            coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] }
            coordIndex [0 1 2]
          }
        }
      ]
    }
  ]
}
Shape {
  geometry IndexedFaceSet { coord Coordinate { point [0 0 -1 1 0 -1 0 1 -1] } coordIndex [0 1 2 -1] }
}
"#;

    #[test]
    fn nested_transforms_with_def_and_use() {
        let scene = ok(NESTED);
        let mesh = &scene.mesh;
        assert_eq!(mesh.triangles.len(), 6);
        assert_eq!(
            mesh.triangles_per_group(),
            vec![("outer".to_string(), 1), ("shape3".to_string(), 1), ("tile".to_string(), 4)]
        );
        let colour = |name: &str| mesh.groups.iter().find(|g| g.name == name).map(|g| g.colour);
        assert_eq!(colour("tile"), Some(Some([1.0, 0.0, 0.0])));
        assert_eq!(colour("outer"), Some(Some([0.0, 0.0, 1.0])));
        assert_eq!(colour("shape3"), Some(None));
        // inner: (x, y, 0) -> (-x, 3y + 1, 0); outer: (x, y, z) -> (10 - 2y, 2x, 2z).
        // The first tile spans x 2..8, y -2..0 at z 0; the used tile (z + 5) spans x 8..10,
        // y 0..2 at z 10; the last shape spans 0..1, 0..1 at z -1.
        let b = mesh.bounds().unwrap();
        assert!(close3(b.min, [0.0, -2.0, -1.0]), "{b:?}");
        assert!(close3(b.max, [10.0, 2.0, 10.0]), "{b:?}");
        // The first tile, turned over by the half turn about Y, faces -Z.
        let tile = mesh.groups.iter().position(|g| g.name == "tile").unwrap() as u32;
        let normals = mesh.normals.as_ref().unwrap();
        let first = mesh.triangle_group.iter().position(|&g| g == tile).unwrap();
        let n = normals[mesh.triangles[first][0] as usize];
        assert!(close3(n, [0.0, 0.0, -1.0]), "{n:?}");
        assert!(mesh.positions.iter().any(|&p| close3(p, [8.0, -2.0, 0.0])));
        assert!(mesh.positions.iter().any(|&p| close3(p, [10.0, 2.0, 10.0])));
    }

    fn one_face(index: &str, points: &str, extra: &str) -> String {
        format!(
            "#VRML V2.0 utf8\nShape {{ geometry IndexedFaceSet {{\n  coord Coordinate {{ point [{points}] }}\n  coordIndex [{index}]\n  {extra}\n}} }}\n"
        )
    }

    #[test]
    fn ccw_false_reverses_winding_and_quads_make_two_triangles() {
        let tri = "0 0 0, 1 0 0, 0 1 0";
        let front = ok(&one_face("0 1 2", tri, ""));
        let back = ok(&one_face("0 1 2", tri, "ccw FALSE"));
        assert!(area_vector(&front.mesh, front.mesh.triangles[0])[2] > 0.0);
        assert!(area_vector(&back.mesh, back.mesh.triangles[0])[2] < 0.0);
        assert_eq!(back.mesh.normals.as_ref().unwrap()[0], [0.0, 0.0, -1.0]);
        assert!(!front.mesh.groups[0].double_sided);
        let two_sided = ok(&one_face("0 1 2", tri, "solid FALSE"));
        assert!(two_sided.mesh.groups[0].double_sided);

        let quad = ok(&one_face("0 1 2 3 -1", "0 0 0, 2 0 0, 2 1 0, 0 1 0", ""));
        assert_eq!(quad.mesh.triangles.len(), 2);
        let area: f32 =
            quad.mesh.triangles.iter().map(|&t| area_vector(&quad.mesh, t)[2] / 2.0).sum();
        assert!(close(area, 2.0));
    }

    #[test]
    fn concave_polygon_is_ear_clipped() {
        // An L of area 3, starting at a corner from which a fan would fold over the notch.
        let l = "2 1 0, 1 1 0, 1 2 0, 0 2 0, 0 0 0, 2 0 0";
        let scene = ok(&one_face("0 1 2 3 4 5", l, "convex FALSE"));
        let mesh = &scene.mesh;
        assert_eq!(mesh.triangles.len(), 4);
        let mut total = 0.0;
        for &t in &mesh.triangles {
            let a = area_vector(mesh, t)[2] / 2.0;
            assert!(a > 0.0, "every triangle faces +Z");
            total += a;
        }
        assert!(close(total, 3.0), "{total}");
        // The same polygon, fanned as if convex, does not cover the L exactly.
        let fanned = parse(&one_face("0 1 2 3 4 5", l, ""), Path::new(PATH)).unwrap();
        let unsigned: f32 = fanned
            .mesh
            .triangles
            .iter()
            .map(|&t| (area_vector(&fanned.mesh, t)[2] / 2.0).abs())
            .sum();
        assert!(!close(unsigned, 3.0));
        // Mirrored in the plane (clockwise), ear clipping still covers it, facing -Z.
        let scene = ok(&one_face("5 4 3 2 1 0", l, "convex FALSE"));
        let total: f32 =
            scene.mesh.triangles.iter().map(|&t| area_vector(&scene.mesh, t)[2] / 2.0).sum();
        assert!(close(total, -3.0), "{total}");
    }

    const CUBE_POINTS: &str = "0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 1, 1 0 1, 1 1 1, 0 1 1";
    const CUBE_FACES: &str = "0 3 2 1 -1 4 5 6 7 -1 0 1 5 4 -1 3 7 6 2 -1 0 4 7 3 -1 1 2 6 5";

    #[test]
    fn crease_angle_splits_or_smooths_cube_corners() {
        let sharp = ok(&one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 0.5"));
        assert_eq!(sharp.mesh.triangles.len(), 12);
        assert_eq!(sharp.mesh.positions.len(), 24);
        let normals = sharp.mesh.normals.as_ref().unwrap();
        let mut pairs: Vec<[u32; 6]> = sharp
            .mesh
            .positions
            .iter()
            .zip(normals)
            .map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]].map(f32::to_bits))
            .collect();
        pairs.sort();
        pairs.dedup();
        assert_eq!(pairs.len(), 24);
        for n in normals {
            assert_eq!(n.iter().filter(|c| c.abs() == 1.0).count(), 1, "axis normal {n:?}");
        }
        let faceted = ok(&one_face(CUBE_FACES, CUBE_POINTS, ""));
        assert_eq!(faceted.mesh.positions.len(), 24);

        let smooth = ok(&one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 2.0"));
        assert_eq!(smooth.mesh.positions.len(), 8);
        let normals = smooth.mesh.normals.as_ref().unwrap();
        let third = 1.0 / 3f32.sqrt();
        for (p, n) in smooth.mesh.positions.iter().zip(normals) {
            let outward = p.map(|c| if c > 0.5 { third } else { -third });
            assert!(close3(*n, outward), "{p:?} {n:?}");
        }
    }

    #[test]
    fn viewpoint_follows_its_transform() {
        let text = r#"#VRML V2.0 utf8
Transform { translation 1 2 3 children [
  Viewpoint { position 0 0 10 description "front \"door\"" }
  Transform { rotation 0 1 0 1.5707963268 children Viewpoint { fieldOfView 0.5 } }
] }
Shape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0 1 0 0 0 1 0] } coordIndex 0 } }
"#;
        // `coordIndex 0` alone is a one-vertex face: refused; use a full face instead.
        let text = text.replace("coordIndex 0", "coordIndex [0 1 2]");
        let scene = ok(&text);
        assert_eq!(scene.viewpoints.len(), 2);
        let front = &scene.viewpoints[0];
        assert!(close3(front.position, [1.0, 2.0, 13.0]));
        assert_eq!(front.description, "front \"door\"");
        assert!(close(front.orientation.1, 0.0));
        assert!(close(front.field_of_view, std::f32::consts::FRAC_PI_4)); // §6.53 default
        // The default position (0 0 10), turned a quarter about Y, is (10 0 0), then moved.
        let side = &scene.viewpoints[1];
        assert!(close3(side.position, [11.0, 2.0, 3.0]), "{:?}", side.position);
        assert!(close3(side.orientation.0, [0.0, 1.0, 0.0]), "{:?}", side.orientation);
        assert!(close(side.orientation.1, std::f32::consts::FRAC_PI_2));
        assert!(close(side.field_of_view, 0.5));
    }

    #[test]
    fn mirroring_transform_keeps_front_faces() {
        let text = one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "");
        let text = text.replacen("Shape", "Transform { scale -1 1 1 children Shape", 1) + "}\n";
        let scene = ok(&text);
        // x is mirrored: the face still faces +Z, so its winding was flipped.
        assert_eq!(scene.mesh.normals.as_ref().unwrap()[0], [0.0, 0.0, 1.0]);
        assert!(area_vector(&scene.mesh, scene.mesh.triangles[0])[2] > 0.0);
    }

    #[test]
    fn skips_what_it_does_not_draw() {
        let text = r#"#VRML V2.0 utf8
WorldInfo { title "Temple, \\ east" info ["a" "b"] }
NavigationInfo { type ["EXAMINE", "ANY"] headlight FALSE speed 2 }
Background { skyColor [0 0 1, 1 1 1] skyAngle [1.2] }
DEF sun DirectionalLight { direction 0 -1 0 on TRUE }
DEF clock TimeSensor { cycleInterval 4 loop TRUE }
DEF mover Script {
  eventIn SFTime tick
  eventOut SFVec3f where
  field SFFloat speed 1.5
  url "javascript: function tick(t) { }"
}
ROUTE clock.time TO mover.tick
Switch { whichChoice -1 choice [ DEF hidden Shape {
  appearance Appearance { material Material { diffuseColor 0 1 0 shininess 0.2 }
                          texture ImageTexture { url ["a.png"] } }
  geometry IndexedFaceSet {
    coord Coordinate { point [0 0 0 1 0 0 0 1 0] }
    normal Normal { vector [0 0 1] }
    normalPerVertex FALSE colorPerVertex TRUE
    texCoord TextureCoordinate { point [0 0, 1 0, 0 1] }
    coordIndex [0 1 2 -1]
    texCoordIndex [0 1 2 -1]
  }
} ] }
Shape { geometry Box { size 1 1 1 } }
Inline { url "other.wrl" }
Transform { translation 0 0 1 children [ USE hidden ] }
"#;
        let scene = ok(text);
        assert_eq!(scene.mesh.triangles_per_group(), vec![("hidden".to_string(), 1)]);
        assert_eq!(scene.mesh.groups[0].colour, Some([0.0, 1.0, 0.0]));
        assert!(scene.mesh.positions.iter().all(|p| p[2] == 1.0));
    }

    #[test]
    fn zero_area_triangles_are_dropped() {
        let scene = ok(&one_face("0 1 2 -1 0 1 3", "0 0 0, 1 0 0, 0 1 0, 2 0 0", ""));
        assert_eq!(scene.mesh.triangles.len(), 1);
    }

    #[test]
    fn refuses_other_headers_and_prototypes() {
        let e = err("#VRML V1.0 ascii\nSeparator { }\n");
        assert_has(&e, &["t.wrl:1:1", "VRML 1.0", "only VRML97 (#VRML V2.0 utf8) is read"]);
        let e = err("solid cube\n");
        assert_has(&e, &["t.wrl:1:1", "only VRML97"]);
        let e = err("#VRML V2.0 utf8\n\nPROTO Column [ field SFFloat h 1 ] { Group { } }\n");
        assert_has(&e, &["t.wrl:3:1", "PROTO is not supported", "expand"]);
        let e = err("#VRML V2.0 utf8\nGroup { children [ EXTERNPROTO X [] \"x.wrl\" ] }\n");
        assert_has(&e, &["t.wrl:2:20", "EXTERNPROTO"]);
    }

    #[test]
    fn syntax_errors_say_what_was_expected_and_found() {
        let e = err("#VRML V2.0 utf8\nShape {\n  geometry IndexedFaceSet { coord [ }\n}\n");
        assert_has(&e, &["t.wrl:3:37", "expected a value or the `]`", "found `}`"]);
        let e = err("#VRML V2.0 utf8\nShape {\n");
        assert_has(&e, &["t.wrl:3:1", "expected a field name", "the end of the file", "2:1"]);
        let e = err("#VRML V2.0 utf8\nShape { appearance \"x }\n");
        assert_has(&e, &["t.wrl:2:20", "closing `\"`"]);
        let e = err("#VRML V2.0 utf8\nTransform { translation 1.2.3 }\n");
        assert_has(&e, &["t.wrl:2:25", "expected a number, found `1.2.3`"]);
        let e = err("#VRML V2.0 utf8\n[ ]\n");
        assert_has(&e, &["t.wrl:2:1", "expected a node, found `[`"]);
    }

    #[test]
    fn bad_content_is_refused_with_its_place() {
        let e = err(&one_face("0 1 7", "0 0 0, 1 0 0, 0 1 0", ""));
        assert_has(
            &e,
            &["t.wrl:4:19", "coordIndex 7", "has 3 points", "shape `shape1`", "fix the index"],
        );
        let e = err(&one_face("0 1 2 -1 0 1 -1", "0 0 0, 1 0 0, 0 1 0", ""));
        assert_has(&e, &["t.wrl:4:24", "face 1 of shape `shape1` has 2 vertices", "at least 3"]);
        let e = err(&one_face("0 1 2", "0 0 0, 1 1e999 0, 0 1 0", ""));
        assert_has(&e, &["t.wrl:3:38", "not a finite number", "point 1"]);
        let e = err("#VRML V2.0 utf8\nGroup { children [\n  USE pillar\n] }\n");
        assert_has(&e, &["t.wrl:3:7", "USE `pillar`", "DEF pillar"]);
        let e =
            err("#VRML V2.0 utf8\nWorldInfo { title \"empty\" }\nShape { geometry Sphere { } }\n");
        assert_has(&e, &["t.wrl", "the file has no IndexedFaceSet triangles"]);
        let e = err(&(one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "")
            .replace("Shape", "Transform { translation 1 2 children Shape")
            + "}"));
        assert_has(
            &e,
            &["t.wrl: 2:13: `translation` of Transform at 2:1", "expected 3 numbers, found 2"],
        );
        let e = err(&one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "ccw 1"));
        assert_has(&e, &["`ccw`", "TRUE or FALSE"]);
    }

    #[test]
    fn limits_depth_and_triangles() {
        let deep = format!(
            "#VRML V2.0 utf8\n{}{}",
            "Group { children [\n".repeat(300),
            "] }\n".repeat(300)
        );
        let e = err(&deep);
        let fine = format!(
            "#VRML V2.0 utf8\n{}{}{}",
            "Transform { children [\n".repeat(MAX_DEPTH - 3),
            one_face("0 1 2", "0 0 0 1 0 0 0 1 0", "").trim_start_matches("#VRML V2.0 utf8"),
            "] }\n".repeat(MAX_DEPTH - 3)
        );
        assert_eq!(ok(&fine).mesh.triangles.len(), 1);
        assert_has(&e, &["t.wrl", "nesting depth", "over the limit of 256", "flatten"]);
        // USE copies count towards the depth too.
        let mut chain = "#VRML V2.0 utf8\nDEF g0 Group { }\n".to_string();
        for k in 1..=300 {
            chain += &format!("DEF g{k} Group {{ children [ USE g{} ] }}\n", k - 1);
        }
        chain += "Group { children [ Group { children [ USE g300 ] } ] }\n".repeat(2).as_str();
        assert_has(&err(&chain), &["nesting depth", "limit of 256"]);
        // Five copies of a two-triangle quad (1 + 2 in q2 + 2 in USE q2) make 10 triangles.
        let text = one_face("0 1 2 3", "0 0 0, 1 0 0, 1 1 0, 0 1 0", "").replacen(
            "Shape",
            "DEF q Transform { children Shape",
            1,
        ) + "}\nDEF q2 Group { children [ USE q USE q ] }\nUSE q2\n";
        assert_eq!(ok(&text).mesh.triangles.len(), 10);
        let five = Limits { max_triangles: 5, ..Limits::default() };
        let e = match parse_limited(&text, Path::new(PATH), &five) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("limit not applied"),
        };
        assert_has(&e, &["t.wrl", "triangles", "limit of 5", "simplify"]);
    }

    #[test]
    fn every_prefix_is_an_answer_not_a_panic() {
        let inputs =
            [NESTED.to_string(), one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 2 convex FALSE")];
        for text in &inputs {
            let mut cut = 0;
            while cut <= text.len() {
                if text.is_char_boundary(cut) {
                    let _ = parse(&text[..cut], Path::new(PATH));
                }
                cut += 5;
            }
        }
    }

    #[test]
    fn load_reports_missing_files() {
        let e = load(Path::new("/nonexistent/restauro/x.wrl")).unwrap_err();
        assert!(matches!(e, SceneError::Io { .. }));
        assert_has(&e.to_string(), &["x.wrl"]);
    }
}
