//! Shading normals against the analytic sphere. A UV sphere of radius 1 in 24 × 12 facets, lit
//! by the sun 60° off the camera's axis, is a Lambertian ball: its luminance where the camera
//! ray meets the true sphere at normal n is L = ρ E max(0, n·s) / π (ρ = 0.5, E = 10 000 lux on
//! a surface facing the sun, s the direction to the sun). Each pixel's expected value averages
//! that over the pixel's own camera rays (`camera_ray`, the renderer's), so sampling noise
//! cancels and what is left is the shading. The facets alone are off by up to half their
//! angle; the vertex normals, interpolated, follow the sphere.

use glam::Vec3A;
use restauro_render::prepared::{PreparedScene, Settings};
use restauro_render::tile::{camera_ray, film_xyz, pixel};
use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_scene::scene_file::Integrator;
use restauro_scene::sun::{SunPosition, direction_to_sun};

const SIZE: u32 = 40;
const SPP: u32 = 16;
const RHO: f64 = 0.5;
const E_LUX: f64 = 10_000.0;
/// The sun 60° round from the camera (which looks along +Y), 10° up.
const SUN: SunPosition = SunPosition { azimuth_deg: 240.0, elevation_deg: 10.0 };

/// A UV sphere of radius 1 about the origin: `rings` × `segments` quads, each vertex's normal
/// its radius (written as `vn` when `normals`, negated when `flip`).
fn sphere_obj(rings: usize, segments: usize, normals: bool, flip: bool) -> String {
    let mut s = String::new();
    let sign = if flip { -1.0 } else { 1.0 };
    for i in 0..=rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let p = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
            s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
            s += &format!("vn {} {} {}\n", sign * p[0], sign * p[1], sign * p[2]);
        }
    }
    let at = |i: usize, j: usize| i * segments + j % segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            if normals {
                s += &format!("f {0}//{0} {1}//{1} {2}//{2} {3}//{3}\n", q[0], q[1], q[2], q[3]);
            } else {
                s += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
            }
        }
    }
    s
}

fn load(dir: &std::path::Path, obj: &str) -> LoadedScene {
    std::fs::write(dir.join("ball.obj"), obj).unwrap();
    let toml = format!(
        "format = 1\n[camera]\nposition = [0.0, -20.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n\
         vertical_fov_deg = 6.0\nwidth = {SIZE}\nheight = {SIZE}\n\
         [render]\nintegrator = \"whitted\"\nsamples_per_pixel = {SPP}\nmax_depth = 1\n\
         [spectra]\nday = {{ illuminant = \"D65\" }}\ngrey = {{ constant = {RHO} }}\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"ball\"\nmesh = \"ball.obj\"\nmaterial = \"grey\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = {E_LUX}\nazimuth_deg = {}\n\
         elevation_deg = {}\nspectrum = \"day\"\n",
        SUN.azimuth_deg, SUN.elevation_deg
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    load_folder(&dir.join("scene.toml"), &Limits::default()).unwrap()
}

fn prepare(scene: &LoadedScene) -> PreparedScene {
    let settings = Settings {
        integrator: Integrator::Whitted,
        samples_per_pixel: SPP,
        max_depth: 1,
        seed: 3,
        grids: false,
        noise_target: 0.0,
    };
    PreparedScene::new(scene, None, settings).unwrap()
}

/// The unit normal where the ray from `origin` along unit `d` meets the unit sphere.
fn sphere_normal(origin: Vec3A, d: Vec3A) -> Option<Vec3A> {
    let b = origin.dot(d);
    let disc = b * b - (origin.length_squared() - 1.0);
    (disc >= 0.0).then(|| (origin + d * (-b - disc.sqrt())).normalize())
}

/// A pixel's rendered luminance, its expected one, and the least n·s and n·v over its rays;
/// `None` where a ray misses the sphere.
fn pixels(prepared: &PreparedScene) -> Vec<(f64, f64, f32, f32)> {
    let s = Vec3A::from(direction_to_sun(SUN).map(|c| c as f32));
    let origin = prepared.camera.origin;
    let mut out = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let mut expected = 0.0;
            let (mut least_lit, mut least_facing) = (1.0f32, 1.0f32);
            let mut all_hit = true;
            for k in 0..SPP {
                let d = camera_ray(prepared, x, y, k).0;
                let Some(n) = sphere_normal(origin, d) else {
                    all_hit = false;
                    break;
                };
                least_lit = least_lit.min(n.dot(s));
                least_facing = least_facing.min(-n.dot(d));
                expected += RHO * E_LUX * f64::from(n.dot(s).max(0.0)) / std::f64::consts::PI;
            }
            if all_hit {
                let rendered = f64::from(film_xyz(&pixel(prepared, x, y))[1]);
                out.push((rendered, expected / f64::from(SPP), least_lit, least_facing));
            }
        }
    }
    out
}

/// The mean relative error of the pixels lit at least `lit` (n·s over all their rays), away
/// from the silhouette (n·v ≥ 0.3, where the inscribed facets and the sphere part).
fn mean_error(p: &[(f64, f64, f32, f32)], lit: f32) -> (f64, usize) {
    let chosen: Vec<_> = p.iter().filter(|q| q.2 >= lit && q.3 >= 0.3).collect();
    let sum: f64 = chosen.iter().map(|q| (q.0 / q.1 - 1.0).abs()).sum();
    (sum / chosen.len() as f64, chosen.len())
}

#[test]
fn vertex_normals_shade_a_coarse_sphere_as_the_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let smooth = pixels(&prepare(&load(dir.path(), &sphere_obj(12, 24, true, false))));
    let flat = pixels(&prepare(&load(dir.path(), &sphere_obj(12, 24, false, false))));
    let (smooth_error, n) = mean_error(&smooth, 0.25);
    let (flat_error, _) = mean_error(&flat, 0.25);
    assert!(n > 200, "only {n} pixels compared");
    assert!(smooth_error < 0.01, "smooth: mean error {smooth_error} over {n} pixels");
    // The test can fail: the facets alone are far off.
    assert!(flat_error > 3.0 * smooth_error, "flat {flat_error} against smooth {smooth_error}");
}

/// Near the terminator (n·s from 0.02 to 0.12, within half a facet's angle of it) a coarse mesh
/// shaded by its vertex normals has facets whose own plane faces away from the sun while their
/// shading normals face it; lit from the point moved out to the smooth surface, they darken
/// with the sphere instead of going black facet by facet (without the move, 5 of the 63 pixels
/// here are below half their value).
#[test]
fn the_terminator_of_a_coarse_sphere_is_not_stepped() {
    let dir = tempfile::tempdir().unwrap();
    let smooth = pixels(&prepare(&load(dir.path(), &sphere_obj(12, 24, true, false))));
    let band: Vec<_> = smooth.iter().filter(|q| q.2 >= 0.02 && q.2 < 0.12 && q.3 >= 0.3).collect();
    assert!(band.len() > 40, "only {} pixels near the terminator", band.len());
    let dark = band.iter().filter(|q| q.0 < 0.5 * q.1).count();
    assert!(
        dark * 50 <= band.len(),
        "{dark} of {} pixels near the terminator are dark",
        band.len()
    );
}

/// Normals written facing into the ball (a winding and normals that disagree, common in scans)
/// shade as those facing out: they are taken on the side the ray came from.
#[test]
fn normals_facing_away_from_the_face_shade_as_if_turned() {
    let dir = tempfile::tempdir().unwrap();
    let out = prepare(&load(dir.path(), &sphere_obj(12, 24, true, false)));
    let inward = prepare(&load(dir.path(), &sphere_obj(12, 24, true, true)));
    for (x, y) in [(20, 20), (14, 22), (25, 17)] {
        assert_eq!(pixel(&out, x, y), pixel(&inward, x, y), "pixel ({x}, {y})");
    }
}
