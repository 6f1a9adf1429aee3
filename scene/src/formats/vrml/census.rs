//! How much a file expands to, counted before anything is built.

use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

use super::MAX_DEPTH;
use super::lexer::Pos;
use super::parser::{Node, Value};
use super::primitives;
use crate::error::SceneError;
use crate::limits::Limits;

pub(super) const TRIANGLES_FIX: &str = "simplify the model or split it into several files, or \
                                        raise the limit with --max-triangles";

pub(super) fn instances_limit(path: &Path, value: u64, limit: u64) -> SceneError {
    SceneError::Limit {
        path: path.to_path_buf(),
        what: "the number of node instances (counting USE copies)".to_string(),
        value,
        limit,
        fix: "use fewer nested USEs of large groups, or raise the limit with --max-instances"
            .to_string(),
    }
}

/// A node nested deeper than [`MAX_DEPTH`] once `USE` copies are counted: the census refuses
/// it, and the walk has the same backstop.
pub(super) fn depth_limit(path: &Path, pos: Pos, depth: usize) -> SceneError {
    SceneError::Limit {
        path: path.to_path_buf(),
        what: format!(
            "the nesting depth of nodes (with USE copies) at {}:{}",
            pos.line, pos.column
        ),
        value: depth as u64,
        limit: MAX_DEPTH as u64,
        fix: "flatten the scene graph (fewer nested Transforms, Groups and USEs)".to_string(),
    }
}

/// How much a node expands to, counting every `USE` copy, worked out once per node (a `USE`
/// shares the node it names): the instances the walk will visit and an upper bound on the
/// triangles it will make (a face of n corners makes at most n − 2; a primitive what its
/// tessellation makes). A few hundred bytes of `DEF`/`USE` can stand for 2^40 instances, and
/// a few bytes of `ElevationGrid` for 10^10 triangles; counting first refuses such a file at
/// once, where building it would take hours or all the memory.
pub(super) struct Census<'a> {
    path: &'a Path,
    limits: &'a Limits,
    counted: HashMap<usize, (u64, u64)>,
}

impl<'a> Census<'a> {
    pub fn new(path: &'a Path, limits: &'a Limits) -> Self {
        Self { path, limits, counted: HashMap::new() }
    }

    pub fn check(&mut self, roots: &[Rc<Node>]) -> crate::Result<()> {
        let (mut instances, mut triangles) = (0u64, 0u64);
        for root in roots {
            let (i, t) = self.count(root, 1)?;
            instances = instances.saturating_add(i);
            triangles = triangles.saturating_add(t);
        }
        if instances > self.limits.max_instances {
            return Err(instances_limit(self.path, instances, self.limits.max_instances));
        }
        if triangles > self.limits.max_triangles {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: "the number of triangles (counting USE copies)".to_string(),
                value: triangles,
                limit: self.limits.max_triangles,
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
            return Err(depth_limit(self.path, node.pos, depth));
        }
        let below: Vec<Rc<Node>> = match node.kind.as_str() {
            "Transform" | "Group" | "Anchor" | "Billboard" | "Collision" => {
                node.nodes("children").to_vec()
            }
            // Whichever choice is drawn, at most all of them.
            "Switch" => node.nodes("choice").to_vec(),
            // Every level is kept (the render chooses one).
            "LOD" => node.nodes("level").to_vec(),
            _ => Vec::new(),
        };
        let (mut instances, mut triangles) = (1u64, 0u64);
        if node.kind == "Shape"
            && let Some(geometry) = node.first_node("geometry")
        {
            triangles = self.geometry(geometry)?;
        }
        for child in &below {
            let (i, t) = self.count(child, depth + 1)?;
            instances = instances.saturating_add(i);
            triangles = triangles.saturating_add(t);
        }
        self.counted.insert(key, (instances, triangles));
        Ok((instances, triangles))
    }

    /// The most triangles one geometry node makes; one that alone exceeds the limit is
    /// refused by its place.
    fn geometry(&self, geometry: &Node) -> crate::Result<u64> {
        let (triangles, how) = match geometry.kind.as_str() {
            "IndexedFaceSet" => match geometry.field("coordIndex").map(|f| &*f.value) {
                Some(Value::Nums(index, _)) => {
                    let ends = index.iter().filter(|&&n| n == -1.0).count() as u64;
                    let corners = index.len() as u64 - ends;
                    (corners.saturating_sub(2 * ends), "its coordIndex")
                }
                _ => (0, ""),
            },
            _ => primitives::triangle_bound(geometry).unwrap_or_default(),
        };
        if triangles > self.limits.max_triangles {
            return Err(SceneError::Limit {
                path: self.path.to_path_buf(),
                what: format!(
                    "the number of triangles of the {} at {}:{} ({how})",
                    geometry.kind, geometry.pos.line, geometry.pos.column
                ),
                value: triangles,
                limit: self.limits.max_triangles,
                fix: format!("make the {} smaller, or {TRIANGLES_FIX}", geometry.kind),
            });
        }
        Ok(triangles)
    }
}
