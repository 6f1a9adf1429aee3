//! The worker binary refuses to start without what it needs, and says what to give.
//!
//! These also make `cargo test --workspace` build the worker binary, which the cluster tests
//! in `tests/` start as a real process.

use std::process::Command;

fn worker() -> Command {
    let mut run = Command::new(env!("CARGO_BIN_EXE_restauro-worker"));
    run.env_remove("RESTAURO_WORKER_TOKEN")
        .env_remove("RESTAURO_COORDINATOR")
        .env("RUST_BACKTRACE", "0");
    run
}

#[test]
fn without_a_token_it_says_how_to_give_one() {
    let run = worker().args(["--coordinator", "http://127.0.0.1:1"]).output().unwrap();
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("give --token-file FILE or set RESTAURO_WORKER_TOKEN"), "{err}");
}

#[test]
fn a_coordinator_address_that_is_no_url_is_refused_with_the_form_to_use() {
    let run = worker()
        .args(["--coordinator", "not a url"])
        .env("RESTAURO_WORKER_TOKEN", "a-token")
        .output()
        .unwrap();
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("coordinator URL `not a url`"), "{err}");
    assert!(err.contains("use http://HOST:PORT"), "{err}");
}

/// What the worker logs in about a second while its coordinator is unreachable, with `RUST_LOG`
/// set to `filter`, standard error being a file (not a terminal).
fn log_for(filter: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("worker.log");
    let file = std::fs::File::create(&path).unwrap();
    let mut child = worker()
        .args(["--coordinator", "http://127.0.0.1:1"])
        .env("RESTAURO_WORKER_TOKEN", "a-token")
        .env("RUST_LOG", filter)
        .stderr(file)
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1200));
    let _ = child.kill();
    let _ = child.wait();
    std::fs::read_to_string(&path).unwrap()
}

#[test]
fn logs_to_a_file_are_plain_text_filtered_by_rust_log() {
    let log = log_for("");
    assert!(log.contains("WARN") && log.contains("cannot reach the coordinator"), "{log}");
    assert!(!log.contains('\u{1b}'), "colour codes in a log file: {log:?}");
    // A level, and a level per target, filter it.
    assert_eq!(log_for("error"), "");
    assert_eq!(log_for("warn,restauro_worker=error"), "");
    assert!(log_for("error,restauro_worker=warn").contains("cannot reach"));
    // A filter that does not parse is named, with the form to use, and the default applies.
    let log = log_for("restauro_worker=loud");
    assert!(log.contains("RUST_LOG `restauro_worker=loud` ignored"), "{log}");
    assert!(
        log.contains("e.g. warn,restauro_worker=debug") && log.contains("cannot reach"),
        "{log}"
    );
}
