//! Every stage after assembly keeps finite input finite: an image whose values reach the bound
//! on radiometric data (`restauro_image::radiometric_bound::MAX_RADIOMETRIC`, 10³⁰) is shown,
//! seen (by the light and by the Retinex), drawn in false colour and compared by the real
//! `restauro` binary without an ∞ or a NaN in any file it writes; an image beyond the bound is
//! refused naming the file, the channel and the pixel.

use exr::prelude::*;
use restauro_image::image_files::{XyzImage, write_xyz_exr};
use restauro_image::radiometric_bound::MAX_RADIOMETRIC;
use restauro_tests::{restauro, text};
use std::path::Path;

const W: usize = 32;
const H: usize = 24;

/// An image of ordinary stone (50 cd/m²) with a patch at the bound, one of tiny values and one
/// of black, and an adapting white to match (at the bound over the bright patch, 0 over the
/// black one), lit by two lights.
fn image_at_the_bound() -> XyzImage {
    let patch = |i: usize| match (i % W / 8, i / W / 8) {
        (1, 1) => MAX_RADIOMETRIC,
        (2, 1) => 1e-30,
        (3, 2) => 0.0,
        _ => 50.0,
    };
    let pixels = (0..W * H).map(|i| [0.95, 1.0, 0.99].map(|k| patch(i) * k)).collect();
    let white = (0..W * H)
        .map(|i| {
            let y = if patch(i) == 50.0 { 160.0 } else { patch(i) };
            [0.95 * y, y, 0.99 * y, 0.5 * y]
        })
        .collect();
    XyzImage {
        width: W,
        height: H,
        pixels,
        emitter: None,
        lit_by: Some((0..W * H).map(|i| if i % W < W / 2 { 1 } else { 2 }).collect()),
        white: Some(white),
    }
}

/// Every channel of every layer of an OpenEXR file, by name.
fn channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let image = read_all_flat_layers_from_file(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut out = Vec::new();
    for layer in image.layer_data {
        for c in layer.channel_data.list {
            out.push((c.name.to_string(), c.sample_data.values_as_f32().collect()));
        }
    }
    out
}

fn assert_finite_exr(path: &Path) {
    for (name, values) in channels(path) {
        let bad = values.iter().position(|v| !v.is_finite());
        assert!(
            bad.is_none(),
            "{path:?}: channel {name} has {:?} at {bad:?}",
            bad.map(|i| values[i])
        );
    }
}

fn run(args: &[&str]) -> String {
    let o = restauro(args);
    assert!(o.status.success(), "restauro {args:?}: {}", text(&o));
    text(&o)
}

#[test]
fn every_stage_keeps_an_image_at_the_bound_finite() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at_bound = d.join("bound.exr");
    write_xyz_exr(&at_bound, &image_at_the_bound(), &[]).unwrap();
    // The writer's own RGB channels are finite too.
    assert_finite_exr(&at_bound);
    let plain = d.join("plain.exr");
    let mut stone = image_at_the_bound();
    stone.pixels.iter_mut().for_each(|p| *p = [47.5, 50.0, 49.5]);
    write_xyz_exr(&plain, &stone, &[]).unwrap();
    let input = at_bound.to_str().unwrap();
    let out = |name: &str| d.join(name).to_str().unwrap().to_owned();

    run(&["display", input, "--out", &out("display.png")]);
    run(&["display", input, "--out", &out("false.png"), "--false-colour", "luminance"]);
    let linear = ["--false-colour", "luminance", "--scale", "linear"];
    run(&[&["display", input, "--out", &out("linear.png")][..], &linear[..]].concat());
    for adaptation in ["light", "retinex"] {
        let (png, exr) = (out(&format!("{adaptation}.png")), out(&format!("{adaptation}.exr")));
        let args = ["retinex", input, "--adaptation", adaptation, "--out", &png, "--exr", &exr];
        run(&args);
        assert_finite_exr(Path::new(&exr));
    }
    for white in ["auto", "absolute:100", "relative"] {
        let folder = out(&format!("compare-{}", white.replace(':', "-")));
        run(&["compare", input, plain.to_str().unwrap(), "--white", white, "--out", &folder]);
        let json = std::fs::read_to_string(Path::new(&folder).join("compare.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&json).unwrap();
        let stats = &summary["delta_e00"];
        for key in ["mean", "median", "p95", "max"] {
            assert!(stats[key].as_f64().is_some_and(f64::is_finite), "{white}: {key} in {json}");
        }
    }
}

#[test]
fn an_image_beyond_the_bound_is_refused_naming_the_channel_and_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let huge = d.join("huge.exr");
    let mut image = image_at_the_bound();
    image.pixels[W + 3] = [1.0, 3.4e38, 1.0];
    image.white = None;
    write_xyz_exr(&huge, &image, &[]).unwrap_or_else(|e| panic!("{e}"));
    let input = huge.to_str().unwrap();
    let png = d.join("out.png");
    let png = png.to_str().unwrap();
    for args in [
        &["display", input, "--out", png][..],
        &["retinex", input, "--out", png],
        &["compare", input, input, "--out", d.join("c").to_str().unwrap()],
    ] {
        let o = restauro(args);
        assert!(!o.status.success(), "{args:?} accepted 3.4e38");
        let said = text(&o);
        assert!(said.contains(&format!("{input}: channel")), "{args:?}: {said}");
        assert!(
            said.contains("is 3.4e38; colour values must be finite and within ±1e30"),
            "{said}"
        );
        assert!(!png_exists(png), "{args:?} wrote a file");
    }
}

fn png_exists(path: &str) -> bool {
    Path::new(path).exists()
}
