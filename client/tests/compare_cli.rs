//! `restauro compare` and `restauro render --variants`, as a user runs them.

mod common;
use common::*;

use restauro_image::image_files::{XyzImage, write_xyz_exr};
use restauro_spectral::Lab;
use restauro_spectral::appearance::d65_white;

/// A grey of lightness `l` (CIELAB, relative to a D65 white of Y = 1).
fn grey(l: f64) -> [f32; 3] {
    let xyz = Lab { l, a: 0.0, b: 0.0 }.to_xyz(d65_white());
    [xyz.x as f32, xyz.y as f32, xyz.z as f32]
}

#[test]
fn compare_maps_the_difference_and_summarises_it() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 20);
    let a = XyzImage::new(w, h, vec![grey(50.0); w * h]);
    // B: the left half 5 L* lighter.
    let b = XyzImage::new(
        w,
        h,
        (0..w * h).map(|i| grey(if i % w < w / 2 { 55.0 } else { 50.0 })).collect(),
    );
    let (pa, pb) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    write_xyz_exr(&pa, &a, &[]).unwrap();
    write_xyz_exr(&pb, &b, &[]).unwrap();
    let out = dir.path().join("cmp");
    let text = ok(&[
        "compare",
        pa.to_str().unwrap(),
        pb.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--white",
        "relative",
    ]);
    assert!(text.contains("50.0 % above 2"), "{text}");
    for f in ["delta-e.png", "side-by-side.png", "split.png", "compare.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "restauro.compare/1");
    let stats = &json["delta_e00"];
    // A pure lightness step at L̄* 52.5: ΔE00 = ΔL*/S_L (CIE 142-2001).
    let sl = 1.0 + 0.015 * 2.5f64.powi(2) / (20.0 + 2.5f64.powi(2)).sqrt();
    let step = 5.0 / sl;
    assert!((stats["max"].as_f64().unwrap() - step).abs() < 0.01, "{stats}");
    assert!((stats["mean"].as_f64().unwrap() - step / 2.0).abs() < 0.01, "{stats}");
    assert_eq!(stats["share_above_threshold"], 0.5);
    assert_eq!(stats["pixels"], (w * h) as u64);

    // Images of two sizes are refused, with both sizes named.
    let small = dir.path().join("small.exr");
    write_xyz_exr(&small, &XyzImage::new(4, 4, vec![grey(50.0); 16]), &[]).unwrap();
    let e = refused(&[
        "compare",
        pa.to_str().unwrap(),
        small.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("40×20") && e.contains("4×4"), "{e}");
    let e = refused(&["compare", pa.to_str().unwrap(), pb.to_str().unwrap(), "--white", "bright"]);
    assert!(e.contains("--white"), "{e}");
}

#[test]
fn render_variants_renders_each_and_compares_them() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("aosta");
    ok(&["scene", "aosta", "--out", scene.to_str().unwrap(), "--width", "96", "--height", "54"]);
    let out = dir.path().join("out");
    let text = ok(&[
        "render",
        scene.join("aosta.toml").to_str().unwrap(),
        "--in-process",
        "--spp",
        "1",
        "--variants",
        "as-found,cleaned",
        "--out",
        out.to_str().unwrap(),
    ]);
    for stem in ["aosta-as-found", "aosta-cleaned"] {
        assert!(out.join(format!("{stem}.exr")).is_file(), "{text}");
    }
    for what in ["rendered", "seen"] {
        let json = out.join("compare-as-found-vs-cleaned").join(what).join("compare.json");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        // Cleaning changes the stone: the mean difference is well above nothing.
        assert!(json["delta_e00"]["mean"].as_f64().unwrap() > 0.5, "{what}: {json}");
    }
    // One variant or several, not both: clap's usage error.
    let o = restauro(&["render", "x.toml", "--variant", "a", "--variants", "a,b"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--variants"), "{e}");
}
