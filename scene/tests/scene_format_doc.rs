//! `docs/scene-format.md` kept in step with the schema: every key and every keyword value of
//! `scene_file.rs` appears in it, every ```toml block in it parses as (part of) a scene, and
//! every whole scene in it passes the loader's checks with stand-in files.
//!
//! Where the names come from: the source of `scene/src/scene_file.rs`, not a list written here.
//! Serialising populated values would need a value of every type, and most have no `Default`
//! (their required fields have none); the test would then construct them by hand, and an
//! optional field filled with `None` would hide the keys of its type. Reading the source sees
//! every struct, every variant's keys and every keyword's spelling, with serde's renaming rules
//! applied as serde applies them. The reader refuses any serde attribute it does not know (an
//! `alias`, a `flatten`, a renaming rule it cannot apply) and any type of a key that the file
//! does not define, so that a change it cannot follow fails here instead of passing unseen.

use restauro_scene::assets::Assets;
use restauro_scene::load::{Limits, load, parse_scene};
use restauro_scene::scene_file::SceneFile;
use restauro_scene::{Result, SceneError};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const DOC: &str = "docs/scene-format.md";

fn read(relative: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn doc() -> String {
    read(&format!("../{DOC}"))
}

/// What a scene file may spell: the keys of its tables and the keywords of its values.
#[derive(Debug, Default)]
struct Schema {
    /// Keys, by the type that has them (`Light::Sun`, `Camera`, …).
    keys: BTreeMap<String, BTreeSet<String>>,
    /// Keyword values (`cook-torrance`, `full-moon`), by enum.
    keywords: BTreeMap<String, BTreeSet<String>>,
}

/// The names and arguments of a `#[serde(…)]` attribute: `rename_all = "kebab-case"` gives
/// `("rename_all", Some("kebab-case"))`, `untagged` gives `("untagged", None)`.
fn serde_args(attribute: &str) -> Vec<(String, Option<String>)> {
    let Some(inner) = attribute.strip_prefix("#[serde(").and_then(|a| a.strip_suffix(")]")) else {
        return Vec::new();
    };
    inner
        .split(',')
        .map(str::trim)
        .filter(|a| !a.is_empty())
        .map(|a| match a.split_once('=') {
            Some((k, v)) => (k.trim().to_owned(), Some(v.trim().trim_matches('"').to_owned())),
            None => (a.to_owned(), None),
        })
        .collect()
}

/// The serde attributes of an item or a field, checked against those this reader understands.
#[derive(Debug, Default)]
struct Serde {
    rename: Option<String>,
    rename_all: Option<String>,
    tag: Option<String>,
    untagged: bool,
    skip: bool,
}

impl Serde {
    fn from(attributes: &[String]) -> Self {
        let mut s = Serde::default();
        for (key, value) in attributes.iter().flat_map(|a| serde_args(a)) {
            match key.as_str() {
                "rename" => s.rename = value,
                "rename_all" => s.rename_all = value,
                "tag" => s.tag = value,
                "untagged" => s.untagged = true,
                "skip" | "skip_deserializing" => s.skip = true,
                // These change no name a scene file spells.
                "default"
                | "deny_unknown_fields"
                | "deserialize_with"
                | "with"
                | "skip_serializing"
                | "skip_serializing_if"
                | "serialize_with"
                | "bound" => {}
                other => panic!(
                    "scene_file.rs uses #[serde({other})], which this test cannot follow; teach \
                     `Serde::from` what names it makes"
                ),
            }
        }
        s
    }
}

/// A key (`max_depth`) or a variant (`CookTorrance`) as serde's `rename_all = rule` spells it;
/// keys are snake_case already, so only the rules that change them do.
fn renamed(name: &str, rule: &str, is_key: bool) -> String {
    let words: Vec<String> = if is_key {
        name.split('_').map(str::to_owned).collect()
    } else {
        let mut words = Vec::new();
        for c in name.chars() {
            if c.is_uppercase() || words.is_empty() {
                words.push(String::new());
            }
            words.last_mut().expect("a word").push(c.to_ascii_lowercase());
        }
        words
    };
    match rule {
        "lowercase" if is_key => name.to_owned(),
        "lowercase" => name.to_ascii_lowercase(),
        "snake_case" => words.join("_"),
        "kebab-case" => words.join("-"),
        other => {
            panic!("rename_all = \"{other}\" is not a rule this test applies; teach `renamed`")
        }
    }
}

/// The type names a key's type mentions (`Option<BTreeMap<String, Variant>>` → `Option`,
/// `BTreeMap`, `String`, `Variant`).
fn type_names(ty: &str) -> impl Iterator<Item = &str> {
    ty.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| w.chars().next().is_some_and(char::is_uppercase))
}

/// Splits `text` at the commas outside `<…>`, `[…]` and `(…)`: the `key: Type` pairs of a
/// struct variant written on one line.
fn top_level_commas(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut parts) = (0i32, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '<' | '[' | '(' => depth += 1,
            '>' | ']' | ')' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts.into_iter().map(str::trim).filter(|p| !p.is_empty()).collect()
}

/// `line` without a leading `pub`, `pub(crate)` or `pub(super)`.
fn without_visibility(line: &str) -> &str {
    match line.strip_prefix("pub") {
        Some(rest) if rest.starts_with('(') => rest.split_once(')').map_or(line, |(_, r)| r),
        Some(rest) if rest.starts_with(' ') => rest,
        _ => line,
    }
    .trim_start()
}

/// An attribute that starts on `first`, with the lines it continues on.
fn attribute<'a>(first: &str, lines: &mut impl Iterator<Item = &'a str>) -> String {
    let mut attribute = first.to_owned();
    while attribute.matches('[').count() > attribute.matches(']').count() {
        attribute.push_str(lines.next().expect("the attribute's end"));
    }
    attribute
}

/// What the schema reader gathers as it reads: the schema, every type defined, and (the type
/// that has the key, the key's type) pairs, checked once every type is known.
#[derive(Default)]
struct Reading {
    schema: Schema,
    defined: BTreeSet<String>,
    key_types: Vec<(String, String)>,
}

impl Reading {
    /// Adds the key of `key_and_type` (a member's line, `pub name: Type,`) to `owner`'s keys,
    /// spelt as serde spells it.
    fn add_key(&mut self, owner: &str, key_and_type: &str, spelling: &dyn Fn(&str) -> String) {
        let (key, ty) = without_visibility(key_and_type).split_once(':').expect("a key");
        let key = key.trim().trim_start_matches("r#");
        self.schema.keys.entry(owner.to_owned()).or_default().insert(spelling(key));
        self.key_types.push((owner.to_owned(), ty.trim().trim_end_matches([',', '{']).to_owned()));
    }
}

/// Reads the serde items of `source` (scene_file.rs): every struct and enum deriving
/// `Deserialize`, outside the test module. Members are one a line, as rustfmt writes them.
fn schema(source: &str) -> Schema {
    let source = source.split("#[cfg(test)]").next().expect("the text before the tests");
    let mut reading = Reading::default();

    // Comments dropped (doc comments say `key: value` too), blank lines skipped.
    let mut lines =
        source.lines().map(|l| l.split("//").next().unwrap_or("").trim()).filter(|l| !l.is_empty());
    let mut attributes: Vec<String> = Vec::new();
    while let Some(line) = lines.next() {
        if line.starts_with("#[") {
            attributes.push(attribute(line, &mut lines));
            continue;
        }
        let item = std::mem::take(&mut attributes);
        let words: Vec<&str> = without_visibility(line).split_whitespace().collect();
        let (kind, name) = match words.as_slice() {
            [kind @ ("struct" | "enum"), name, ..] => {
                (*kind, name.trim_end_matches(['{', '(', ';']).to_owned())
            }
            _ => continue,
        };
        reading.defined.insert(name.clone());
        let derives_deserialize =
            item.iter().any(|a| a.starts_with("#[derive(") && a.contains("Deserialize"));
        if !derives_deserialize || !line.ends_with('{') {
            continue; // a hand-written or key-less type (`Scale`), or no serde type at all
        }
        let container = Serde::from(&item);
        if let Some(tag) = &container.tag {
            reading.add_key(&name, &format!("{tag}: String"), &|key: &str| key.to_owned());
        }
        read_body(&mut reading, &mut lines, kind, &name, &container);
    }
    // A key whose type comes from elsewhere would hide that type's keys from this reader.
    let known = ["Option", "Vec", "BTreeMap", "String"];
    for (owner, ty) in &reading.key_types {
        for t in type_names(ty) {
            assert!(
                known.contains(&t) || reading.defined.contains(t),
                "{owner} has a key of type `{ty}`, and `{t}` is not defined in scene_file.rs; \
                 this test reads only that file, so teach it where `{t}` is"
            );
        }
    }
    reading.schema
}

/// Reads the body of the serde item `name` (a `kind`, struct or enum, whose container
/// attributes are `container`) up to its closing brace: members at depth 1, a struct variant's
/// keys at depth 2.
fn read_body<'a>(
    reading: &mut Reading,
    lines: &mut impl Iterator<Item = &'a str>,
    kind: &str,
    name: &str,
    container: &Serde,
) {
    let mut depth = 1;
    let mut member_attributes: Vec<String> = Vec::new();
    let mut variant: Option<String> = None;
    while let Some(line) = lines.next() {
        if line.starts_with("#[") {
            member_attributes.push(attribute(line, lines));
            continue;
        }
        let member = Serde::from(&std::mem::take(&mut member_attributes));
        let (opens, closes) = (line.matches('{').count(), line.matches('}').count());
        let word: String = line.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let key_spelling = |key: &str| match (&member.rename, &container.rename_all) {
            (Some(r), _) => r.clone(),
            (None, Some(rule)) if kind == "struct" => renamed(key, rule, true),
            _ => key.to_owned(),
        };
        match (kind, depth) {
            _ if member.skip => {}
            ("struct", 1) if line.contains(':') => reading.add_key(name, line, &key_spelling),
            ("enum", 2) if line.contains(':') => {
                let owner = format!("{name}::{}", variant.as_deref().unwrap_or("?"));
                reading.add_key(&owner, line, &key_spelling);
            }
            ("enum", 1) if !word.is_empty() => {
                assert!(
                    member.rename_all.is_none(),
                    "{name}::{word}: a variant's own rename_all is not followed by this test"
                );
                // An untagged enum's variants are told apart by their keys, not by a word.
                if !container.untagged {
                    let spelt = match (&member.rename, &container.rename_all) {
                        (Some(r), _) => r.clone(),
                        (None, Some(rule)) => renamed(&word, rule, false),
                        (None, None) => word.clone(),
                    };
                    reading.schema.keywords.entry(name.to_owned()).or_default().insert(spelt);
                }
                // `Mix { mix: Vec<MixPart> },`: a struct variant on one line.
                if let (Some(a), Some(b)) = (line.find('{'), line.rfind('}')) {
                    let owner = format!("{name}::{word}");
                    for pair in top_level_commas(&line[a + 1..b]) {
                        reading.add_key(&owner, pair, &|key: &str| key.to_owned());
                    }
                }
                variant = Some(word.clone());
            }
            _ => {}
        }
        depth = depth + opens - closes;
        if depth == 0 {
            break;
        }
    }
}

fn the_schema() -> Schema {
    schema(&read("src/scene_file.rs"))
}

/// The reader finds what the schema is known to hold; if it found nothing, every check below
/// would pass.
#[test]
fn the_schema_reader_finds_the_schema() {
    let s = the_schema();
    let has = |owner: &str, key: &str| s.keys.get(owner).is_some_and(|k| k.contains(key));
    assert!(has("SceneFile", "format") && has("SceneFile", "variants"), "{s:#?}");
    assert!(has("Camera", "vertical_fov_deg") && has("ViewpointRef", "index"), "{s:#?}");
    assert!(has("Light", "kind") && has("Light::Spot", "falloff_deg"), "{s:#?}");
    assert!(has("Light::Sun", "site") && has("SiteTime", "datetime"), "{s:#?}");
    assert!(has("SpectrumSource::File", "extrapolate") && has("MixPart", "weight"), "{s:#?}");
    let word = |e: &str, w: &str| s.keywords.get(e).is_some_and(|k| k.contains(w));
    assert!(word("MaterialModel", "cook-torrance") && word("SunPreset", "full-moon"), "{s:#?}");
    assert!(word("Light", "sky") && word("Integrator", "whitted") && word("UpAxis", "y"));
    assert!(!s.keywords.contains_key("SpectrumSource"), "untagged: its variants are no words");
}

/// Every key of the schema is written in the document as `key`.
#[test]
fn every_key_of_the_schema_is_documented() {
    let doc = doc();
    let missing: Vec<String> = the_schema()
        .keys
        .iter()
        .flat_map(|(owner, keys)| keys.iter().map(move |k| (owner, k)))
        .filter(|(_, k)| !doc.contains(&format!("`{k}`")))
        .map(|(owner, k)| format!("`{k}` (of {owner})"))
        .collect();
    assert!(missing.is_empty(), "{DOC} does not document {}", missing.join(", "));
}

/// Every keyword a value may be (`"cook-torrance"`, `"full-moon"`) is written in the document,
/// as `word` or `"word"`.
#[test]
fn every_keyword_of_the_schema_is_documented() {
    let doc = doc();
    let missing: Vec<String> = the_schema()
        .keywords
        .iter()
        .flat_map(|(owner, words)| words.iter().map(move |w| (owner, w)))
        .filter(|(_, w)| !doc.contains(&format!("`{w}`")) && !doc.contains(&format!("`\"{w}\"`")))
        .map(|(owner, w)| format!("\"{w}\" (of {owner})"))
        .collect();
    assert!(missing.is_empty(), "{DOC} does not document {}", missing.join(", "));
}

/// The ```toml blocks of a Markdown text, with the line each starts on.
fn toml_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        match (&mut current, line.trim_start().starts_with("```")) {
            (None, true) if line.trim() == "```toml" => current = Some((i + 1, String::new())),
            (Some(_), true) => blocks.push(current.take().expect("a block")),
            (Some((_, text)), false) => {
                text.push_str(line);
                text.push('\n');
            }
            _ => {}
        }
    }
    assert!(current.is_none(), "{DOC}: a ```toml block is not closed");
    blocks
}

/// A whole scene: it says which format it is.
fn is_whole_scene(text: &str) -> bool {
    text.lines().any(|l| l.trim_start().starts_with("format ="))
}

/// Stand-ins for the files a whole example names, so that the loader checks everything else: a
/// mesh with the parts the scene refers to, a flat spectrum, a shipped photometric test file.
struct StandIns {
    name: PathBuf,
    /// Per mesh reference, the part names the scene refers to.
    parts: BTreeMap<String, BTreeSet<String>>,
}

impl StandIns {
    fn new(file: &SceneFile, name: PathBuf) -> Self {
        let mut parts: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        let mesh_of = |object: &str| file.objects.iter().find(|o| o.name == object);
        for o in &file.objects {
            parts.entry(o.mesh.clone()).or_default().extend(o.materials.keys().cloned());
            if let Some(r) = &o.replaces
                && let Some(target) = mesh_of(&r.object)
            {
                parts.entry(target.mesh.clone()).or_default().extend(r.groups.iter().cloned());
            }
        }
        for v in file.variants.values() {
            for key in v.states.keys() {
                if let Some((object, part)) = key.split_once('/')
                    && let Some(o) = mesh_of(object)
                {
                    parts.entry(o.mesh.clone()).or_default().insert(part.to_owned());
                }
            }
        }
        Self { name, parts }
    }

    /// An OBJ with one triangle for each part (`default` when the scene names none).
    fn obj(&self, reference: &str) -> String {
        let mut text = String::new();
        let parts = self.parts.get(reference).cloned().unwrap_or_default();
        let parts: Vec<Option<String>> =
            if parts.is_empty() { vec![None] } else { parts.into_iter().map(Some).collect() };
        for (k, part) in parts.iter().enumerate() {
            let x = k as f64;
            text += &format!("v {x} 0 0\nv {} 0 0\nv {x} 0 1\n", x + 1.0);
            if let Some(p) = part {
                text += &format!("usemtl {p}\n");
            }
            text += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
        }
        text
    }
}

impl Assets for StandIns {
    fn read(&self, reference: &str, place: &str) -> Result<Vec<u8>> {
        let photometric = |name: &str| read(&format!("tests/data/photometric/{name}"));
        let text = match restauro_scene::assets::extension(reference).as_str() {
            "obj" => self.obj(reference),
            "csv" => "wavelength_nm,value\n380,0.5\n780,0.5\n".to_owned(),
            "ies" => photometric("isotropic_1000cd.ies"),
            "ldt" => photometric("ldt_isym1_absolute.ldt"),
            other => {
                return Err(SceneError::invalid(
                    &self.name,
                    place,
                    format!(
                        "the test has no stand-in for a `.{other}` file; name .obj, .csv, .ies \
                         or .ldt files in whole-scene examples, or add a stand-in"
                    ),
                ));
            }
        };
        Ok(text.into_bytes())
    }

    fn scene_path(&self) -> &Path {
        &self.name
    }
}

/// What a snippet is written after: the least a scene must have to parse. A snippet with its own
/// `[camera]` is written after the first line only.
const BASE: &str = r#"format = 1
[camera]
position = [0.0, -10.0, 1.6]
target = [0.0, 0.0, 1.6]
width = 64
height = 48
"#;

/// Every ```toml block parses: a whole scene (it has `format =`) with the loader's own parser,
/// then through every check of the loader with stand-in files; a snippet after a minimal scene,
/// with the same parser, so that a key the schema does not have, a misspelt keyword or a wrong
/// type fails here. (Snippets are not checked further: they name spectra and materials that
/// only a whole scene defines.) Failures are reported at their line in the document.
#[test]
fn every_toml_example_parses_as_a_scene() {
    let blocks = toml_blocks(&doc());
    assert!(blocks.len() >= 10, "{DOC} has only {} ```toml blocks", blocks.len());
    let mut whole = 0;
    let mut failures = Vec::new();
    for (fence, block) in &blocks {
        let name = PathBuf::from(format!("{DOC}, the block at line {fence}"));
        let (text, prefix) = if is_whole_scene(block) {
            whole += 1;
            (block.clone(), "")
        } else {
            let own_camera =
                toml::from_str::<toml::Table>(block).is_ok_and(|t| t.contains_key("camera"));
            let prefix = if own_camera { BASE.lines().next().expect("a line") } else { BASE };
            (format!("{}\n{block}", prefix.trim_end()), prefix.trim_end())
        };
        let outcome = parse_scene(&text, &name).and_then(|file| {
            if !prefix.is_empty() {
                return Ok(());
            }
            let stand_ins = StandIns::new(&file, name.clone());
            load(file, &stand_ins, &Limits::default()).map(drop)
        });
        match outcome {
            Ok(()) => {}
            // The line in the document: the block's lines start after its fence.
            Err(SceneError::Syntax { line, column, problem, .. }) => {
                let line = fence + line - prefix.lines().count();
                failures.push(format!("{DOC}:{line}:{column}: {problem}"));
            }
            Err(e) => failures.push(e.to_string()),
        }
    }
    assert!(whole >= 2, "{DOC} should hold a minimal and a complete scene; it holds {whole}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The reader of this test: keys of structs and struct variants, renamed keywords, the tag,
/// and a refusal of what it does not follow.
#[test]
fn the_schema_reader_follows_serde_renaming() {
    let source = r#"
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lamp {
    /// A doc comment: with a colon.
    pub power_w: f64,
    #[serde(rename = "colour")]
    pub color: Option<Vec<Shade>>,
    #[serde(skip)]
    pub cache: u32,
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum Shade {
    WarmWhite,
    #[serde(rename = "blue")]
    Cold { kelvin: f64 },
}

#[derive(Deserialize)]
pub(crate) struct Hidden {
    #[serde(
        default,
        rename = "shown"
    )]
    pub(crate) hidden: bool,
}
"#;
    let s = schema(source);
    let keys = |owner: &str| s.keys[owner].iter().cloned().collect::<Vec<_>>();
    assert_eq!(keys("Lamp"), ["colour", "power_w"]);
    assert_eq!(keys("Shade"), ["type"]);
    assert_eq!(keys("Shade::Cold"), ["kelvin"]);
    assert_eq!(s.keywords["Shade"].iter().collect::<Vec<_>>(), ["blue", "warm-white"]);
    assert_eq!(keys("Hidden"), ["shown"]);
    let alias =
        "#[derive(Deserialize)]\npub struct A {\n    #[serde(alias = \"b\")]\n    pub a: u32,\n}\n";
    assert!(std::panic::catch_unwind(|| schema(alias)).is_err(), "an alias is refused");
    let foreign = "#[derive(Deserialize)]\npub struct A {\n    pub a: Option<Elsewhere>,\n}\n";
    assert!(std::panic::catch_unwind(|| schema(foreign)).is_err(), "a foreign type is refused");
}
