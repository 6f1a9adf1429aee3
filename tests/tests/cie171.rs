//! CIE 171:2006, *Test cases to assess the accuracy of lighting computer programs*: the
//! analytic cases, as the scenes shipped in `validation/cie171/`, computed by
//! `restauro illuminance` as a user runs them. References are the cases' closed forms, computed
//! here (and, for 5.2, the published table besides). `docs/validation.md` lists the figures.

use restauro_tests::{restauro, text};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A copy of the shipped validation scenes, with `edit` applied to `scene`.
fn validation_copy(scene: &str, edit: &dyn Fn(String) -> String) -> tempfile::TempDir {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../validation/cie171");
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(&shipped).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    let file = dir.path().join(scene);
    let text = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, edit(text)).unwrap();
    dir
}

/// Runs `restauro illuminance` on `scene` with `extra`; the JSON document.
fn illuminance(scene: &Path, extra: &[&str]) -> Value {
    let out: PathBuf = scene.parent().unwrap().join("out");
    let mut args =
        vec!["illuminance", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let o = restauro(&args);
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&o)))
}

fn grids(doc: &Value) -> &Vec<Value> {
    doc["grids"].as_array().unwrap()
}

fn grid<'a>(doc: &'a Value, name: &str) -> &'a Value {
    grids(doc).iter().find(|g| g["name"] == name).unwrap()
}

fn points(grid: &Value) -> &Vec<Value> {
    grid["points"].as_array().unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number"))
}

/// Σ key·A over every point of every grid, and the area.
fn integral(doc: &Value, key: &str) -> (f64, f64) {
    grids(doc).iter().fold((0.0, 0.0), |(sum, area), g| {
        let cell = f(&g["cell_area_m2"]);
        let s: f64 = points(g).iter().map(|p| f(&p[key]) * cell).sum();
        (sum + s, area + cell * points(g).len() as f64)
    })
}

/// 5.2: a point source 3 m above the centre of a 4 × 4 m plane, I(θ) = 1000 cos θ cd, from an
/// IES file and from an EULUMDAT file (1° steps). E = I₀ h²/d⁴; the published table agrees
/// with the closed form to 0.03 lx. Tolerance 0.1 % (linear interpolation of the table).
#[test]
fn case_5_2_point_source_from_ies_and_eulumdat() {
    let table = [
        (0.0, 0.0, 111.11),
        (0.5, 0.0, 105.21),
        (1.0, 0.0, 90.02),
        (1.5, 0.0, 71.11),
        (0.5, 0.5, 99.73),
        (1.0, 0.5, 85.64),
        (1.5, 0.5, 68.06),
        (1.0, 1.0, 74.36),
        (1.5, 1.0, 59.98),
        (1.5, 1.5, 49.39),
    ];
    for scene in ["point-ies.toml", "point-ldt.toml"] {
        let dir = validation_copy(scene, &|t| t);
        let doc = illuminance(&dir.path().join(scene), &["--in-process"]);
        let got = points(grid(&doc, "table"));
        assert_eq!(got.len(), table.len());
        for ((x, y, published), p) in table.iter().zip(got) {
            let d2: f64 = x * x + y * y + 9.0;
            let reference = 1000.0 * 9.0 / (d2 * d2);
            assert!((reference - published).abs() < 0.05, "the closed form at ({x}, {y})");
            let lux = f(&p["lux"]);
            let error = lux / reference - 1.0;
            eprintln!(
                "5.2 {scene} ({x}, {y}): {lux:.3} lx, closed form {reference:.3} lx ({:+.4} %)",
                100.0 * error
            );
            assert!(error.abs() < 0.001, "{scene} ({x}, {y}): {lux} lx against {reference:.4}");
            assert_eq!(f(&p["indirect_lux"]), 0.0, "a black plane reflects nothing");
        }
    }
}

/// ∫ cos θ dω over a convex polygon seen from a point with unit normal `n` (Lambert's
/// formula: ½ Σ γᵢ n·(Rᵢ × Rᵢ₊₁)/|Rᵢ × Rᵢ₊₁|, γᵢ the angle between Rᵢ and Rᵢ₊₁).
fn projected_solid_angle(point: [f64; 3], n: [f64; 3], polygon: &[[f64; 3]]) -> f64 {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let sum: f64 = (0..polygon.len())
        .map(|i| {
            let (a, b) = (sub(polygon[i], point), sub(polygon[(i + 1) % polygon.len()], point));
            let gamma = (dot(a, b) / (dot(a, a) * dot(b, b)).sqrt()).clamp(-1.0, 1.0).acos();
            let c = cross(a, b);
            gamma * dot(n, c) / dot(c, c).sqrt()
        })
        .sum();
    0.5 * sum.abs()
}

/// 5.3: a 1 × 1 m Lambertian emitter of 1000 cd/m² centred in the ceiling of a black
/// 4 × 4 × 3 m room, facing down (an area luminaire, sampled by area, stratified). E = L ∫ cos θ
/// dω from Lambert's polygon formula, on the wall y = 0 at x = 2, z = 0.25 … 2.75 and on the
/// floor along x = 2, y = 0.25 … 3.75. Tolerance 0.2 % per point (1024 samples a point).
#[test]
fn case_5_3_area_source() {
    let dir = validation_copy("area.toml", &|t| t);
    let doc = illuminance(&dir.path().join("area.toml"), &["--in-process"]);
    let panel = [[1.5, 1.5, 3.0], [2.5, 1.5, 3.0], [2.5, 2.5, 3.0], [1.5, 2.5, 3.0]];
    let mut worst = 0.0f64;
    for (name, count) in [("wall", 11), ("floor", 15)] {
        let g = grid(&doc, name);
        assert_eq!(points(g).len(), count);
        for p in points(g) {
            let at: Vec<f64> = p["position"].as_array().unwrap().iter().map(f).collect();
            let n: Vec<f64> = p["normal"].as_array().unwrap().iter().map(f).collect();
            let reference =
                1000.0 * projected_solid_angle([at[0], at[1], at[2]], [n[0], n[1], n[2]], &panel);
            let error = f(&p["lux"]) / reference - 1.0;
            worst = worst.max(error.abs());
            assert!(error.abs() < 0.002, "{name} {at:?}: {} lx against {reference:.4}", p["lux"]);
        }
    }
    eprintln!("5.3: every point within {:.4} % of Lambert's formula", 100.0 * worst);
}

/// The area luminaire's flux, π L A, all reaches the black room around it: Σ E·A over the
/// room's six faces (grids of 0.1 m cells; the emitter's own square gets nothing) is 3141.6 lm.
#[test]
fn an_area_luminaire_gives_its_whole_flux() {
    let dir = validation_copy("room.toml", &|t| {
        let lamp = "[[lights]]\nkind = \"area\"\ncorner = [1.5, 1.5, 3.0]\nu = [1.0, 0.0, 0.0]\n\
                    v = [0.0, 1.0, 0.0]\nnormal = [0.0, 0.0, -1.0]\nluminance_cd_m2 = 1000.0\n\
                    spectrum = \"flat\"\n";
        t.replace("[[lights]]\nkind = \"point\"\nposition = [1.3, 2.6, 1.1]\nflux_lm = 10000.0\nspectrum = \"flat\"\n", lamp)
            .replace("samples_per_pixel = 1", "samples_per_pixel = 64")
    });
    let doc = illuminance(&dir.path().join("room.toml"), &["--in-process"]);
    let (flux, _) = integral(&doc, "lux");
    let reference = std::f64::consts::PI * 1000.0;
    eprintln!("area luminaire: Σ E·A = {flux:.2} lm of {reference:.2} lm");
    assert!((flux / reference - 1.0).abs() < 0.005, "Σ E·A = {flux:.2} lm of {reference:.2}");
}

/// 5.4: an isotropic 10 000 lm source in a closed black 4 × 4 × 3 m room: Σ E·A over all six
/// surfaces (grids of 0.1 m cells) is the source's flux, to 0.5 %.
#[test]
fn case_5_4_flux_is_conserved() {
    let dir = validation_copy("room.toml", &|t| t);
    let doc = illuminance(&dir.path().join("room.toml"), &["--in-process"]);
    let (flux, area) = integral(&doc, "lux");
    assert!((area - 80.0).abs() < 1e-9, "the grids cover the room's 80 m²: {area}");
    eprintln!("5.4: Σ E·A = {flux:.2} lm of 10 000 lm");
    assert!((flux / 10_000.0 - 1.0).abs() < 0.005, "Σ E·A = {flux:.1} lm of 10 000 lm");
}

/// 5.8: a 4 m cube, all faces of reflectance ρ, an isotropic 10 000 lm source at its centre.
/// Every unit of flux is absorbed at last, so over the faces the area-weighted mean of the
/// indirect illuminance is ρΦ/((1 − ρ) S_T), S_T = 96 m², in any closed room (in a sphere it
/// is the same at every point; a cube's corners get a little less). Path traced with no bounce
/// cap (`max_depth = 0`). Tolerance 1 %.
#[test]
fn case_5_8_integrating_cube() {
    for (rho, spp) in [(0.05, "64"), (0.5, "128"), (0.9, "256"), (0.95, "512")] {
        let dir = validation_copy("cube.toml", &|t| {
            t.replace("wall = { constant = 0.95 }", &format!("wall = {{ constant = {rho} }}"))
        });
        let doc = illuminance(&dir.path().join("cube.toml"), &["--in-process", "--spp", spp]);
        let (indirect, area) = integral(&doc, "indirect_lux");
        let mean = indirect / area;
        let reference = rho * 10_000.0 / ((1.0 - rho) * 96.0);
        eprintln!(
            "5.8 ρ = {rho}: mean indirect {mean:.3} lx against {reference:.3} lx ({:+.2} %)",
            100.0 * (mean / reference - 1.0)
        );
        assert!(
            (mean / reference - 1.0).abs() < 0.01,
            "ρ = {rho}: mean indirect {mean:.3} lx against {reference:.3} lx"
        );
    }
}

/// The grids compute bit-identically on an embedded cluster (real coordinator and worker
/// processes on loopback) and in-process, with a sky, a luminaire and inter-reflection; and
/// every file is written.
#[test]
fn grids_on_the_farm_are_the_in_process_grids() {
    let dir = validation_copy("room.toml", &|t| {
        t.replace(
            "integrator = \"whitted\"\nsamples_per_pixel = 1",
            "integrator = \"path\"\nsamples_per_pixel = 16\nmax_depth = 4",
        )
        .replace(
            "black = { constant = 0.0 }",
            "black = { constant = 0.6 }\nday = { illuminant = \"D65\" }",
        ) + "\n[[lights]]\nkind = \"sky\"\nilluminance_lux = 10000.0\nspectrum = \"day\"\n"
    });
    // The ceiling open to the sky.
    let obj = dir.path().join("room.obj");
    let mesh = std::fs::read_to_string(&obj).unwrap().replace("f 5 8 7 6\n", "");
    std::fs::write(&obj, mesh).unwrap();
    let scene = dir.path().join("room.toml");
    let in_process = illuminance(&scene, &["--in-process"]);
    let farm = illuminance(&scene, &["--workers", "2"]);
    assert_eq!(farm, in_process);
    let floor = grid(&farm, "floor");
    assert!(f(&floor["min_lux"]) > 0.0 && f(&floor["mean_lux"]) > f(&floor["min_lux"]));
    let indirect: f64 = points(floor).iter().map(|p| f(&p["indirect_lux"])).sum();
    assert!(indirect > 0.0, "the walls reflect light onto the floor");
    let u = f(&floor["uniformity"]);
    assert!((u - f(&floor["min_lux"]) / f(&floor["mean_lux"])).abs() < 1e-12);
    let out = dir.path().join("out");
    for file in ["floor.csv", "floor.png", "north.png", "illuminance.json", "room-illuminance.exr"]
    {
        assert!(out.join(file).is_file(), "{file}");
    }
    let csv = std::fs::read_to_string(out.join("floor.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 40 * 40);
}

/// A scene without grids is refused, naming the table to add; no EXR is left behind.
#[test]
fn a_scene_without_grids_is_refused_by_name() {
    let dir = validation_copy("room.toml", &|t| t.split("\n[[grids]]").next().unwrap().to_owned());
    let scene = dir.path().join("room.toml");
    let out = dir.path().join("out");
    let o = restauro(&[
        "illuminance",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--in-process",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no calculation grid; add a [[grids]] table"), "{}", text(&o));
    assert!(!out.join("room-illuminance.exr").exists());
}
