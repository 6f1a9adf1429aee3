//! `restauro color` and `restauro demo` as a user runs them: the real binary in a child process.

mod common;
use common::*;

use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::{Lab, library};
use serde_json::Value;
use std::path::Path;

fn json(args: &[&str]) -> Value {
    serde_json::from_str(&ok(args)).expect("valid JSON")
}

fn lab(v: &Value) -> Lab {
    Lab::new(v["l"].as_f64().unwrap(), v["a"].as_f64().unwrap(), v["b"].as_f64().unwrap())
}

#[test]
fn color_works_on_every_shipped_spectrum() {
    for name in library::names() {
        let v = json(&["color", name, "--json"]);
        assert_eq!(v["schema"], "restauro.color/1");
        let s = &v["sample"];
        assert_eq!(s["name"], name);
        let l = lab(&s["lab"]).l;
        assert!((0.0..=100.0).contains(&l), "{name}: L* {l}");
        let hex = s["hex"].as_str().unwrap();
        assert!(hex.len() == 7 && hex.starts_with('#'), "{name}: {hex}");
        // ECOSTRESS data carry their acknowledgement.
        assert_eq!(s["acknowledgement"].is_string(), name.contains("__eco_"), "{name}");
    }
    let text = ok(&["color", "travertine_tufa_solid__eco_ward73"]);
    assert!(text.contains("L*a*b*") && text.contains("#a3937d"), "{text}");
    assert!(text.contains("380–395 nm extrapolated"), "{text}");
    assert!(text.contains("Jet Propulsion Laboratory"), "{text}");
}

#[test]
fn json_output_is_stable_and_has_the_documented_fields() {
    let args = [
        "color",
        "marble_white_solid__eco_ward95",
        "-i",
        "A",
        "--observer",
        "10",
        "--space",
        "p3",
        "--json",
    ];
    assert_eq!(ok(&args), ok(&args));
    let v = json(&args);
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "schema",
            "illuminant",
            "observer",
            "space",
            "adaptation",
            "sample",
            "compare",
            "delta_e00"
        ]
    );
    let sample_keys: Vec<&str> =
        v["sample"].as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        sample_keys,
        [
            "name",
            "origin",
            "xyz",
            "xy",
            "lab",
            "chroma",
            "hue_deg",
            "rgb_linear",
            "rgb_encoded",
            "rgb8",
            "hex",
            "in_gamut",
            "notes",
            "acknowledgement"
        ]
    );
    assert_eq!(v["observer"], "CIE 1964 10°");
    assert_eq!(v["space"], "display-p3");
    // Every key is described in docs/color-json.md.
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/color-json.md");
    let doc = std::fs::read_to_string(doc_path).unwrap();
    for key in keys.iter().chain(&sample_keys) {
        assert!(doc.contains(&format!("`{key}`")), "docs/color-json.md does not describe `{key}`");
    }
}

#[test]
fn compare_reports_ciede2000_between_the_two() {
    let v = json(&[
        "color",
        "travertine_tufa_solid__eco_ward73",
        "--compare",
        "limestone_weathered_surface__usgs_CU02-11A",
        "-i",
        "C",
        "--json",
    ]);
    let de = v["delta_e00"].as_f64().unwrap();
    let expect = ciede2000(lab(&v["sample"]["lab"]), lab(&v["compare"]["lab"]));
    assert_eq!(de, expect);
    assert!(de > 1.0);
    assert!(
        ok(&[
            "color",
            "travertine_tufa_solid__eco_ward73",
            "--compare",
            "limestone_weathered_surface__usgs_CU02-11A"
        ])
        .contains("CIEDE2000 ΔE00 = ")
    );
    // A material against itself differs by nothing.
    let same = json(&[
        "color",
        "chalk_solid__eco_ward67",
        "--compare",
        "chalk_solid__eco_ward67",
        "--json",
    ]);
    assert_eq!(same["delta_e00"].as_f64().unwrap(), 0.0);
}

#[test]
fn the_perfect_white_is_white_under_every_light_when_adapted() {
    let dir = tempfile::tempdir().unwrap();
    let white = dir.path().join("white.csv");
    std::fs::write(&white, "wavelength_nm,reflectance\n380,1\n780,1\n").unwrap();
    let white = white.to_str().unwrap();
    for light in ["A", "D50", "F2", "daylight:4000", "blackbody:2000"] {
        let v = json(&["color", white, "-i", light, "--json"]);
        assert_eq!(v["sample"]["hex"], "#ffffff", "{light}");
        assert!((v["sample"]["xyz"]["y"].as_f64().unwrap() - 100.0).abs() < 1e-9);
    }
    // Without adaptation the light's colour cast shows: A is warm, and beyond the sRGB gamut.
    let raw = json(&["color", white, "-i", "A", "--adapt", "none", "--json"]);
    let rgb: Vec<f64> = raw["sample"]["rgb_linear"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(rgb[0] > rgb[2] * 2.0, "{rgb:?}");
    assert_eq!(raw["sample"]["in_gamut"], false);
    let text = ok(&["color", white, "-i", "A", "--adapt", "none"]);
    assert!(text.contains("outside the srgb gamut"), "{text}");
}

#[test]
fn an_illuminant_from_a_csv_file() {
    let dir = tempfile::tempdir().unwrap();
    let spd = dir.path().join("flat.csv");
    // A flat spectrum is illuminant E: the same colours.
    std::fs::write(&spd, "# flat\n300,5\n900,5\n").unwrap();
    let a = json(&["color", "chalk_solid__eco_ward67", "-i", spd.to_str().unwrap(), "--json"]);
    let e = json(&["color", "chalk_solid__eco_ward67", "-i", "E", "--json"]);
    for k in ["x", "y", "z"] {
        let (a, e) =
            (a["sample"]["xyz"][k].as_f64().unwrap(), e["sample"]["xyz"][k].as_f64().unwrap());
        // Equal up to f32 rounding of the band products (the two spectra differ in scale).
        assert!((a - e).abs() < 1e-6, "{k}: {a} vs {e}");
    }
    // A light that emits nothing visible is refused.
    std::fs::write(&spd, "300,0\n900,0\n").unwrap();
    let err = refused(&["color", "chalk_solid__eco_ward67", "-i", spd.to_str().unwrap()]);
    assert!(err.contains("emits nothing between 380 and 780 nm"), "{err}");
}

/// Each kind of bad spectrum file is refused with the file, the line and what to do.
#[test]
fn bad_spectrum_files_are_refused_with_file_line_and_fix() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &str); 9] = [
        (
            "unsorted.csv",
            "380,0.1\n600,0.2\n500,0.3\n780,0.3\n",
            ":3: the wavelength 500 nm is smaller than 600 nm on line 2; sort the lines",
        ),
        (
            "duplicate.csv",
            "380,0.1\n380,0.2\n780,0.3\n",
            ":2: the wavelength 380 nm already appears on line 1",
        ),
        (
            "text.csv",
            "wavelength_nm,reflectance\n380,0.1\n385,high\n780,0.3\n",
            ":3: the value `high` is not a number",
        ),
        (
            "nan.csv",
            "380,0.1\n385,NaN\n780,0.3\n",
            ":2: the value is `NaN`, which is not a finite number",
        ),
        (
            "inf.csv",
            "380,0.1\n385,inf\n780,0.3\n",
            ":2: the value is `inf`, which is not a finite number",
        ),
        ("negative.csv", "380,0.1\n385,-0.3\n780,0.3\n", ":2: the reflectance -0.3 is below 0"),
        ("above.csv", "380,0.1\n385,42\n780,0.3\n", ":2: the reflectance 42 is above 1"),
        (
            "short.csv",
            "# visible only from 420\n420,0.1\n780,0.3\n",
            ":2: the data cover 420–780 nm but restauro renders 380–780 nm",
        ),
        (
            "columns.csv",
            "380,0.1,0.2\n780,0.3,0.3\n",
            ":1: expected two fields `wavelength_nm,value`",
        ),
    ];
    for (name, text, expect) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let err = refused(&["color", path.to_str().unwrap()]);
        let want = format!("error: {}{expect}", path.display());
        assert!(err.starts_with(&want), "{name}:\n got  {err}\n want {want}");
    }
    // The short file is accepted when extrapolation is allowed, and the extrapolation is said.
    let short = dir.path().join("short.csv");
    let text = ok(&["color", short.to_str().unwrap(), "--extrapolate"]);
    assert!(text.contains("note: 380–415 nm extrapolated"), "{text}");
    // Tiny negative noise is clamped and said.
    let noisy = dir.path().join("noisy.csv");
    std::fs::write(&noisy, "380,-0.003\n385,0.1\n780,0.3\n").unwrap();
    assert!(ok(&["color", noisy.to_str().unwrap()]).contains("clamped to 0"));
}

#[test]
fn unknown_names_are_refused_with_suggestions() {
    let err = refused(&["color", "travertin"]);
    assert!(err.contains("did you mean travertine_"), "{err}");
    let err = refused(&["color", "chalk_solid__eco_ward67", "-i", "D56"]);
    assert!(err.contains("unknown illuminant `D56`"), "{err}");
    let err = refused(&["color", "chalk_solid__eco_ward67", "-i", "daylight:2000"]);
    assert!(err.contains("4000 K to 25000 K"), "{err}");
    let err = refused(&["color", "missing/file.csv"]);
    assert!(err.contains("neither a readable file"), "{err}");
}

#[test]
fn list_prints_the_library() {
    let text = ok(&["color", "--list"]);
    assert_eq!(text.lines().count(), library::names().count());
    assert!(text.contains("carbon_black_soot_proxy__usgs_GDS68"));
}
