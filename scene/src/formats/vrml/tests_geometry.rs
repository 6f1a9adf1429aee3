//! Primitives against their analytic areas, volumes and bounds (ISO/IEC 14772-1 §6.7, §6.11,
//! §6.14, §6.17, §6.18, §6.43).

use std::f64::consts::PI;
use std::path::Path;
use std::time::{Duration, Instant};

use super::tests::{assert_has, close3, err, ok};
use super::*;
use crate::mesh::Mesh;

fn world(body: &str) -> VrmlScene {
    ok(&format!("#VRML V2.0 utf8\n{body}\n"))
}

fn shape(geometry: &str) -> VrmlScene {
    world(&format!("Shape {{ geometry {geometry} }}"))
}

fn corners(mesh: &Mesh, t: [u32; 3]) -> [[f64; 3]; 3] {
    t.map(|i| mesh.positions[i as usize].map(f64::from))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The total area of the triangles.
fn area(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = corners(mesh, t);
            norm(cross(sub(b, a), sub(c, a))) / 2.0
        })
        .sum()
}

/// The enclosed volume by the divergence theorem: positive only if every face winds
/// counter-clockwise seen from outside.
fn volume(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = corners(mesh, t);
            let n = cross(b, c);
            (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6.0
        })
        .sum()
}

fn within(value: f64, expected: f64, fraction: f64) -> bool {
    (value - expected).abs() <= fraction * expected.abs()
}

#[test]
fn box_has_the_area_volume_and_bounds_of_its_size() {
    let scene = shape("Box { size 1 2 3 }");
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 12, "six faces of two triangles");
    assert!(within(area(mesh), 2.0 * (1.0 * 2.0 + 2.0 * 3.0 + 3.0 * 1.0), 1e-6));
    assert!(within(volume(mesh), 6.0, 1e-6), "{}", volume(mesh));
    let b = mesh.bounds().unwrap();
    assert!(close3(b.min, [-0.5, -1.0, -1.5]) && close3(b.max, [0.5, 1.0, 1.5]), "{b:?}");
    // §6.7's default size is 2 2 2.
    let unit = shape("Box { }");
    assert!(within(volume(&unit.mesh), 8.0, 1e-6));
    // Flat faces: every normal is an axis.
    for n in unit.mesh.normals.as_ref().unwrap() {
        assert_eq!(n.iter().filter(|c| c.abs() == 1.0).count(), 1, "{n:?}");
    }
}

#[test]
fn sphere_points_lie_on_the_sphere_and_its_area_approaches_four_pi_r_squared() {
    let r = 2.0;
    let scene = shape("Sphere { radius 2 }");
    let mesh = &scene.mesh;
    let normals = mesh.normals.as_ref().unwrap();
    for (p, n) in mesh.positions.iter().zip(normals) {
        let p = p.map(f64::from);
        assert!((norm(p) - r).abs() < 1e-5, "{p:?}");
        // Smooth: the normal is the radius.
        let radial = p.map(|c| (c / r) as f32);
        assert!(close3(*n, radial), "{n:?} at {p:?}");
    }
    // Inscribed: a little less than the sphere, within a few per cent.
    let (a, v) = (area(mesh), volume(mesh));
    assert!(a < 4.0 * PI * r * r && within(a, 4.0 * PI * r * r, 0.03), "{a}");
    assert!(v > 0.0 && within(v, 4.0 / 3.0 * PI * r * r * r, 0.03), "{v}");
}

#[test]
fn cylinder_area_is_its_side_and_caps_and_flags_remove_parts() {
    let (r, h): (f64, f64) = (1.5, 4.0);
    let side = 2.0 * PI * r * h;
    let cap = PI * r * r;
    let full = shape("Cylinder { radius 1.5 height 4 }");
    assert!(within(area(&full.mesh), side + 2.0 * cap, 0.02), "{}", area(&full.mesh));
    assert!(within(volume(&full.mesh), cap * h, 0.02), "{}", volume(&full.mesh));
    let b = full.mesh.bounds().unwrap();
    assert!(close3(b.min, [-1.5, -2.0, -1.5]) && close3(b.max, [1.5, 2.0, 1.5]), "{b:?}");
    let open = shape("Cylinder { radius 1.5 height 4 top FALSE bottom FALSE }");
    assert!(within(area(&open.mesh), side, 0.02));
    let lids = shape("Cylinder { radius 1.5 height 4 side FALSE }");
    assert!(within(area(&lids.mesh), 2.0 * cap, 0.02));
    let top = shape("Cylinder { radius 1.5 height 4 side FALSE bottom FALSE }");
    assert!(top.mesh.positions.iter().all(|p| (p[1] - 2.0).abs() < 1e-6));
    assert!(top.mesh.normals.as_ref().unwrap().iter().all(|n| *n == [0.0, 1.0, 0.0]));
}

#[test]
fn cone_area_is_pi_r_s_plus_its_base() {
    let (r, h): (f64, f64) = (1.0, 2.0);
    let slant = (r * r + h * h).sqrt();
    let cone = shape("Cone { }"); // §6.11 defaults: bottomRadius 1, height 2
    let mesh = &cone.mesh;
    assert!(within(area(mesh), PI * r * slant + PI * r * r, 0.02), "{}", area(mesh));
    assert!(within(volume(mesh), PI * r * r * h / 3.0, 0.02), "{}", volume(mesh));
    let b = mesh.bounds().unwrap();
    assert!(close3(b.min, [-1.0, -1.0, -1.0]) && close3(b.max, [1.0, 1.0, 1.0]), "{b:?}");
    let no_base = shape("Cone { bottom FALSE }");
    assert!(within(area(&no_base.mesh), PI * r * slant, 0.02));
    let base = shape("Cone { side FALSE bottomRadius 3 }");
    assert!(within(area(&base.mesh), PI * 9.0, 0.02));
    assert!(base.mesh.normals.as_ref().unwrap().iter().all(|n| *n == [0.0, -1.0, 0.0]));
}

#[test]
fn transforms_place_primitives() {
    let scene = world(
        "Transform { translation 10 0 0 scale 2 2 2 children [ Shape { geometry Box { } } ] }",
    );
    let b = scene.mesh.bounds().unwrap();
    assert!(close3(b.min, [8.0, -2.0, -2.0]) && close3(b.max, [12.0, 2.0, 2.0]), "{b:?}");
    assert!(within(volume(&scene.mesh), 64.0, 1e-6));
    // A mirror keeps the faces outward.
    let mirrored = world("Transform { scale -1 1 1 children Shape { geometry Sphere { } } }");
    assert!(volume(&mirrored.mesh) > 0.0);
}

#[test]
fn elevation_grid_has_two_triangles_per_cell_and_its_heights() {
    let heights: Vec<f64> = (0..12).map(|k| (k * k) as f64 * 0.1).collect();
    let list: Vec<String> = heights.iter().map(|h| h.to_string()).collect();
    let grid = format!(
        "ElevationGrid {{ xDimension 4 zDimension 3 xSpacing 0.5 zSpacing 2 height [{}] }}",
        list.join(" ")
    );
    let scene = shape(&grid);
    assert_eq!(scene.mesh.triangles.len(), 2 * (4 - 1) * (3 - 1));
    for j in 0..3 {
        for i in 0..4 {
            let expected = [0.5 * i as f32, heights[i + 4 * j] as f32, 2.0 * j as f32];
            assert!(scene.mesh.positions.iter().any(|&p| close3(p, expected)), "{expected:?}");
        }
    }
    // §6.17: counter-clockwise seen from above, so a flat grid faces +Y; ccw FALSE faces −Y.
    let flat = "ElevationGrid { xDimension 2 zDimension 2 height [0 0 0 0] ";
    let up = shape(&format!("{flat} }}"));
    assert!(up.mesh.normals.as_ref().unwrap().iter().all(|n| *n == [0.0, 1.0, 0.0]));
    assert!(!up.mesh.groups[0].double_sided);
    let down = shape(&format!("{flat} ccw FALSE solid FALSE }}"));
    assert!(down.mesh.normals.as_ref().unwrap().iter().all(|n| *n == [0.0, -1.0, 0.0]));
    assert!(down.mesh.groups[0].double_sided);
    let e = err(
        "#VRML V2.0 utf8\nShape { geometry ElevationGrid { xDimension 3 zDimension 3 height [0 1] } }\n",
    );
    assert_has(&e, &["t.wrl", "`height` of ElevationGrid at 2:18", "2 heights", "9 points"]);
}

#[test]
fn extrusion_of_the_default_square_along_a_straight_spine_is_a_box() {
    // §6.18's defaults: the square of side 2 from y = 0 to y = 1, capped.
    let scene = shape("Extrusion { }");
    let mesh = &scene.mesh;
    assert!(within(area(mesh), 2.0 * (2.0 * 1.0 + 1.0 * 2.0 + 2.0 * 2.0), 1e-6), "{}", area(mesh));
    assert!(within(volume(mesh), 4.0, 1e-6), "{}", volume(mesh));
    let b = mesh.bounds().unwrap();
    assert!(close3(b.min, [-1.0, 0.0, -1.0]) && close3(b.max, [1.0, 1.0, 1.0]), "{b:?}");
    // Along X instead (a collinear spine not along Y): the square turns with it.
    let along_x = shape("Extrusion { spine [0 0 0, 3 0 0] }");
    let b = along_x.mesh.bounds().unwrap();
    assert!(close3(b.min, [0.0, -1.0, -1.0]) && close3(b.max, [3.0, 1.0, 1.0]), "{b:?}");
    assert!(within(volume(&along_x.mesh), 12.0, 1e-6), "{}", volume(&along_x.mesh));
    // Without caps, only the four sides.
    let open = shape("Extrusion { beginCap FALSE endCap FALSE }");
    assert!(within(area(&open.mesh), 8.0, 1e-6));
    // Scaled by half at the top: a frustum of volume h/3 (A1 + A2 + √(A1·A2)).
    let frustum = shape("Extrusion { scale [1 1, 0.5 0.5] }");
    assert!(within(volume(&frustum.mesh), (4.0 + 1.0 + 2.0) / 3.0, 1e-6));
}

#[test]
fn extrusion_of_a_circle_along_a_closed_circular_spine_is_a_torus() {
    let (big, small) = (3.0f64, 0.5f64);
    let circle = |n: usize, radius: f64, three: bool| -> String {
        (0..=n)
            .map(|k| {
                let t = std::f64::consts::TAU * (k % n) as f64 / n as f64;
                let (s, c) = (radius * t.sin(), radius * t.cos());
                if three { format!("{c} 0 {s}") } else { format!("{s} {c}") }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let torus = format!(
        "Extrusion {{ spine [{}] crossSection [{}] creaseAngle 1 }}",
        circle(48, big, true),
        circle(24, small, false)
    );
    let scene = shape(&torus);
    let mesh = &scene.mesh;
    for p in &mesh.positions {
        let p = p.map(f64::from);
        let from_spine = ((p[0] * p[0] + p[2] * p[2]).sqrt() - big).hypot(p[1]);
        assert!((from_spine - small).abs() < 1e-4, "{p:?}");
    }
    let area_expected = 4.0 * PI * PI * big * small;
    assert!(within(area(mesh), area_expected, 0.02), "{} vs {area_expected}", area(mesh));
    let volume_expected = 2.0 * PI * PI * big * small * small;
    assert!(within(volume(mesh), volume_expected, 0.03), "{}", volume(mesh));
    // Closed both ways: no caps, and the seams share their points.
    assert_eq!(mesh.triangles.len(), 2 * 48 * 24);
    assert_eq!(mesh.positions.len(), 48 * 24);
}

#[test]
fn bad_sizes_are_refused_with_their_place_and_fix() {
    let e = err("#VRML V2.0 utf8\nShape { geometry Sphere { radius -1 } }\n");
    assert_has(&e, &["t.wrl: 2:27: `radius` of Sphere at 2:18", "-1", "greater than 0"]);
    let e = err("#VRML V2.0 utf8\nShape { geometry Box { size 1 0 1 } }\n");
    assert_has(&e, &["`size` of Box at 2:18", "greater than 0"]);
    let e = err("#VRML V2.0 utf8\nShape { geometry Cylinder { height 1e999 } }\n");
    assert_has(&e, &["`height` of Cylinder", "not a finite number"]);
    let e = err("#VRML V2.0 utf8\nShape { geometry Extrusion { scale [1 -1] } }\n");
    assert_has(&e, &["`scale` of Extrusion", "negative"]);
    let e = err(
        "#VRML V2.0 utf8\nShape { geometry Extrusion { spine [0 0 0 0 1 0 0 2 0] orientation [0 1 0 1, 0 1 0 2] } }\n",
    );
    assert_has(&e, &["`orientation` of Extrusion", "3 spine points"]);
    let e = err("#VRML V2.0 utf8\nShape { geometry ElevationGrid { xDimension -2 } }\n");
    assert_has(&e, &["`xDimension` of ElevationGrid", "whole number"]);
}

#[test]
fn hostile_sizes_are_refused_before_anything_is_built() {
    let start = Instant::now();
    let e = err(
        "#VRML V2.0 utf8\nShape {\n  geometry ElevationGrid { xDimension 100000 zDimension 100000 }\n}\n",
    );
    assert_has(&e, &["t.wrl", "ElevationGrid at 3:12", "xDimension", "over the limit of 50000000"]);
    let spine: Vec<String> = (0..3000).map(|k| format!("0 {k} 0")).collect();
    let section: Vec<String> = (0..20000).map(|k| format!("{} {}", k % 7, k / 7)).collect();
    let e = err(&format!(
        "#VRML V2.0 utf8\nShape {{ geometry Extrusion {{ spine [{}] crossSection [{}] }} }}\n",
        spine.join(" "),
        section.join(" ")
    ));
    assert_has(&e, &["Extrusion at 2:18", "over the limit of 50000000"]);
    // A million spheres by USE are counted, not tessellated.
    let mut text = "#VRML V2.0 utf8\nDEF s0 Shape { geometry Sphere { } }\n".to_string();
    for k in 1..=20 {
        text += &format!("DEF s{k} Group {{ children [ USE s{} USE s{} ] }}\n", k - 1, k - 1);
    }
    assert_has(&err(&text), &["triangles (counting USE copies)", "limit of 50000000"]);
    assert!(start.elapsed() < Duration::from_secs(10), "{:?}", start.elapsed());
}

#[test]
fn ten_thousand_lights_make_one_note() {
    let mut text = "#VRML V2.0 utf8\nShape { geometry Box { } }\n".to_string();
    for k in 0..10_000 {
        text += &format!("PointLight {{ location {k} 0 0 }}\n");
    }
    text += "Shape { geometry DEF t Text { string \"a\" } }\nShape { geometry USE t }\n";
    let scene = parse(&text, Path::new("t.wrl")).unwrap();
    assert_eq!(scene.notes.len(), 2, "{:?}", scene.notes);
    assert_has(&scene.notes[0], &["t.wrl:3: PointLight", "10000 such nodes", "[[lights]]"]);
    assert_has(&scene.notes[1], &["t.wrl:10003: Text is not drawn"]);
    assert!(!scene.notes[1].contains("such nodes"), "a USE is the same node");
}
