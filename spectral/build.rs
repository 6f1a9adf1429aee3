//! Embeds the shipped spectrum library (`data/spectra/*.csv` at the workspace root) into the
//! crate: one `(stem, text)` entry per file, sorted by stem, so that spectra can be named by
//! their file stem anywhere the program runs, without the repository beside it.

use std::io::Write;
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let dir = manifest.join("../data/spectra");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut entries: Vec<(String, PathBuf)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot read the spectrum library {}: {e}", dir.display()))
        .filter_map(|entry| {
            let path = entry.ok()?.path();
            let stem = path.file_stem()?.to_str()?.to_owned();
            // Files starting with `_` are catalogues, not spectra.
            (path.extension()? == "csv" && !stem.starts_with('_')).then_some((stem, path))
        })
        .collect();
    entries.sort();
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets it")).join("library.rs");
    let mut f = std::fs::File::create(&out).expect("write OUT_DIR/library.rs");
    writeln!(f, "pub(crate) static FILES: &[(&str, &str)] = &[").unwrap();
    for (stem, path) in &entries {
        let path = path.canonicalize().expect("library file path");
        writeln!(f, "    ({stem:?}, include_str!({:?})),", path.display().to_string()).unwrap();
    }
    writeln!(f, "];").unwrap();
}
