//! The coordinator binary refuses to start without what it needs, and says what to give.

use std::process::Command;

#[test]
fn without_tokens_it_says_how_to_give_them() {
    let dir = tempfile::tempdir().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_restauro-coordinator"))
        .args(["--listen", "127.0.0.1:0", "--data"])
        .arg(dir.path())
        .env_remove("RESTAURO_CLIENT_TOKEN")
        .env_remove("RESTAURO_WORKER_TOKEN")
        .output()
        .unwrap();
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("give --client-token-file FILE or set RESTAURO_CLIENT_TOKEN"), "{err}");
}
