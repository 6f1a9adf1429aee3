//! The README's commands, run in order as a new user runs them, so that every line stays true.
//!
//! Every ```sh block of the README is taken, in order, and run as one bash script in an empty
//! folder (so a block may use what an earlier one wrote, as the README's order promises), with
//! only these changes:
//!
//! * `cargo run --release -p restauro --` is the `restauro` executable these tests were built
//!   with (the same code; a second, release build would take minutes);
//! * `cargo test --workspace` is skipped: it is the command running this test;
//! * sizes are reduced where a flag allows: `demo --quick`, `scene aosta` at 160×90, `--spp 1`;
//! * the cluster's port 7878 is a free port, and the studio's 7880 another, so that tests
//!   running at once do not collide;
//! * the checkout's `validation/` folder (scenes the README refers to) is copied into the
//!   folder first, as a user running the README from the checkout has it.
//!
//! A failing line fails the test with the script's output.

use restauro_tests::binary;
use std::process::Command;

/// The README's ```sh blocks, each line with its continuations joined.
fn shell_lines(readme: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut in_block = false;
    let mut pending = String::new();
    for line in readme.lines() {
        match (in_block, line.trim_start().starts_with("```")) {
            (false, true) => in_block = line.trim() == "```sh",
            (true, true) => in_block = false,
            (true, false) => {
                if let Some(head) = line.strip_suffix('\\') {
                    pending.push_str(head);
                    continue;
                }
                pending.push_str(line);
                lines.push(std::mem::take(&mut pending));
            }
            (false, false) => {}
        }
    }
    lines
}

/// One README line as the test runs it (see the module comment).
fn adapted(line: &str, (port, studio_port): (u16, u16)) -> Option<String> {
    let command = line.split('#').next().unwrap_or("").trim();
    if command.starts_with("cargo test") {
        return None;
    }
    let mut out = line.replace("cargo run --release -p restauro --", "\"$RESTAURO\"");
    out = out.replace("7878", &port.to_string());
    out = out.replace("7880", &studio_port.to_string());
    if command.contains(" -- demo") {
        out = out.replacen(" demo", " demo --quick", 1);
    }
    if command.contains(" scene aosta ") {
        out = out.replacen(" scene aosta ", " scene aosta --width 160 --height 90 ", 1);
    }
    Some(out.replace("--spp 16", "--spp 1"))
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

#[test]
fn every_readme_command_runs_in_order() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let lines = shell_lines(&readme);
    assert!(lines.len() > 20, "premise: the README has its commands: {lines:?}");
    let ports = (free_port(), free_port());
    let body: Vec<String> = lines.iter().filter_map(|l| adapted(l, ports)).collect();
    // Whatever the script leaves running (a coordinator it did not get to stop) is stopped.
    let script = format!(
        "set -euo pipefail\ntrap 'kill $(jobs -p) 2>/dev/null || true' EXIT\nset -x\n{}\n",
        body.join("\n")
    );
    let dir = tempfile::tempdir().unwrap();
    copy_folder(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../validation"),
        &dir.path().join("validation"),
    );
    let mut bash = Command::new("bash");
    bash.arg("-c")
        .arg(&script)
        .current_dir(dir.path())
        .env("RESTAURO", binary("restauro"))
        .env("RESTAURO_PROGRESS_INTERVAL_S", "30")
        .env_remove("RESTAURO_COORDINATOR")
        .env_remove("RESTAURO_TOKEN");
    let out = restauro_tests::output_within(&mut bash, restauro_tests::patience());
    assert!(
        out.status.success(),
        "the README's commands failed:\n{}\n--- stdout\n{}\n--- stderr\n{}",
        script,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // What the README says they write is there.
    for file in [
        "out/demo/report.md",
        "out/seen.png",
        "out/fixed.png",
        "out/aosta/aosta.toml",
        "out/render/aosta-as-found.exr",
        "out/cleaned/aosta-cleaned.exr",
        "out/as-found/aosta-as-found.exr",
        "out/hypotheses/compare-as-found-vs-cleaned/seen/compare.json",
        "out/compare/delta-e.png",
        "out/aosta.tar",
    ] {
        assert!(dir.path().join(file).is_file(), "{file} was not written");
    }
}

#[test]
fn the_runner_reads_blocks_and_continuations() {
    let readme = "text\n```sh\n# c\nfoo a \\\n  b\n```\n```toml\nx = 1\n```\n```sh\nbar\n```\n";
    assert_eq!(shell_lines(readme), ["# c", "foo a   b", "bar"]);
    assert_eq!(adapted("cargo test --workspace   # all", (1, 2)), None);
    assert_eq!(
        adapted("cargo run --release -p restauro -- demo   # x", (9, 10)).unwrap(),
        "\"$RESTAURO\" demo --quick   # x"
    );
}

/// Copies the folder `from` into `to`, recursively.
fn copy_folder(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_folder(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}
