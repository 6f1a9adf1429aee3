//! `restauro bench tracer --scene-file`: a scene of the user's own is measured at the size asked
//! for, and a file that is not there is refused by name.

use restauro_tests::{aosta_scene, restauro, text};

#[test]
fn the_tracer_benchmark_measures_a_scene_file_at_the_size_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let scene = aosta_scene(dir.path(), 320, 240);
    let o = restauro(&[
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
    assert!(o.status.success(), "{}", text(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["scene"], scene.as_str());
    assert_eq!((report["width"].as_u64(), report["height"].as_u64()), (Some(48), Some(32)));
    let samples = 48 * 32 * 2;
    for integrator in ["whitted", "path"] {
        let runs = report[integrator].as_array().unwrap();
        assert_eq!(runs.len(), 2, "{integrator}: one run on each thread count");
        for run in runs {
            // At least the camera ray of every sample, and the rate follows from the counts.
            let rays = run["rays"].as_u64().unwrap();
            assert!(rays >= samples, "{integrator}: {rays} rays for {samples} samples");
            let rate = run["samples_per_cpu_s"].as_f64().unwrap();
            let cpu_s = run["cpu_s"].as_f64().unwrap();
            assert!(rate.is_finite() && rate > 0.0, "{integrator}: {rate}");
            assert!((rate * cpu_s - samples as f64).abs() < 1e-6 * samples as f64);
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
