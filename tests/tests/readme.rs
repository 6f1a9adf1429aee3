//! The commands of the README and of the guides, run in order as a new user runs them, so that
//! every line stays true; and every link between those pages leads somewhere.
//!
//! Every ```sh block of the README and then of the guides ([`GUIDES`], in the order each guide
//! says it follows) is taken, in order, and run as one bash script in an empty folder (so a block
//! may use what an earlier one wrote, as the pages' order promises), with only these changes:
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

/// The pages whose commands run, in the order a reader follows them: the README first, then the
/// guides, each of which says what it builds on.
const GUIDES: [&str; 4] =
    ["README.md", "docs/restorers.md", "docs/lighting.md", "docs/operators.md"];

/// The pages whose links are followed: the guides, and every other page of `docs/`.
fn pages(root: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut pages: Vec<_> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    pages.sort();
    pages.insert(0, root.join("README.md"));
    pages
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

#[test]
fn every_readme_command_runs_in_order() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let lines: Vec<String> = GUIDES
        .iter()
        .flat_map(|page| shell_lines(&std::fs::read_to_string(root.join(page)).unwrap()))
        .collect();
    assert!(lines.len() > 20, "premise: the pages have their commands: {lines:?}");
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
        "the commands of the README and the guides failed:\n{}\n--- stdout\n{}\n--- stderr\n{}",
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

/// The GitHub anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown page's headings (outside code blocks).
fn anchors(text: &str) -> Vec<String> {
    let mut in_code = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code && line.starts_with('#') {
            out.push(anchor(line.trim_start_matches('#')));
        }
    }
    out
}

/// The relative links of a Markdown page: `](target)`, web addresses left out.
fn links(text: &str) -> Vec<String> {
    text.split("](")
        .skip(1)
        .filter_map(|rest| rest.split(')').next())
        .filter(|t| !t.starts_with("http://") && !t.starts_with("https://"))
        .map(str::to_owned)
        .collect()
}

/// Every link of the README and of `docs/` names a file of the checkout, and a heading of the
/// page where it names one, so that a reader sent somewhere finds it.
#[test]
fn every_link_between_the_pages_leads_somewhere() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut broken = Vec::new();
    for page in pages(&root) {
        let text = std::fs::read_to_string(&page).unwrap();
        for link in links(&text) {
            let (file, fragment) = link.split_once('#').unwrap_or((&link, ""));
            let target =
                if file.is_empty() { page.clone() } else { page.parent().unwrap().join(file) };
            if !target.exists() {
                broken.push(format!("{}: {link}: no such file", page.display()));
                continue;
            }
            let is_markdown = target.extension().is_some_and(|e| e == "md");
            if !fragment.is_empty() && is_markdown {
                let headings = anchors(&std::fs::read_to_string(&target).unwrap());
                if !headings.iter().any(|h| h == fragment) {
                    broken.push(format!("{}: {link}: no heading #{fragment}", page.display()));
                }
            }
        }
    }
    assert!(broken.is_empty(), "links that lead nowhere:\n{}", broken.join("\n"));
}

#[test]
fn anchors_are_made_as_github_makes_them() {
    assert_eq!(
        anchor(" What a person standing there sees: the seen image and display"),
        "what-a-person-standing-there-sees-the-seen-image-and-display"
    );
    assert_eq!(anchors("# A b\n```\n# not\n```\n## C-d_e"), ["a-b", "c-d_e"]);
    assert_eq!(
        links("[a](b.md#c) [w](https://x.org) ![i](images/p.png)"),
        ["b.md#c", "images/p.png"]
    );
}
