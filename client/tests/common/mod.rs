//! Running the real `restauro` binary, as the command-line tests do.
#![allow(dead_code)] // each test file uses a different part

use std::process::{Command, Output};

pub fn restauro(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_restauro")).args(args).output().expect("run restauro")
}

/// Run, require success, return stdout.
pub fn ok(args: &[&str]) -> String {
    let out = restauro(args);
    assert!(out.status.success(), "{args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// The error a user sees: exit status 1, nothing on stdout, one `error:` line on stderr.
pub fn refused(args: &[&str]) -> String {
    refused_with(args, 1)
}

/// A value the command line itself refuses, before anything runs: exit status 2 (a usage
/// error), nothing on stdout, clap's `error:` naming the flag on stderr.
pub fn refused_usage(args: &[&str]) -> String {
    refused_with(args, 2)
}

/// A refusal with exit status `code`: nothing on stdout, an `error:` on stderr, no panic.
fn refused_with(args: &[&str], code: i32) -> String {
    let out = restauro(args);
    assert_eq!(out.status.code(), Some(code), "{args:?} should fail with status {code}");
    assert!(out.stdout.is_empty());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}
