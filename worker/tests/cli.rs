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
