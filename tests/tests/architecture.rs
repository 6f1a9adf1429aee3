//! The architecture page is the workspace: its crate table names every member, each crate's
//! folder and the restauro crates it uses, as the `Cargo.toml` files say; dependencies point one
//! way, down the table; and the scene model and the tracer build without a network stack.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn toml_of(path: &Path) -> toml::Table {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.parse().unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// One row of the page's crate table.
#[derive(Debug)]
struct Row {
    name: String,
    folder: String,
    uses: BTreeSet<String>,
}

/// The rows of the table under `## The crates` in `docs/architecture.md`, in order.
fn table() -> Vec<Row> {
    let page = std::fs::read_to_string(root().join("docs/architecture.md")).unwrap();
    let section = page.split("## The crates").nth(1).expect("the page has `## The crates`");
    section
        .lines()
        .skip_while(|l| !l.starts_with("| crate |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|line| {
            let cells: Vec<&str> = line.trim_matches('|').split(" | ").map(str::trim).collect();
            assert_eq!(cells.len(), 4, "a row has crate, folder, role and uses: {line}");
            let uses = match cells[3] {
                "—" => BTreeSet::new(),
                list => list.split(", ").map(str::to_owned).collect(),
            };
            Row { name: cells[0].to_owned(), folder: cells[1].trim_matches('`').to_owned(), uses }
        })
        .collect()
}

/// The restauro crates a member's `[dependencies]` name.
fn restauro_dependencies(manifest: &toml::Table) -> BTreeSet<String> {
    manifest
        .get("dependencies")
        .and_then(|d| d.as_table())
        .map(|d| d.keys().filter(|k| k.starts_with("restauro")).cloned().collect())
        .unwrap_or_default()
}

#[test]
fn the_crate_table_is_the_workspace() {
    let rows = table();
    assert!(rows.len() >= 10, "premise: the table has its rows: {rows:?}");
    let workspace = toml_of(&root().join("Cargo.toml"));
    let members: BTreeSet<String> = workspace["workspace"]["members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| format!("{}/", m.as_str().unwrap()))
        .collect();
    let folders: BTreeSet<String> = rows.iter().map(|r| r.folder.clone()).collect();
    assert_eq!(folders, members, "the table's folders are the workspace's members");

    let mut above = BTreeSet::new();
    for row in &rows {
        let manifest = toml_of(&root().join(&row.folder).join("Cargo.toml"));
        assert_eq!(manifest["package"]["name"].as_str(), Some(row.name.as_str()), "{row:?}");
        let uses = restauro_dependencies(&manifest);
        assert_eq!(uses, row.uses, "{}: the restauro crates its Cargo.toml uses", row.name);
        let below: Vec<_> = uses.difference(&above).collect();
        assert!(below.is_empty(), "{} uses {below:?}, which the table puts below it", row.name);
        above.insert(row.name.clone());
    }
}

/// Every package `name` depends on, however deep, by `Cargo.lock` (which lists each package's
/// dependencies as the build resolved them, its tests' too).
fn closure(lock: &toml::Table, name: &str) -> BTreeSet<String> {
    let packages: BTreeMap<String, Vec<String>> = lock["package"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let deps =
                p.get("dependencies").and_then(|d| d.as_array()).cloned().unwrap_or_default();
            let deps = deps
                .iter()
                .map(|d| d.as_str().unwrap().split(' ').next().unwrap().to_owned())
                .collect();
            (p["name"].as_str().unwrap().to_owned(), deps)
        })
        .collect();
    let mut seen = BTreeSet::new();
    let mut todo = vec![name.to_owned()];
    while let Some(next) = todo.pop() {
        for dep in packages.get(&next).into_iter().flatten() {
            if seen.insert(dep.clone()) {
                todo.push(dep.clone());
            }
        }
    }
    seen
}

#[test]
fn the_scene_model_and_the_tracer_build_without_a_network_stack() {
    let lock = toml_of(&root().join("Cargo.lock"));
    assert!(
        closure(&lock, "restauro-assets").contains("tokio"),
        "premise: the lock file shows what fetching files by URL builds"
    );
    for name in ["restauro-spectral", "restauro-scene", "restauro-render"] {
        let network: Vec<_> = closure(&lock, name)
            .into_iter()
            .filter(|d| ["tokio", "hyper", "rustls", "tonic", "h2"].contains(&d.as_str()))
            .collect();
        assert!(network.is_empty(), "{name} builds {network:?}");
    }
}
