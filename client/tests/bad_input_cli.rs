//! Hostile input through the real binary (issue 15): what the user sees is one `error:` line
//! naming the file, the place and the fix — no NaN printed with exit status 0, no wait on a
//! FIFO, no panic, no message said twice.

mod common;
use common::*;

use restauro_image::image_files::{XyzImage, write_xyz_exr};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Run restauro, killing it if it has not finished within `seconds`; its stderr.
fn refused_within(seconds: u64, args: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_restauro"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(seconds);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("restauro {args:?} did not finish within {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(1), "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: ") && !stderr.contains("panicked"), "{stderr}");
    stderr
}

#[test]
fn an_illuminant_whose_products_overflow_is_refused_not_printed_as_nan() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.csv");
    std::fs::write(&big, "380,1e300\n780,1e300\n").unwrap();
    let err = refused(&[
        "color",
        "travertine_tufa_solid__eco_ward73",
        "--illuminant",
        big.to_str().unwrap(),
    ]);
    assert!(
        err.starts_with(&format!(
            "error: {}:1: the value 1e300 is larger than the 1e25",
            big.display()
        )),
        "{err}"
    );
    assert!(!err.contains("NaN"), "{err}");
}

#[cfg(unix)]
#[test]
fn retinex_refuses_a_fifo_instead_of_waiting_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.exr");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let out = dir.path().join("out.png");
    let err =
        refused_within(20, &["retinex", fifo.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(err.contains(&format!("{}: not a regular file", fifo.display())), "{err}");
}

#[test]
fn a_truncated_exr_is_described_once() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.exr");
    let image = XyzImage::new(8, 4, vec![[1.0, 2.0, 3.0]; 32]);
    write_xyz_exr(&good, &image, &[]).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.exr");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = dir.path().join("out.png");
    let err = refused(&["retinex", cut.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(err.contains(&format!("{}: not a readable OpenEXR file", cut.display())), "{err}");
    let problem = err.split("OpenEXR file: ").nth(1).unwrap();
    let first = &problem[..problem.find(';').unwrap()];
    assert_eq!(err.matches(first).count(), 1, "said twice: {err}");
}

#[test]
fn a_missing_scene_is_reported_once_in_plain_words() {
    let err = refused(&["scene", "check", "/nonexistent/restauro/scene.toml"]);
    assert_eq!(
        err.trim_end(),
        "error: /nonexistent/restauro/scene.toml: the file does not exist; check the path (and the current folder)"
    );
}

#[test]
fn an_object_scaled_past_the_tracer_is_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aosta");
    ok(&["scene", "aosta", "--out", out.to_str().unwrap(), "--width", "32", "--height", "18"]);
    let sunny = std::fs::read_to_string(out.join("aosta.toml")).unwrap();
    let scaled = out.join("scaled.toml");
    std::fs::write(
        &scaled,
        sunny.replace("name = \"facade\"", "name = \"facade\"\ntransform = { scale = 1e308 }"),
    )
    .unwrap();
    for args in [
        vec!["scene", "check", scaled.to_str().unwrap()],
        vec![
            "render",
            scaled.to_str().unwrap(),
            "--in-process",
            "--spp",
            "1",
            "--out",
            dir.path().join("r").to_str().unwrap(),
        ],
    ] {
        let err = refused_within(120, &args);
        assert!(err.contains("objects[0] (facade).transform: vertex"), "{err}");
        assert!(err.contains("beyond ±1e9 m"), "{err}");
    }
}
