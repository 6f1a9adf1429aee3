//! `restauro bench tracer --scene-file`: a scene of the user's own is measured at the size asked
//! for, and a file that is not there is refused by name.

use restauro_tests::{aosta_scene, restauro, text};

/// The JSON report of `restauro <args>`, which must succeed.
fn report(args: &[&str]) -> serde_json::Value {
    let o = restauro(args);
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn the_tracer_benchmark_measures_a_scene_file_at_the_size_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let scene = aosta_scene(dir.path(), 320, 240);
    let report = report(&[
        "bench",
        "tracer",
        "--scene-file",
        &scene,
        "--width",
        "48",
        "--height",
        "32",
        "--spp",
        "2",
        "--repeats",
        "1",
        "--progress",
        "none",
    ]);
    assert_eq!(report["scene"], scene.as_str());
    assert_eq!((report["width"].as_u64(), report["height"].as_u64()), (Some(48), Some(32)));
    let samples = 48 * 32 * 2;
    for integrator in ["whitted", "path"] {
        let runs = report[integrator].as_array().unwrap();
        assert_eq!(runs.len(), 2, "{integrator}: one run on each thread count");
        for run in runs {
            // At least the camera ray of every sample, and the rate follows from the counts.
            let rays = run["rays"].as_u64().unwrap();
            let least = samples * run["repetitions"].as_u64().unwrap();
            assert!(rays >= least, "{integrator}: {rays} rays for {least} samples");
            // A small image is traced again until the CPU clock (10 ms ticks) has moved.
            let repetitions = run["repetitions"].as_u64().unwrap();
            let rate = run["samples_per_cpu_s"].as_f64().unwrap();
            let cpu_s = run["cpu_s"].as_f64().unwrap();
            assert!(cpu_s >= 0.2, "{integrator}: {cpu_s} CPU-seconds");
            let all = (samples * repetitions) as f64;
            assert!((rate * cpu_s - all).abs() < 1e-6 * all, "{integrator}: {rate} × {cpu_s}");
        }
    }
}

#[test]
fn the_tracer_benchmark_refuses_a_missing_scene_file_by_name() {
    let o = restauro(&[
        "bench",
        "tracer",
        "--scene-file",
        "/nowhere/scene.toml",
        "--width",
        "8",
        "--height",
        "8",
        "--progress",
        "none",
    ]);
    assert!(!o.status.success());
    assert!(text(&o).contains("/nowhere/scene.toml"), "{}", text(&o));
}

/// `restauro bench mesh` reads, prepares and traces reliefs of the sizes asked for, as real
/// PLY files, and reports each.
#[test]
fn the_mesh_benchmark_reports_each_size() {
    let report = report(&[
        "bench",
        "mesh",
        "--triangles",
        "2000,20000",
        "--width",
        "32",
        "--height",
        "18",
        "--spp",
        "1",
        "--progress",
        "none",
    ]);
    let sizes = report["sizes"].as_array().unwrap();
    assert_eq!(sizes.len(), 2);
    for (size, asked) in sizes.iter().zip([2000u64, 20000]) {
        let triangles = size["triangles"].as_u64().unwrap();
        assert!(triangles.abs_diff(asked) * 20 < asked, "{triangles} triangles for {asked}");
        // A triangle takes a few dozen bytes prepared (BVH, triangle, normal, material), and the
        // file 12 + 13 bytes or so (its share of a vertex, and its face).
        let prepared = size["prepared_bytes_per_triangle"].as_f64().unwrap();
        assert!((40.0..400.0).contains(&prepared), "{prepared} bytes a triangle");
        let file_bytes = size["file_mib"].as_f64().unwrap() * 1048576.0 / triangles as f64;
        assert!((15.0..25.0).contains(&file_bytes), "{file_bytes} bytes a triangle in the file");
        assert!(size["rays_per_cpu_s"].as_f64().unwrap() > 0.0);
    }
}
