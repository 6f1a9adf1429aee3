//! What a file holds that restauro reads but does not draw, said once per kind of node with
//! the line of the first one and how many there are: never dropped silently, never ten
//! thousand lines for ten thousand lights.

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::rc::Rc;

use super::lexer::Pos;
use super::parser::{Node, Value};

/// At most this many kinds of node are noted one by one; the rest are counted in one note.
const MAX_KINDS: usize = 24;

/// Nodes with nothing to show in a still image (§6.29, §6.55, the sensors, interpolators and
/// sounds): no note.
const SILENT: [&str; 12] = [
    "WorldInfo",
    "NavigationInfo",
    "TimeSensor",
    "TouchSensor",
    "ProximitySensor",
    "VisibilitySensor",
    "CylinderSensor",
    "PlaneSensor",
    "SphereSensor",
    "Sound",
    "AudioClip",
    "Viewpoint",
];

#[derive(Debug)]
struct Entry {
    /// The inlined file the node is in (`None`: the world's own file).
    file: Option<Rc<Path>>,
    first: Pos,
    label: String,
    why: String,
    count: u64,
}

#[derive(Debug, Default)]
pub(super) struct Notes {
    entries: Vec<Entry>,
    by_label: HashMap<String, usize>,
    /// Nodes already noted, by address: a node `USE`d many times counts once.
    seen: HashSet<usize>,
    /// Nodes of the kinds past [`MAX_KINDS`].
    more: u64,
    /// The `Inline`d file being walked, if any: its nodes are noted with its name.
    pub file: Option<Rc<Path>>,
}

impl Notes {
    /// A node met among a group's children that is not a group, a Shape or a Viewpoint.
    pub fn child(&mut self, node: &Node) {
        let kind = node.kind.as_str();
        if SILENT.contains(&kind) || kind.ends_with("Interpolator") {
            return;
        }
        let why = match kind {
            "PointLight" | "SpotLight" | "DirectionalLight" => {
                "is not used: the lights of the file are ignored, restauro's lights come from \
                 the scene's [[lights]]; add the light there"
                    .to_string()
            }
            "Script" => "is not run: restauro renders one still instant, so what the script \
                         would change is not applied"
                .to_string(),
            "Inline" => format!(
                "is not drawn ({}): the file was read on its own; read it as a scene's mesh, \
                 which draws the files its Inlines name",
                urls(node)
            ),
            "Background" | "Fog" => "is not used: restauro's sky and atmosphere come from the \
                                     scene file"
                .to_string(),
            _ => return self.geometry(node),
        };
        self.add(node, node.kind.clone(), why);
    }

    /// A Shape's geometry that is not drawn, or a node that is not known at all.
    pub fn geometry(&mut self, node: &Node) {
        if let Some(ext) = &node.external {
            let why = format!(
                "(declared at line {}) is not drawn: its url ({}) is not fetched; inline the \
                 PROTO into this file, or give the EXTERNPROTO the url \"#{}\" of a PROTO of \
                 this file",
                ext.pos.line,
                quoted(&ext.urls),
                ext.name
            );
            return self.add(node, format!("EXTERNPROTO `{}`", ext.name), why);
        }
        let why = match node.kind.as_str() {
            "Text" => "is not drawn: restauro renders no text; model the lettering as faces if \
                       it matters"
                .to_string(),
            "IndexedLineSet" | "PointSet" => {
                "is not drawn: lines and points have no area to render".to_string()
            }
            _ => "is not a VRML97 node restauro draws here; it is skipped".to_string(),
        };
        self.add(node, node.kind.clone(), why);
    }

    /// An Appearance's texture (§6.22, §6.28, §6.33).
    pub fn texture(&mut self, node: &Node) {
        let why = "is ignored: surfaces are shaded with the scene's spectra (or the Material's \
                   diffuseColor), not with images";
        self.add(node, node.kind.clone(), why.to_string());
    }

    fn add(&mut self, node: &Node, label: String, why: String) {
        if !self.seen.insert(node as *const Node as usize) {
            return;
        }
        let key = match &self.file {
            Some(file) => format!("{}\0{label}", file.display()),
            None => label.clone(),
        };
        if let Some(&i) = self.by_label.get(&key) {
            let entry = &mut self.entries[i];
            entry.count += 1;
            if node.pos.line < entry.first.line {
                entry.first = node.pos;
            }
        } else if self.entries.len() < MAX_KINDS {
            self.by_label.insert(key, self.entries.len());
            let file = self.file.clone();
            self.entries.push(Entry { file, first: node.pos, label, why, count: 1 });
        } else {
            self.more += 1;
        }
    }

    /// The notes, in line order: `file.wrl:LINE: Kind is not drawn (…)`.
    pub fn lines(&self, path: &Path) -> Vec<String> {
        let mut entries: Vec<&Entry> = self.entries.iter().collect();
        entries.sort_by_key(|e| (e.file.clone(), e.first.line, e.first.column));
        let mut out: Vec<String> = entries
            .iter()
            .map(|e| {
                let count = if e.count > 1 {
                    format!(" ({} such nodes; the first is on this line)", e.count)
                } else {
                    String::new()
                };
                let file = e.file.as_deref().unwrap_or(path);
                format!("{}:{}: {} {}{count}", file.display(), e.first.line, e.label, e.why)
            })
            .collect();
        if self.more > 0 {
            out.push(format!(
                "{}: {} more nodes of other kinds are not drawn either",
                path.display(),
                self.more
            ));
        }
        out
    }

    /// The kinds noted, for a message: "Text (line 3), PointLight (line 5)".
    pub fn summary(&self) -> String {
        let kinds: Vec<String> =
            self.entries.iter().map(|e| format!("{} (line {})", e.label, e.first.line)).collect();
        kinds.join(", ")
    }
}

/// An Inline's urls, quoted.
fn urls(node: &Node) -> String {
    match node.field("url").map(|f| &*f.value) {
        Some(Value::Strs(urls, _)) if !urls.is_empty() => quoted(urls),
        _ => "no url".to_string(),
    }
}

fn quoted(urls: &[String]) -> String {
    let shown: Vec<String> = urls.iter().take(3).map(|u| format!("\"{u}\"")).collect();
    shown.join(" ")
}
