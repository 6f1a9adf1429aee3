//! Progress when nobody watches a terminal: a render whose standard error is a pipe (as under
//! `nohup`, in CI or a job scheduler) prints plain progress lines, and no ANSI codes.

mod common;
use common::*;
use std::process::Command;

fn render(dir: &std::path::Path, progress: &str) -> String {
    let scene = dir.join("aosta").join("aosta.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_restauro"))
        .args(["render", scene.to_str().unwrap(), "--in-process", "--spp", "1", "--progress"])
        .arg(progress)
        .arg("--out")
        .arg(dir.join(format!("out-{progress}")))
        // Lines every 10 ms, so that a render of a fraction of a second prints some.
        .env("RESTAURO_PROGRESS_INTERVAL_S", "0.01")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stderr).unwrap()
}

#[test]
fn a_render_in_a_log_prints_plain_progress_lines() {
    let dir = tempfile::tempdir().unwrap();
    let scene_dir = dir.path().join("aosta");
    let scene = scene_dir.to_str().unwrap();
    ok(&["scene", "aosta", "--out", scene, "--width", "480", "--height", "270"]);
    for mode in ["auto", "plain"] {
        let log = render(dir.path(), mode);
        let lines: Vec<&str> = log.lines().filter(|l| l.starts_with("restauro: render ")).collect();
        assert!(!lines.is_empty(), "{mode}: no progress line in {log:?}");
        assert!(lines.iter().all(|l| l.contains(" tiles (") && l.contains(" elapsed")), "{log}");
        // The last says the whole image is done.
        let last = lines.last().unwrap();
        assert!(last.contains("(100 %)"), "{mode}: {last}");
        assert!(!log.contains('\u{1b}'), "{mode}: ANSI codes in a log: {log:?}");
    }
    assert_eq!(render(dir.path(), "none"), "", "--progress none prints nothing");
}
