//! `restauro demo --quick`, the README's first command at its smallest, through the embedded
//! cluster: every image it lists exists and decodes, the sample board obeys ρ·E/π, and under CIE
//! A the Retinex brings each stone closer to its D65 render than the unfiltered render is — the
//! paper's claim (Rossi, Marini & Rizzi 2004, Fig. 12), measured here from the EXR files — the
//! report gives the "after" difference to the D65 render as rendered and as seen, and it and the
//! command's output name things for people, not by their enums' Debug names.

use restauro_image::image_files::{XyzImage, read_exr};
use restauro_scene::scene_file::{Integrator, SkyModel};
use restauro_spectral::Lab;
use restauro_spectral::appearance::d65_white;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::colorimetry::Xyz;
use restauro_tests::{restauro, text};
use serde_json::Value;
use std::path::Path;

fn decode_png(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height)
}

/// The mean XYZ over `rect` ({x0, y0, x1, y1}) and the coefficient of variation of its Y.
fn mean(image: &XyzImage, rect: &Value) -> (Xyz, f64) {
    let r = |k: &str| rect[k].as_u64().unwrap() as usize;
    let (mut sum, mut sum_y2, mut n) = ([0.0f64; 3], 0.0, 0.0);
    for y in r("y0")..r("y1") {
        for x in r("x0")..r("x1") {
            let p = image.pixels[y * image.width + x];
            for k in 0..3 {
                sum[k] += f64::from(p[k]);
            }
            sum_y2 += f64::from(p[1]).powi(2);
            n += 1.0;
        }
    }
    assert!(n > 20.0, "the square {rect} covers {n} pixels");
    let m = sum.map(|v| v / n);
    let variance = (sum_y2 / n - m[1] * m[1]).max(0.0);
    (Xyz::from_array(m), variance.sqrt() / m[1])
}

/// The words of `text` that look like a Rust enum variant's Debug name: two or more capitalised
/// parts run together (`CieOvercast`, `SummerAfternoon`), or, for the given single-word
/// variants (`Path`, `Uniform`), the word itself, alone or lower-cased, as a whole table cell.
fn debug_names<'a>(text: &'a str, single: &[String]) -> Vec<&'a str> {
    let mut found = Vec::new();
    for word in text.split(|c: char| !c.is_alphanumeric()) {
        let chars: Vec<char> = word.chars().collect();
        let camel = chars.first().is_some_and(|c| c.is_uppercase())
            && chars.windows(2).any(|w| w[0].is_lowercase() && w[1].is_uppercase());
        // OpenEXR is the file format's name.
        if (camel && word != "OpenEXR") || single.iter().any(|s| s == word) {
            found.push(word);
        }
    }
    for cell in text.split('|').map(str::trim) {
        if single.iter().any(|s| s.to_lowercase() == cell) {
            found.push(cell);
        }
    }
    found
}

#[test]
fn the_quick_demo_writes_what_it_lists_and_the_retinex_adapts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = restauro(&["demo", "--quick", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains(&format!("results are in {}", out.display())), "{}", text(&o));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let markdown = std::fs::read_to_string(out.join("report.md")).unwrap();

    let listed = every_listed_image_decodes(&out, &report, &markdown);
    let renders = report["renders"].as_array().unwrap();
    // The facade under three lights, as found and cleaned; the stones under four illuminants;
    // the facade floodlit at night, and its grid; the photo block; the sun study as found and
    // cleaned.
    assert_eq!(renders.len(), 15);
    the_sun_study_has_every_hour(renders);
    the_floodlit_bays_figures_are_its_grids(&out, &report, &markdown, &listed);
    for r in renders {
        for f in r["files"].as_array().unwrap() {
            assert!(listed.contains(&f.as_str().unwrap()), "{f} is not listed");
        }
        assert!(r["render_s"].as_f64().unwrap() > 0.0, "{r}");
    }
    for sheet in [
        "facade.png",
        "cleaning-delta-e.png",
        "stones.png",
        "boards.png",
        "block.png",
        "sun-study.png",
    ] {
        assert!(listed.contains(&format!("sheets/{sheet}").as_str()), "{sheet}");
    }
    nothing_half_written_is_left(&out);
    the_retinex_brings_each_stone_closer_to_d65(&out, &report);
    after_is_measured_against_the_d65_render_as_rendered_and_as_seen(&out, &report, &markdown);
    names_are_for_people(&markdown, &text(&o), renders);
}

/// The sun study: each hypothesis every hour from 08:00 to 19:00, each frame rendered and seen.
fn the_sun_study_has_every_hour(renders: &[Value]) {
    for variant in ["as-found", "cleaned"] {
        let job = format!("sun-study-{variant}");
        let r = renders.iter().find(|r| r["job"] == job.as_str()).unwrap();
        let files: Vec<&str> =
            r["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap()).collect();
        for hour in 0..12 {
            for suffix in [".exr", ".png", "-retinex.exr", "-retinex.png"] {
                let file = format!("renders/{job}/{job}-{hour:04}{suffix}");
                assert!(files.contains(&file.as_str()), "{file} in {files:?}");
            }
        }
        assert_eq!(files.len(), 12 * 4);
    }
}

/// Every image the report lists exists and decodes, and report.md lists it too: the files
/// listed.
fn every_listed_image_decodes<'a>(out: &Path, report: &'a Value, markdown: &str) -> Vec<&'a str> {
    let images = report["images"].as_array().unwrap();
    let listed: Vec<&str> = images.iter().map(|i| i["file"].as_str().unwrap()).collect();
    for file in &listed {
        let path = out.join(file);
        if file.ends_with(".png") {
            let (w, h) = decode_png(&path);
            assert!(w > 0 && h > 0, "{file}");
        } else {
            assert!(file.ends_with(".exr"), "{file}");
            let image = read_exr(&path, usize::MAX).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(image.pixels.len(), image.width * image.height, "{file}");
            assert!(image.pixels.iter().flatten().all(|v| v.is_finite()), "{file}");
        }
        assert!(markdown.contains(file), "report.md does not list {file}");
    }
    listed
}

/// The floodlit bay: its figures are its grid's, and its map is listed.
fn the_floodlit_bays_figures_are_its_grids(
    out: &Path,
    report: &Value,
    markdown: &str,
    listed: &[&str],
) {
    let f = &report["floodlighting"];
    let document: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join(f["document"].as_str().unwrap())).unwrap(),
    )
    .unwrap();
    let grid = &document["grids"][0];
    let lux: Vec<f64> =
        grid["points"].as_array().unwrap().iter().map(|p| p["lux"].as_f64().unwrap()).collect();
    let (min, max) = lux.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let average = lux.iter().sum::<f64>() / lux.len() as f64;
    assert_eq!(f["points"].as_u64().unwrap() as usize, lux.len());
    assert!(max > 0.0 && min >= 0.0, "the floodlights light the bay: {min} to {max} lx");
    assert!((f["mean_lux"].as_f64().unwrap() - average).abs() < 1e-6 * average.max(1.0));
    let u = f["uniformity"].as_f64().unwrap();
    assert!((u - min / average).abs() < 1e-9, "uniformity {u} against {}", min / average);
    assert!(listed.contains(&f["map"].as_str().unwrap()), "the map is not listed");
    assert!(markdown.contains("## The facade floodlit at night"));
}

/// Nothing half-written is left: every file was written under a temporary name and renamed.
fn nothing_half_written_is_left(out: &Path) {
    let mut folders = vec![out.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else {
                assert!(!path.to_string_lossy().ends_with(".tmp"), "{} is left", path.display());
            }
        }
    }
}

/// The render `name`'s EXR, as rendered.
fn rendered(out: &Path, name: &str) -> XyzImage {
    let path = out.join(format!("renders/{name}/{name}.exr"));
    read_exr(&path, usize::MAX).unwrap()
}

/// The render `name`'s EXR as seen (its Retinex output).
fn seen(out: &Path, name: &str) -> XyzImage {
    let path = out.join(format!("renders/{name}/{name}-retinex.exr"));
    read_exr(&path, usize::MAX).unwrap()
}

/// CIELAB of `xyz` against a white of luminance `white_y` at D65's chromaticity.
fn lab(xyz: Xyz, white_y: f64) -> Lab {
    Lab::from_xyz(xyz.scale(1.0 / white_y), d65_white())
}

/// The stone experiment, from the files: the white tile obeys ρ·E/π, and under CIE A the
/// Retinex brings each of the four stones closer to its D65 render than the unfiltered render.
fn the_retinex_brings_each_stone_closer_to_d65(out: &Path, report: &Value) {
    let (d65, a, a_seen) =
        (rendered(out, "samples-D65"), rendered(out, "samples-A"), seen(out, "samples-A"));
    let samples = report["samples"].as_array().unwrap();
    let white = samples.iter().find(|s| s["state"] == "reference").unwrap();
    let (white_d65, cv) = mean(&d65, &white["rect"]);
    // The white tile (ρ = 0.9, a Lambertian square under 1000 lux from above): 0.9·1000/π cd/m²,
    // within 0.5 % (the light is a direction; only f32 rounding and the spectral sums differ).
    let expect = 0.9 * 1000.0 / std::f64::consts::PI;
    assert!((white_d65.y / expect - 1.0).abs() < 0.005, "{} vs {expect}", white_d65.y);
    assert!(cv < 1e-3, "the white tile is not uniform: {cv}");
    let (white_a, _) = mean(&a, &white["rect"]);
    let mut checked = 0;
    for s in samples.iter().filter(|s| s["state"] != "reference") {
        let (reference, cv) = mean(&d65, &s["rect"]);
        assert!(cv < 0.01, "{}: not a uniform square ({cv})", s["label"]);
        let reference = lab(reference, white_d65.y);
        let unfiltered = lab(mean(&a, &s["rect"]).0, white_a.y);
        let retinex = lab(mean(&a_seen, &s["rect"]).0, 1.0);
        let (before, after) = (ciede2000(reference, unfiltered), ciede2000(reference, retinex));
        assert!(
            after < before,
            "{} under CIE A: ΔE00 to the D65 render {after:.2} as seen, {before:.2} as rendered",
            s["label"]
        );
        checked += 1;
    }
    assert_eq!(checked, 4);
}

/// "After" is measured against the D65 render as rendered and as seen (its seen image),
/// in both forms of the report. Under D65 the seen square is compared with itself: 0.
fn after_is_measured_against_the_d65_render_as_rendered_and_as_seen(
    out: &Path,
    report: &Value,
    markdown: &str,
) {
    assert!(markdown.contains("| after: ΔE00 to D65 rendered |"), "{markdown}");
    assert!(markdown.contains("| after: ΔE00 to D65 seen |"), "{markdown}");
    let (d65_seen, a_seen) = (seen(out, "samples-D65"), seen(out, "samples-A"));
    let samples = report["samples"].as_array().unwrap();
    let stones = report["stones"].as_array().unwrap();
    assert_eq!(stones.len(), 4 * samples.len());
    for c in stones {
        assert!(c["before_retinex"].get("delta_e00_to_d65_seen").is_none(), "{c}");
        let after = c["after_retinex"]["delta_e00_to_d65_seen"].as_f64().unwrap();
        assert!(after.is_finite() && after >= 0.0, "{c}");
        if c["illuminant"] == "D65" {
            assert_eq!(after, 0.0, "{c}");
        }
        if c["illuminant"] == "A" {
            // From the EXR files: the square of the A render's Retinex output against the same
            // square of the D65 render's.
            let s = samples
                .iter()
                .find(|s| s["stone"] == c["stone"] && s["state"] == c["state"])
                .unwrap();
            let expect = ciede2000(
                lab(mean(&d65_seen, &s["rect"]).0, 1.0),
                lab(mean(&a_seen, &s["rect"]).0, 1.0),
            );
            assert!((after - expect).abs() < 1e-6, "{c}: {after} vs {expect} from the files");
        }
    }
}

/// Names for people, in report.md and the command's `output`: the integrators and skies by
/// their names, no Debug names anywhere.
fn names_are_for_people(markdown: &str, output: &str, renders: &[Value]) {
    let single: Vec<String> = [Integrator::Whitted, Integrator::Path]
        .iter()
        .map(|i| format!("{i:?}"))
        .chain([SkyModel::Uniform, SkyModel::CieOvercast].iter().map(|m| format!("{m:?}")))
        .filter(|name| !name.chars().skip(1).any(char::is_uppercase))
        .filter(|name| name != "Whitted")
        .collect();
    assert!(single.contains(&"Path".to_string()) && single.contains(&"Uniform".to_string()));
    for (what, body) in [("report.md", markdown), ("the output", output)] {
        let found = debug_names(body, &single);
        assert!(found.is_empty(), "{what} names {found:?}");
    }
    // Whitted is a name as well as a variant: it is only ever "Whitted ray tracing".
    assert!(!markdown.contains("| whitted |") && !markdown.contains("| Whitted |"));
    for r in renders {
        let integrator = match r["integrator"].as_str().unwrap() {
            "path" => "path tracing",
            "whitted" => "Whitted ray tracing",
            other => panic!("integrator {other}"),
        };
        let row = markdown
            .lines()
            .find(|l| l.starts_with(&format!("| {} |", r["job"].as_str().unwrap())))
            .unwrap();
        assert!(row.contains(&format!("| {integrator} |")), "{row}");
    }
    assert!(markdown.contains("CIE overcast sky: 10000 lux on the horizontal"), "{markdown}");
    assert!(markdown.contains("uniform sky: 15000 lux on the horizontal"), "{markdown}");
}
