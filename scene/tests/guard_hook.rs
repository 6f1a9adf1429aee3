//! The panic guard keeps a parser's panic message off the user's terminal, and only that one:
//! checked in a child process (this test binary run again), whose stderr is what a user would
//! see.

use restauro_scene::guard;
use std::process::Command;

const CHILD: &str = "RESTAURO_GUARD_HOOK_CHILD";

/// In the child: one panic inside the guard, one outside it.
#[test]
fn child_panics_inside_and_outside_the_guard() {
    if std::env::var_os(CHILD).is_none() {
        return;
    }
    let inside: Result<(), guard::Panicked> = guard::catch(|| panic!("SECRET-PARSER-INTERNALS"));
    assert_eq!(inside, Err(guard::Panicked));
    let outside = std::panic::catch_unwind(|| panic!("VISIBLE-ELSEWHERE"));
    assert!(outside.is_err());
}

#[test]
fn the_hook_hides_guarded_panics_and_only_those() {
    let output = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "child_panics_inside_and_outside_the_guard", "--nocapture"])
        .args(["--test-threads", "1"])
        .env(CHILD, "1")
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "child failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("1 passed"), "the child test did not run:\n{stdout}");
    assert!(!stderr.contains("SECRET-PARSER-INTERNALS"), "a guarded panic was printed:\n{stderr}");
    assert!(stderr.contains("VISIBLE-ELSEWHERE"), "an unguarded panic was hidden:\n{stderr}");
}
