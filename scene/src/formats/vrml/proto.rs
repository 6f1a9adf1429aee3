//! Prototypes (§4.8, §4.9): declarations, scopes, and the expansion of an instance into the
//! nodes of the PROTO's body.
//!
//! An instance is expanded when it is read: the body's first node is copied, with each field
//! that `IS` a PROTO field given the instance's value (or the declared default). Only the
//! nodes with an `IS` in or below them are copied; the rest of the body is shared by every
//! instance, and the nodes copied are counted against `max_instances`, so a chain of
//! prototypes that each use the one before twice cannot fill memory. A `DEF`/`USE` pair inside
//! a body is copied once per instance (the copies are remembered by the node they copy), so
//! each instance's `USE` refers to its own `DEF`.

use std::collections::HashMap;
use std::rc::Rc;

use super::lexer::Pos;
use super::parser::{Field, Node, Parser, Value};
use crate::error::SceneError;

/// One declaration of a PROTO's or EXTERNPROTO's interface.
#[derive(Debug)]
pub(super) struct Decl {
    pub name: String,
    /// The default of a `field`/`exposedField` of a PROTO.
    pub default: Option<Rc<Value>>,
    /// `field` or `exposedField` (rather than an event, which has no value).
    pub has_value: bool,
}

#[derive(Debug)]
pub(super) struct Proto {
    pub pos: Pos,
    pub decls: Vec<Decl>,
    /// The body's first node (§4.8.3).
    pub root: Rc<Node>,
}

/// An EXTERNPROTO (§4.9; its interface is read and not kept): its name, its urls and, for a url `"#Name"`, the PROTO of this file
/// it names.
#[derive(Debug)]
pub(super) struct Extern {
    pub name: String,
    pub pos: Pos,
    pub urls: Vec<String>,
    pub target: Option<String>,
}

#[derive(Clone, Debug)]
pub(super) enum ProtoDef {
    Local(Rc<Proto>),
    Extern(Rc<Extern>),
}

/// The names one scope declares (§4.6.2, §4.8.3): the file, or one PROTO body.
#[derive(Debug, Default)]
pub(super) struct Scope {
    pub defs: HashMap<String, Rc<Node>>,
    pub protos: HashMap<String, ProtoDef>,
}

/// Copies a PROTO body for one instance.
pub(super) struct Expander<'p, 'a> {
    parser: &'p mut Parser<'a>,
    /// Each field's value: `None` for a field with no value (an event), which is dropped.
    bindings: HashMap<String, Option<Rc<Value>>>,
    /// The copy made of each body node, by address.
    copies: HashMap<usize, Rc<Node>>,
    /// Where the instance is, for messages.
    at: Pos,
}

impl<'p, 'a> Expander<'p, 'a> {
    pub fn new(
        parser: &'p mut Parser<'a>,
        bindings: HashMap<String, Option<Rc<Value>>>,
        at: Pos,
    ) -> Self {
        Expander { parser, bindings, copies: HashMap::new(), at }
    }

    /// `node` for this instance: itself when nothing in it depends on the PROTO's fields.
    /// Recurses once per level of the body, which [`Node::height`] keeps within MAX_DEPTH.
    pub fn expand(&mut self, node: &Rc<Node>) -> crate::Result<Rc<Node>> {
        if !node.has_is {
            return Ok(node.clone());
        }
        let key = Rc::as_ptr(node) as usize;
        if let Some(copy) = self.copies.get(&key) {
            return Ok(copy.clone());
        }
        self.count()?;
        let mut fields = Vec::with_capacity(node.fields.len());
        for field in &node.fields {
            let value = match &*field.value {
                Value::Is(name) => match self.bindings.get(name) {
                    Some(Some(value)) => value.clone(),
                    _ => continue, // an event, or nothing: the node's own default applies
                },
                Value::Nodes(nodes) if nodes.iter().any(|n| n.has_is) => {
                    let copies: crate::Result<Vec<Rc<Node>>> =
                        nodes.iter().map(|n| self.expand(n)).collect();
                    Rc::new(Value::Nodes(copies?))
                }
                _ => field.value.clone(),
            };
            fields.push(Field { name: field.name.clone(), pos: field.pos, value });
        }
        // A Shape copied for this instance may differ from the others (its material can be a
        // field of the PROTO), so it gets a number, and a default name, of its own.
        let ordinal = if node.kind == "Shape" {
            self.parser.shapes += 1;
            self.parser.shapes
        } else {
            node.ordinal
        };
        let mut copy = Node::new(node.kind.clone(), node.def.clone(), node.pos, fields, ordinal);
        copy.external = node.external.clone();
        let copy = Rc::new(copy);
        self.copies.insert(key, copy.clone());
        Ok(copy)
    }

    /// One more node made by expansion, within the limit.
    fn count(&mut self) -> crate::Result<()> {
        self.parser.expanded += 1;
        if self.parser.expanded > self.parser.max_expanded {
            return Err(too_many_copies(self.parser, self.parser.expanded, self.at));
        }
        Ok(())
    }
}

/// The error for expansions past `max_instances`, naming the instance at `at`.
pub(super) fn too_many_copies(parser: &Parser, copies: u64, at: Pos) -> SceneError {
    SceneError::Limit {
        path: parser.path.to_path_buf(),
        what: format!(
            "the number of nodes made by expanding PROTO instances (with the one at {}:{})",
            at.line, at.column
        ),
        value: copies,
        limit: parser.max_expanded,
        fix: format!(
            "use fewer nested PROTO instances (or have the exporter expand them), or raise \
             --max-instances (expansions may copy one node per {} instances allowed)",
            super::parser::EXPANSION_SHARE
        ),
    }
}

/// A node named `def` (the instance's `DEF`), otherwise the same: its fields are shared.
pub(super) fn renamed(node: &Node, def: String) -> Node {
    let fields = node
        .fields
        .iter()
        .map(|f| Field { name: f.name.clone(), pos: f.pos, value: f.value.clone() })
        .collect();
    let mut copy = Node::new(node.kind.clone(), Some(def), node.pos, fields, node.ordinal);
    copy.external = node.external.clone();
    copy
}
