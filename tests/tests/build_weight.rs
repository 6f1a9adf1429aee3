//! The quick start's build stays light (issue 17, item 8: time to first image). A fresh machine
//! compiles every crate that `cargo run --release -p restauro` needs before the first image; the
//! cold build measured 4 min 26 s on two cores (`cargo build --release -p restauro --timings`
//! with an empty registry and target). Adding a dependency is allowed, but should be a
//! decision: this test names what was added when the count passes its budget.

use std::collections::BTreeSet;
use std::process::Command;

/// The crates (normal and build dependencies) of `restauro`: 239 when the budget was set.
const BUDGET: usize = 250;

/// What the running binaries must not compile in: a regex engine (tracing-subscriber's
/// `EnvFilter`; `Targets` parses RUST_LOG without one), C crypto or build systems that need
/// more than a C compiler.
const UNWANTED: [&str; 6] =
    ["regex-automata", "aws-lc-sys", "openssl-sys", "cmake", "bindgen", "native-tls"];

fn tree(edges: &str) -> BTreeSet<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let out = Command::new(cargo)
        .current_dir(root)
        .args(["tree", "-p", "restauro", "-e", edges, "--prefix", "none", "--locked", "--offline"])
        .output()
        .expect("cargo tree runs");
    assert!(out.status.success(), "cargo tree: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn the_quick_start_compiles_no_more_crates_than_its_budget() {
    let all = tree("normal,build");
    assert!(all.contains("restauro") && all.contains("tonic"), "{all:?}");
    assert!(
        all.len() <= BUDGET,
        "`restauro` now builds {} crates, over the budget of {BUDGET}: check what was added \
         (`cargo tree -p restauro -e normal,build`) and whether the quick start needs it",
        all.len()
    );
}

#[test]
fn the_binaries_carry_no_regex_engine_or_c_crypto() {
    let runtime = tree("normal");
    let found: Vec<_> = UNWANTED.iter().filter(|c| runtime.contains(**c)).collect();
    assert!(found.is_empty(), "the restauro binary now depends on {found:?}");
}
