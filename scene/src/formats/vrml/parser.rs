//! The node tree (§4.4, §5): nodes with their fields, whatever the node type, read by a
//! recursive-descent parser that keeps every node's place. `PROTO` instances are expanded as
//! they are read (see [`super::proto`]), so the tree holds only built-in nodes.

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use super::MAX_DEPTH;
use super::lexer::{Lexer, Pos, Tok, Token, describe};
use super::proto::{Decl, Expander, Extern, Proto, ProtoDef, Scope};
use crate::error::SceneError;

/// A parsed node. Fields are kept by name; which ones mean something is decided while walking.
#[derive(Debug)]
pub(super) struct Node {
    pub kind: String,
    pub def: Option<String>,
    pub pos: Pos,
    pub fields: Vec<Field>,
    /// For `Shape` nodes, their number in file order (from 1), which names unnamed shapes;
    /// each expanded copy of a Shape that depends on a PROTO's fields gets its own.
    pub ordinal: usize,
    /// The levels of nodes this one stands for, itself included (`USE`d nodes counted): every
    /// node keeps it within [`MAX_DEPTH`], so nothing that recurses over the tree, dropping it
    /// included, goes deeper.
    pub height: usize,
    /// Whether an `IS` (§4.8.3) is in this node or below it: only such nodes are copied when a
    /// PROTO is instantiated, the rest are shared.
    pub has_is: bool,
    /// How many nodes with an `IS` in or below them this one holds, itself included and
    /// every `USE` counted: what an expansion copies at most, known before copying.
    pub is_nodes: u64,
    /// An instance of an EXTERNPROTO that is not in this file: what it was declared as.
    pub external: Option<Rc<Extern>>,
}

#[derive(Debug)]
pub(super) struct Field {
    pub name: String,
    pub pos: Pos,
    /// Shared, so that a PROTO's field value used in several places, or by several
    /// instances, is held once.
    pub value: Rc<Value>,
}

/// A field value, as far as its syntax tells (§5.2, §5.3): the node's type is not consulted.
#[derive(Debug)]
pub(super) enum Value {
    /// Numbers (SFFloat, SFVec3f, MFInt32, …), each with its position.
    Nums(Vec<f64>, Vec<Pos>),
    /// Strings (SFString, MFString), each with the position of its opening quote.
    Strs(Vec<String>, Vec<Pos>),
    /// SFNode / MFNode; `NULL` is an empty list. `USE`d nodes are shared.
    Nodes(Vec<Rc<Node>>),
    /// `TRUE`, `FALSE` or another bare word.
    Word(String),
    /// A list of words or of mixed items, which nothing here reads.
    Other,
    /// `IS name` in a PROTO body (§4.8.3): the PROTO's field `name`, until instantiated.
    Is(String),
}

impl Node {
    /// A node; its height and whether it holds an `IS` follow from its fields.
    pub fn new(
        kind: String,
        def: Option<String>,
        pos: Pos,
        fields: Vec<Field>,
        ordinal: usize,
    ) -> Node {
        let (mut height, mut has_is, mut below) = (1, false, 0u64);
        for field in &fields {
            match &*field.value {
                Value::Is(_) => has_is = true,
                Value::Nodes(nodes) => {
                    for n in nodes {
                        height = height.max(n.height + 1);
                        has_is |= n.has_is;
                        below = below.saturating_add(n.is_nodes);
                    }
                }
                _ => {}
            }
        }
        let is_nodes = if has_is { below.saturating_add(1) } else { 0 };
        Node { kind, def, pos, fields, ordinal, height, has_is, is_nodes, external: None }
    }

    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().rev().find(|f| f.name == name)
    }

    pub fn nodes(&self, name: &str) -> &[Rc<Node>] {
        match self.field(name).map(|f| &*f.value) {
            Some(Value::Nodes(nodes)) => nodes,
            _ => &[],
        }
    }

    pub fn first_node(&self, name: &str) -> Option<&Rc<Node>> {
        self.nodes(name).first()
    }
}

/// The nodes PROTO expansion may copy are at most `max_instances` / this (1 250 000 by
/// default): unlike instances, which a `USE` shares, copies are held in memory at once (about
/// 150 bytes each), and making them takes time before the census can count anything.
pub(super) const EXPANSION_SHARE: u64 = 16;

/// A PROTO whose body is being read: what `IS` may refer to, and what may not be
/// instantiated inside it (§4.8.3: a prototype cannot contain itself).
struct Defining {
    name: String,
    pos: Pos,
    fields: Vec<String>,
}

pub(super) struct Parser<'a> {
    lexer: Lexer<'a>,
    /// The next token and the one after it (the grammar needs one token of look-ahead past
    /// the next, to tell a node `Type {` from a bare word).
    current: Option<Token>,
    ahead: Option<Token>,
    pub(super) path: &'a Path,
    /// The file's scope, then one per PROTO body being read (§4.6.2, §4.8.3): `DEF` names and
    /// prototypes declared in each.
    scopes: Vec<Scope>,
    defining: Vec<Defining>,
    pub(super) shapes: usize,
    /// Nodes made by expanding prototypes so far, and the most allowed (`max_instances`).
    pub(super) expanded: u64,
    pub(super) max_expanded: u64,
}

impl<'a> Parser<'a> {
    /// `max_instances` bounds the nodes copied by PROTO expansion too (see [`EXPANSION_SHARE`]).
    pub fn new(text: &'a str, path: &'a Path, max_instances: u64) -> crate::Result<Self> {
        let mut lexer = Lexer::new(text, path);
        let current = lexer.next_token()?;
        let ahead = lexer.next_token()?;
        Ok(Parser {
            lexer,
            current,
            ahead,
            path,
            scopes: vec![Scope::default()],
            defining: Vec::new(),
            shapes: 0,
            expanded: 0,
            max_expanded: max_instances / EXPANSION_SHARE,
        })
    }

    fn peek(&self) -> Option<&Token> {
        self.current.as_ref()
    }

    fn peek_second(&self) -> Option<&Token> {
        self.ahead.as_ref()
    }

    fn peek_word(&self) -> Option<&str> {
        match self.peek() {
            Some(Token { tok: Tok::Word(w), .. }) => Some(w),
            _ => None,
        }
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

    pub(super) fn error(&self, pos: Pos, problem: impl Into<String>) -> SceneError {
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

    fn scope(&mut self) -> &mut Scope {
        // The file's scope is never popped.
        let last = self.scopes.len() - 1;
        &mut self.scopes[last]
    }

    /// §4.4: a file is a sequence of nodes, prototypes and routes.
    pub fn parse_file(&mut self) -> crate::Result<Vec<Rc<Node>>> {
        let mut roots = Vec::new();
        while let Some(token) = self.peek() {
            match token.tok.clone() {
                Tok::Word(w) if self.statement_keyword(&w, 1)? => {}
                Tok::Word(_) => roots.push(self.parse_node(1)?),
                _ => return Err(self.expected("a node")),
            }
        }
        Ok(roots)
    }

    /// Handles `ROUTE` (skipped), `PROTO` and `EXTERNPROTO` (declared); false for other words.
    fn statement_keyword(&mut self, word: &str, depth: usize) -> crate::Result<bool> {
        match word {
            "ROUTE" => {
                // §4.10: ROUTE node.eventOut TO node.eventIn (identifiers here keep their dot).
                self.advance()?;
                self.expect_word("the source `node.eventOut` of the ROUTE")?;
                match self.peek_word() {
                    Some("TO") => self.advance()?,
                    _ => return Err(self.expected("`TO` in the ROUTE")),
                }
                self.expect_word("the target `node.eventIn` of the ROUTE")?;
                Ok(true)
            }
            "PROTO" => self.parse_proto(depth).map(|()| true),
            "EXTERNPROTO" => self.parse_externproto().map(|()| true),
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

    /// A node of `height` levels placed at `depth` must fit within [`MAX_DEPTH`].
    pub(super) fn check_height(
        &self,
        depth: usize,
        height: usize,
        pos: Pos,
        copies: &str,
    ) -> crate::Result<()> {
        let total = (depth - 1).saturating_add(height);
        if total > MAX_DEPTH {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!(
                    "the nesting depth of nodes (with {copies}) at {}:{}",
                    pos.line, pos.column
                ),
                value: total as u64,
                limit: MAX_DEPTH as u64,
                fix: format!(
                    "flatten the scene graph (fewer nested Transforms, Groups and {copies})"
                ),
            });
        }
        Ok(())
    }

    /// A node statement (§4.6.2): `DEF name Type { … }`, `USE name` or `Type { … }`.
    fn parse_node(&mut self, depth: usize) -> crate::Result<Rc<Node>> {
        self.check_depth(depth)?;
        if let Some(w) = self.peek_word() {
            if matches!(w, "PROTO" | "EXTERNPROTO") {
                return Err(self.misplaced_proto());
            }
            if matches!(w, "ROUTE" | "NULL" | "TRUE" | "FALSE" | "IS") {
                return Err(self.expected("a node"));
            }
        }
        let (word, pos) = self.expect_word("a node")?;
        match word.as_str() {
            "USE" => self.parse_use(depth),
            "DEF" => {
                let (name, _) = self.expect_word("the name after DEF")?;
                let (kind, kind_pos) = self.expect_word("the node type after the DEF name")?;
                let node = self.parse_body(kind, Some(name.clone()), kind_pos, depth)?;
                self.scope().defs.insert(name, node.clone());
                Ok(node)
            }
            _ => self.parse_body(word, None, pos, depth),
        }
    }

    /// `USE name` (§4.6.2): the node last `DEF`d to `name` in this scope, shared.
    fn parse_use(&mut self, depth: usize) -> crate::Result<Rc<Node>> {
        let (name, name_pos) = self.expect_word("the name after USE")?;
        let found = self.scopes.last().and_then(|s| s.defs.get(&name)).cloned();
        let Some(node) = found else {
            let outer = self.scopes.iter().rev().skip(1).any(|s| s.defs.contains_key(&name));
            let hint = if outer {
                " (a PROTO body sees only the names DEF'd inside it, §4.8.3: pass the node in \
                 through a field of the PROTO instead)"
            } else {
                ""
            };
            return Err(self.error(
                name_pos,
                format!(
                    "USE `{name}`: no node was DEF'd with that name before this point{hint}; \
                     add `DEF {name}` to the node meant (before its first USE; names are \
                     case-sensitive)"
                ),
            ));
        };
        self.check_height(depth, node.height, name_pos, "USE copies")?;
        Ok(node)
    }

    /// `{ field value … }` after a node type; an instance of a prototype is expanded.
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
                    if self.statement_keyword(&w, depth + 1)? {
                        continue;
                    }
                    if let Some(field) = self.parse_field(depth)? {
                        fields.push(field);
                    }
                }
                _ => {
                    return Err(self.expected(&format!(
                        "a field name or the `}}` that closes `{kind}` (opened at {}:{})",
                        pos.line, pos.column
                    )));
                }
            }
        }
        if let Some(proto) = self.prototype(&kind, pos)? {
            return self.instantiate(proto, &kind, def, pos, fields, depth);
        }
        let ordinal = if kind == "Shape" {
            self.shapes += 1;
            self.shapes
        } else {
            0
        };
        Ok(Rc::new(Node::new(kind, def, pos, fields, ordinal)))
    }

    /// One `name value` or `name IS protoField` of a node body; `None` for a Script's
    /// interface declaration (§6.40), which is read and skipped.
    fn parse_field(&mut self, depth: usize) -> crate::Result<Option<Field>> {
        let (name, field_pos) = self.expect_word("a field name")?;
        if matches!(name.as_str(), "eventIn" | "eventOut" | "field" | "exposedField") {
            // §6.40: kind, type, name, then a value, `IS` or (for events) nothing.
            self.expect_word("a field type")?;
            self.expect_word("a field name")?;
            if self.peek_word() == Some("IS") {
                self.parse_is(field_pos)?;
            } else if matches!(name.as_str(), "field" | "exposedField") {
                self.parse_value(&name, depth)?;
            }
            return Ok(None);
        }
        if self.peek_word() == Some("IS") {
            let target = self.parse_is(field_pos)?;
            return Ok(Some(Field { name, pos: field_pos, value: Rc::new(Value::Is(target)) }));
        }
        let value = Rc::new(self.parse_value(&name, depth)?);
        Ok(Some(Field { name, pos: field_pos, value }))
    }

    /// `IS name` (§4.8.3): allowed only in a PROTO body, naming one of its fields.
    fn parse_is(&mut self, field_pos: Pos) -> crate::Result<String> {
        self.advance()?;
        let (target, target_pos) = self.expect_word("the name of a PROTO field after IS")?;
        let Some(proto) = self.defining.last() else {
            return Err(self.error(
                field_pos,
                "IS is used outside a PROTO body; give the field a value instead",
            ));
        };
        if !proto.fields.contains(&target) {
            return Err(self.error(
                target_pos,
                format!(
                    "IS `{target}`: PROTO `{}` (at {}:{}) declares no field `{target}` (it has: \
                     {}); declare it in the PROTO's interface or fix the name",
                    proto.name,
                    proto.pos.line,
                    proto.pos.column,
                    list_or_none(&proto.fields)
                ),
            ));
        }
        Ok(target)
    }

    /// Whether the next tokens start a node: `DEF`, `USE`, or a type followed by `{`.
    fn at_node(&self) -> bool {
        match self.peek().map(|t| &t.tok) {
            Some(Tok::Word(w)) if w == "DEF" || w == "USE" => true,
            Some(Tok::Word(_)) => self.peek_second().map(|t| &t.tok) == Some(&Tok::Open),
            _ => false,
        }
    }

    fn misplaced_proto(&self) -> SceneError {
        self.error(
            self.here(),
            format!(
                "{} declares a prototype among the statements of the file or of a PROTO body, \
                 not as a field's value (§4.8); move it before the node that uses it",
                self.peek_word().unwrap_or("PROTO")
            ),
        )
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
                let (s, pos) = (s.clone(), token.pos);
                self.advance()?;
                Ok(Value::Strs(vec![s], vec![pos]))
            }
            Tok::Word(w) if w == "NULL" => {
                self.advance()?;
                Ok(Value::Nodes(Vec::new()))
            }
            Tok::Word(w) if w == "PROTO" || w == "EXTERNPROTO" => Err(self.misplaced_proto()),
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
        let (mut strs, mut quotes) = (Vec::new(), Vec::new());
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
                Some((Tok::Str(s), pos)) => {
                    strs.push(s.clone());
                    quotes.push(pos);
                    self.advance()?;
                }
                Some((Tok::Word(w), _)) => {
                    if matches!(w.as_str(), "PROTO" | "EXTERNPROTO") {
                        return Err(self.misplaced_proto());
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
            1 if !strs.is_empty() => Value::Strs(strs, quotes),
            1 if !nums.is_empty() => Value::Nums(nums, places),
            _ => Value::Other,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// Prototypes (§4.8, §4.9): declarations and instances.

impl Parser<'_> {
    /// `PROTO Name [ interface ] { body }` (§4.8.1): declared in the current scope. Its body
    /// is read in a scope of its own (§4.8.3), one level deeper than the statement.
    fn parse_proto(&mut self, depth: usize) -> crate::Result<()> {
        self.check_depth(depth)?;
        let pos = self.here();
        self.advance()?;
        let (name, _) = self.expect_word("the name of the PROTO")?;
        self.expect(Tok::OpenList, &format!("`[` and the interface of PROTO `{name}`"))?;
        let decls = self.parse_interface(&name, true, depth)?;
        let open = self.here();
        self.expect(Tok::Open, &format!("`{{` and the body of PROTO `{name}`"))?;
        let fields = decls.iter().map(|d| d.name.clone()).collect();
        self.scopes.push(Scope::default());
        self.defining.push(Defining { name: name.clone(), pos, fields });
        let root = self.parse_proto_body(&name, open, depth + 1);
        self.defining.pop();
        self.scopes.pop();
        let proto = Proto { pos, decls, root: root? };
        self.scope().protos.insert(name, ProtoDef::Local(Rc::new(proto)));
        Ok(())
    }

    /// §4.8.3: the body's first node is what an instance stands for; the nodes after it are
    /// read (their `DEF`s count) but not drawn.
    fn parse_proto_body(&mut self, name: &str, open: Pos, depth: usize) -> crate::Result<Rc<Node>> {
        let mut root = None;
        loop {
            match self.peek() {
                Some(Token { tok: Tok::Close, .. }) => {
                    self.advance()?;
                    break;
                }
                Some(Token { tok: Tok::Word(w), .. }) => {
                    let w = w.clone();
                    if self.statement_keyword(&w, depth)? {
                        continue;
                    }
                    let node = self.parse_node(depth)?;
                    root.get_or_insert(node);
                }
                _ => {
                    return Err(self.expected(&format!(
                        "a node or the `}}` that closes the body of PROTO `{name}` (opened at \
                         {}:{})",
                        open.line, open.column
                    )));
                }
            }
        }
        root.ok_or_else(|| {
            self.error(
                open,
                format!(
                    "the body of PROTO `{name}` has no node; a PROTO's body starts with the node \
                     its instances stand for (§4.8.3): add it"
                ),
            )
        })
    }

    /// The declarations of a PROTO (with default values) or an EXTERNPROTO (without), up to
    /// the closing `]`.
    fn parse_interface(
        &mut self,
        name: &str,
        defaults: bool,
        depth: usize,
    ) -> crate::Result<Vec<Decl>> {
        let mut decls = Vec::new();
        loop {
            let kind = match self.peek() {
                Some(Token { tok: Tok::CloseList, .. }) => {
                    self.advance()?;
                    return Ok(decls);
                }
                Some(Token { tok: Tok::Word(w), .. })
                    if matches!(w.as_str(), "eventIn" | "eventOut" | "field" | "exposedField") =>
                {
                    w.clone()
                }
                _ => {
                    return Err(self.expected(&format!(
                        "`field`, `exposedField`, `eventIn`, `eventOut` or the `]` that closes \
                         the interface of `{name}`"
                    )));
                }
            };
            self.advance()?;
            self.expect_word("a field type")?;
            let (field, _) = self.expect_word("a field name")?;
            let has_value = matches!(kind.as_str(), "field" | "exposedField");
            let default = if defaults && has_value {
                Some(Rc::new(self.parse_value(&field, depth)?))
            } else {
                None
            };
            decls.push(Decl { name: field, default, has_value });
        }
    }

    /// `EXTERNPROTO Name [ interface ] url` (§4.9): declared; only a `"#Name"` url, a PROTO
    /// of this file, is ever resolved (PROTOs are not read from other files).
    fn parse_externproto(&mut self) -> crate::Result<()> {
        let pos = self.here();
        self.advance()?;
        let (name, _) = self.expect_word("the name of the EXTERNPROTO")?;
        self.expect(Tok::OpenList, &format!("`[` and the interface of EXTERNPROTO `{name}`"))?;
        self.parse_interface(&name, false, 1)?;
        let urls = match self.peek() {
            Some(Token { tok: Tok::Str(_) | Tok::OpenList, .. }) => {
                match self.parse_value("url", 1)? {
                    Value::Strs(urls, _) => urls,
                    _ => Vec::new(),
                }
            }
            _ => return Err(self.expected(&format!("the url of EXTERNPROTO `{name}`"))),
        };
        let target = urls.iter().find_map(|u| u.strip_prefix('#')).map(str::to_string);
        let ext = Extern { name: name.clone(), pos, urls, target };
        self.scope().protos.insert(name, ProtoDef::Extern(Rc::new(ext)));
        Ok(())
    }

    /// The PROTO an instance of type `kind` stands for, searching the scopes from the
    /// innermost; `Err` when `kind` is a PROTO whose body is being read (§4.8.3).
    fn prototype(&self, kind: &str, pos: Pos) -> crate::Result<Option<Instance>> {
        if let Some(outer) = self.defining.iter().find(|d| d.name == kind) {
            return Err(self.recursion(kind, outer, pos, ""));
        }
        let found = self.scopes.iter().rev().find_map(|s| s.protos.get(kind)).cloned();
        Ok(match found {
            None => None,
            Some(ProtoDef::Local(proto)) => Some(Instance::Local(proto)),
            Some(ProtoDef::Extern(ext)) => {
                let target = ext.target.as_deref();
                if let Some(outer) = target.and_then(|t| self.defining.iter().find(|d| d.name == t))
                {
                    let via = format!(" through EXTERNPROTO `{kind}`");
                    return Err(self.recursion(&outer.name, outer, pos, &via));
                }
                let local = target.and_then(|t| {
                    match self.scopes.iter().rev().find_map(|s| s.protos.get(t)) {
                        Some(ProtoDef::Local(proto)) => Some(proto.clone()),
                        _ => None,
                    }
                });
                Some(match local {
                    Some(proto) => Instance::Local(proto),
                    None => Instance::External(ext),
                })
            }
        })
    }

    fn recursion(&self, kind: &str, outer: &Defining, pos: Pos, via: &str) -> SceneError {
        self.error(
            pos,
            format!(
                "PROTO `{kind}` (declared at {}:{}) is instantiated inside its own body{via}: \
                 a prototype cannot contain itself, directly or through another (§4.8.3), so \
                 it would never end; replace the inner instance with plain nodes",
                outer.pos.line, outer.pos.column
            ),
        )
    }

    /// An instance (§4.8.2): the PROTO's first body node, its `IS` fields given the
    /// instance's values or the declared defaults.
    fn instantiate(
        &mut self,
        instance: Instance,
        kind: &str,
        def: Option<String>,
        pos: Pos,
        fields: Vec<Field>,
        depth: usize,
    ) -> crate::Result<Rc<Node>> {
        let proto = match instance {
            Instance::Local(proto) => proto,
            Instance::External(ext) => {
                // Not in this file: kept as a node the walk notes, without its fields.
                let mut node = Node::new(kind.to_string(), def, pos, Vec::new(), 0);
                node.external = Some(ext);
                return Ok(Rc::new(node));
            }
        };
        let mut bindings = HashMap::new();
        for decl in &proto.decls {
            bindings.insert(decl.name.clone(), decl.default.clone());
        }
        for field in fields {
            match proto.decls.iter().find(|d| d.name == field.name) {
                Some(decl) if decl.has_value => {
                    bindings.insert(field.name, Some(field.value));
                }
                Some(_) => {} // an event: nothing to give a still image
                None => return Err(self.unknown_field(&proto, kind, &field)),
            }
        }
        self.check_height(depth, proto.root.height, pos, "PROTO expansions")?;
        // A chain of prototypes that each use the one before twice stands for 2^n copies:
        // refused before the first is made.
        let copies = self.expanded.saturating_add(proto.root.is_nodes);
        if copies > self.max_expanded {
            return Err(super::proto::too_many_copies(self, copies, pos));
        }
        let root = Expander::new(self, bindings, pos).expand(&proto.root)?;
        Ok(match def {
            Some(name) => Rc::new(super::proto::renamed(&root, name)),
            None => root,
        })
    }

    fn unknown_field(&self, proto: &Proto, kind: &str, field: &Field) -> SceneError {
        let names: Vec<String> = proto.decls.iter().map(|d| d.name.clone()).collect();
        self.error(
            field.pos,
            format!(
                "`{}`: PROTO `{kind}` (declared at {}:{}) has no such field (it has: {}); fix \
                 the name or declare the field in the PROTO",
                field.name,
                proto.pos.line,
                proto.pos.column,
                list_or_none(&names)
            ),
        )
    }
}

/// What an instance's type resolved to.
enum Instance {
    Local(Rc<Proto>),
    External(Rc<Extern>),
}

fn list_or_none(names: &[String]) -> String {
    if names.is_empty() { "none".to_string() } else { names.join(", ") }
}
