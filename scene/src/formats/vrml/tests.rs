//! The importer's tests: each checks against what the standard or geometry says the result
//! must be, not against what the code happened to produce.

use std::path::Path;

use super::*;
use crate::mesh::Mesh;

pub(super) const PATH: &str = "t.wrl";

pub(super) fn ok(text: &str) -> VrmlScene {
    match parse(text, Path::new(PATH)) {
        Ok(scene) => {
            check_consistent(&scene.mesh);
            scene
        }
        Err(e) => panic!("unexpected error: {e}"),
    }
}

pub(super) fn err(text: &str) -> String {
    match parse(text, Path::new(PATH)) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

pub(super) fn assert_has(message: &str, words: &[&str]) {
    for w in words {
        assert!(message.contains(w), "`{w}` missing from: {message}");
    }
}

pub(super) fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-4
}

pub(super) fn close3(a: [f32; 3], b: [f32; 3]) -> bool {
    (0..3).all(|k| close(a[k], b[k]))
}

fn d(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn x(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Twice the area vector of a triangle of the mesh.
pub(super) fn area_vector(mesh: &Mesh, t: [u32; 3]) -> [f32; 3] {
    let p = t.map(|i| mesh.positions[i as usize]);
    x(d(p[1], p[0]), d(p[2], p[0]))
}

/// One normal per position, unit length, on the front side of every triangle.
pub(super) fn check_consistent(mesh: &Mesh) {
    let normals = mesh.normals.as_ref().expect("normals");
    assert_eq!(normals.len(), mesh.positions.len());
    assert_eq!(mesh.triangles.len(), mesh.triangle_group.len());
    for n in normals {
        assert!(close(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0), "{n:?}");
    }
    for &t in &mesh.triangles {
        let a = area_vector(mesh, t);
        for i in t {
            let n = normals[i as usize];
            assert!(a[0] * n[0] + a[1] * n[1] + a[2] * n[2] > 0.0, "back-facing {t:?}");
        }
    }
}

const NESTED: &str = r#"#VRML V2.0 utf8
# Two levels of Transforms; the tile is used twice.
DEF outer Transform {
  translation 10 0 0
  rotation 0 0 1 1.5707963268
  scale 2 2 2
  children [
DEF inner Transform {
  translation 0 1 0
  rotation 0 1 0 3.1415926536
  scale 1 3 1
  children [
    DEF tile Shape {
      appearance Appearance { material Material { diffuseColor 1 0 0 } }
      geometry IndexedFaceSet {
        coord Coordinate { point [0 0 0, 1 0 0, 1 1 0, 0 1 0] }
        coordIndex [0 1 2 3 -1]
      }
    }
  ]
}
Transform {
  translation 0 0 5
  children [
    USE tile
    Shape {
      appearance Appearance { material Material { diffuseColor 0 0 1 } }
      geometry IndexedFaceSet {
        coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] }
        coordIndex [0 1 2]
      }
    }
  ]
}
  ]
}
Shape {
  geometry IndexedFaceSet { coord Coordinate { point [0 0 -1 1 0 -1 0 1 -1] } coordIndex [0 1 2 -1] }
}
"#;

#[test]
fn nested_transforms_with_def_and_use() {
    let scene = ok(NESTED);
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 6);
    assert_eq!(
        mesh.triangles_per_group(),
        vec![("outer".to_string(), 1), ("shape3".to_string(), 1), ("tile".to_string(), 4)]
    );
    let colour = |name: &str| mesh.groups.iter().find(|g| g.name == name).map(|g| g.colour);
    assert_eq!(colour("tile"), Some(Some([1.0, 0.0, 0.0])));
    assert_eq!(colour("outer"), Some(Some([0.0, 0.0, 1.0])));
    assert_eq!(colour("shape3"), Some(None));
    // inner: (x, y, 0) -> (-x, 3y + 1, 0); outer: (x, y, z) -> (10 - 2y, 2x, 2z).
    // The first tile spans x 2..8, y -2..0 at z 0; the used tile (z + 5) spans x 8..10,
    // y 0..2 at z 10; the last shape spans 0..1, 0..1 at z -1.
    let b = mesh.bounds().unwrap();
    assert!(close3(b.min, [0.0, -2.0, -1.0]), "{b:?}");
    assert!(close3(b.max, [10.0, 2.0, 10.0]), "{b:?}");
    // The first tile, turned over by the half turn about Y, faces -Z.
    let tile = mesh.groups.iter().position(|g| g.name == "tile").unwrap() as u32;
    let normals = mesh.normals.as_ref().unwrap();
    let first = mesh.triangle_group.iter().position(|&g| g == tile).unwrap();
    let n = normals[mesh.triangles[first][0] as usize];
    assert!(close3(n, [0.0, 0.0, -1.0]), "{n:?}");
    assert!(mesh.positions.iter().any(|&p| close3(p, [8.0, -2.0, 0.0])));
    assert!(mesh.positions.iter().any(|&p| close3(p, [10.0, 2.0, 10.0])));
}

fn one_face(index: &str, points: &str, extra: &str) -> String {
    format!(
        "#VRML V2.0 utf8\nShape {{ geometry IndexedFaceSet {{\n  coord Coordinate {{ point [{points}] }}\n  coordIndex [{index}]\n  {extra}\n}} }}\n"
    )
}

#[test]
fn ccw_false_reverses_winding_and_quads_make_two_triangles() {
    let tri = "0 0 0, 1 0 0, 0 1 0";
    let front = ok(&one_face("0 1 2", tri, ""));
    let back = ok(&one_face("0 1 2", tri, "ccw FALSE"));
    assert!(area_vector(&front.mesh, front.mesh.triangles[0])[2] > 0.0);
    assert!(area_vector(&back.mesh, back.mesh.triangles[0])[2] < 0.0);
    assert_eq!(back.mesh.normals.as_ref().unwrap()[0], [0.0, 0.0, -1.0]);
    assert!(!front.mesh.groups[0].double_sided);
    let two_sided = ok(&one_face("0 1 2", tri, "solid FALSE"));
    assert!(two_sided.mesh.groups[0].double_sided);

    let quad = ok(&one_face("0 1 2 3 -1", "0 0 0, 2 0 0, 2 1 0, 0 1 0", ""));
    assert_eq!(quad.mesh.triangles.len(), 2);
    let area: f32 = quad.mesh.triangles.iter().map(|&t| area_vector(&quad.mesh, t)[2] / 2.0).sum();
    assert!(close(area, 2.0));
}

#[test]
fn concave_polygon_is_ear_clipped() {
    // An L of area 3, starting at a corner from which a fan would fold over the notch.
    let l = "2 1 0, 1 1 0, 1 2 0, 0 2 0, 0 0 0, 2 0 0";
    let scene = ok(&one_face("0 1 2 3 4 5", l, "convex FALSE"));
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 4);
    let mut total = 0.0;
    for &t in &mesh.triangles {
        let a = area_vector(mesh, t)[2] / 2.0;
        assert!(a > 0.0, "every triangle faces +Z");
        total += a;
    }
    assert!(close(total, 3.0), "{total}");
    // The same polygon, fanned as if convex, does not cover the L exactly.
    let fanned = parse(&one_face("0 1 2 3 4 5", l, ""), Path::new(PATH)).unwrap();
    let unsigned: f32 =
        fanned.mesh.triangles.iter().map(|&t| (area_vector(&fanned.mesh, t)[2] / 2.0).abs()).sum();
    assert!(!close(unsigned, 3.0));
    // Mirrored in the plane (clockwise), ear clipping still covers it, facing -Z.
    let scene = ok(&one_face("5 4 3 2 1 0", l, "convex FALSE"));
    let total: f32 =
        scene.mesh.triangles.iter().map(|&t| area_vector(&scene.mesh, t)[2] / 2.0).sum();
    assert!(close(total, -3.0), "{total}");
}

const CUBE_POINTS: &str = "0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 1, 1 0 1, 1 1 1, 0 1 1";
const CUBE_FACES: &str = "0 3 2 1 -1 4 5 6 7 -1 0 1 5 4 -1 3 7 6 2 -1 0 4 7 3 -1 1 2 6 5";

#[test]
fn crease_angle_splits_or_smooths_cube_corners() {
    let sharp = ok(&one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 0.5"));
    assert_eq!(sharp.mesh.triangles.len(), 12);
    assert_eq!(sharp.mesh.positions.len(), 24);
    let normals = sharp.mesh.normals.as_ref().unwrap();
    let mut pairs: Vec<[u32; 6]> = sharp
        .mesh
        .positions
        .iter()
        .zip(normals)
        .map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]].map(f32::to_bits))
        .collect();
    pairs.sort();
    pairs.dedup();
    assert_eq!(pairs.len(), 24);
    for n in normals {
        assert_eq!(n.iter().filter(|c| c.abs() == 1.0).count(), 1, "axis normal {n:?}");
    }
    let faceted = ok(&one_face(CUBE_FACES, CUBE_POINTS, ""));
    assert_eq!(faceted.mesh.positions.len(), 24);

    let smooth = ok(&one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 2.0"));
    assert_eq!(smooth.mesh.positions.len(), 8);
    let normals = smooth.mesh.normals.as_ref().unwrap();
    let third = 1.0 / 3f32.sqrt();
    for (p, n) in smooth.mesh.positions.iter().zip(normals) {
        let outward = p.map(|c| if c > 0.5 { third } else { -third });
        assert!(close3(*n, outward), "{p:?} {n:?}");
    }
}

#[test]
fn viewpoint_follows_its_transform() {
    let text = r#"#VRML V2.0 utf8
Transform { translation 1 2 3 children [
  Viewpoint { position 0 0 10 description "front \"door\"" }
  Transform { rotation 0 1 0 1.5707963268 children Viewpoint { fieldOfView 0.5 } }
] }
Shape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0 1 0 0 0 1 0] } coordIndex 0 } }
"#;
    // `coordIndex 0` alone is a one-vertex face: refused; use a full face instead.
    let text = text.replace("coordIndex 0", "coordIndex [0 1 2]");
    let scene = ok(&text);
    assert_eq!(scene.viewpoints.len(), 2);
    let front = &scene.viewpoints[0];
    assert!(close3(front.position.map(|c| c as f32), [1.0, 2.0, 13.0]));
    assert_eq!(front.description, "front \"door\"");
    assert!(close(front.orientation.1, 0.0));
    assert!(close(front.field_of_view, std::f32::consts::FRAC_PI_4)); // §6.53 default
    // The default position (0 0 10), turned a quarter about Y, is (10 0 0), then moved.
    let side = &scene.viewpoints[1];
    assert!(close3(side.position.map(|c| c as f32), [11.0, 2.0, 3.0]), "{:?}", side.position);
    assert!(close3(side.orientation.0, [0.0, 1.0, 0.0]), "{:?}", side.orientation);
    assert!(close(side.orientation.1, std::f32::consts::FRAC_PI_2));
    assert!(close(side.field_of_view, 0.5));
}

#[test]
fn mirroring_transform_keeps_front_faces() {
    let text = one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "");
    let text = text.replacen("Shape", "Transform { scale -1 1 1 children Shape", 1) + "}\n";
    let scene = ok(&text);
    // x is mirrored: the face still faces +Z, so its winding was flipped.
    assert_eq!(scene.mesh.normals.as_ref().unwrap()[0], [0.0, 0.0, 1.0]);
    assert!(area_vector(&scene.mesh, scene.mesh.triangles[0])[2] > 0.0);
}

#[test]
fn skips_what_it_does_not_draw() {
    let text = r#"#VRML V2.0 utf8
WorldInfo { title "Temple, \\ east" info ["a" "b"] }
NavigationInfo { type ["EXAMINE", "ANY"] headlight FALSE speed 2 }
Background { skyColor [0 0 1, 1 1 1] skyAngle [1.2] }
DEF sun DirectionalLight { direction 0 -1 0 on TRUE }
DEF clock TimeSensor { cycleInterval 4 loop TRUE }
DEF mover Script {
  eventIn SFTime tick
  eventOut SFVec3f where
  field SFFloat speed 1.5
  url "javascript: function tick(t) { }"
}
ROUTE clock.time TO mover.tick
Switch { whichChoice -1 choice [ DEF hidden Shape {
  appearance Appearance { material Material { diffuseColor 0 1 0 shininess 0.2 }
                      texture ImageTexture { url ["a.png"] } }
  geometry IndexedFaceSet {
coord Coordinate { point [0 0 0 1 0 0 0 1 0] }
normal Normal { vector [0 0 1] }
normalPerVertex FALSE colorPerVertex TRUE
texCoord TextureCoordinate { point [0 0, 1 0, 0 1] }
coordIndex [0 1 2 -1]
texCoordIndex [0 1 2 -1]
  }
} ] }
Shape { geometry Text { string "Tempio" } }
Inline { url "other.wrl" }
Transform { translation 0 0 1 children [ USE hidden ] }
"#;
    let scene = ok(text);
    assert_eq!(scene.mesh.triangles_per_group(), vec![("hidden".to_string(), 1)]);
    assert_eq!(scene.mesh.groups[0].colour, Some([0.0, 1.0, 0.0]));
    assert!(scene.mesh.positions.iter().all(|p| p[2] == 1.0));
    // What a user might expect to see is noted with its line; the rest is not.
    let notes = scene.notes.join("\n");
    for (line, kind) in [
        (4, "Background"),
        (5, "DirectionalLight"),
        (7, "Script"),
        (16, "ImageTexture"),
        (26, "Text"),
        (27, "Inline"),
    ] {
        assert_has(&notes, &[&format!("t.wrl:{line}: {kind} ")]);
    }
    assert_has(&notes, &["[[lights]]", "\"other.wrl\""]);
    for silent in ["WorldInfo", "NavigationInfo", "TimeSensor", "ROUTE"] {
        assert!(!notes.contains(silent), "{silent} noted: {notes}");
    }
    assert_eq!(scene.notes.len(), 6, "{notes}");
}

#[test]
fn zero_area_triangles_are_dropped() {
    let scene = ok(&one_face("0 1 2 -1 0 1 3", "0 0 0, 1 0 0, 0 1 0, 2 0 0", ""));
    assert_eq!(scene.mesh.triangles.len(), 1);
}

#[test]
fn refuses_other_headers_and_misplaced_prototypes() {
    let e = err("#VRML V1.0 ascii\nSeparator { }\n");
    assert_has(&e, &["t.wrl:1:1", "VRML 1.0", "only VRML97 (#VRML V2.0 utf8) is read"]);
    let e = err("solid cube\n");
    assert_has(&e, &["t.wrl:1:1", "only VRML97"]);
    // §4.8: a PROTO is a statement, not a field's value.
    let e = err("#VRML V2.0 utf8\nGroup { children [ EXTERNPROTO X [] \"x.wrl\" ] }\n");
    assert_has(&e, &["t.wrl:2:20", "EXTERNPROTO declares a prototype", "move it before"]);
    let e = err("#VRML V2.0 utf8\n\nPROTO Column [ field SFFloat h 1 ] { }\n");
    assert_has(&e, &["t.wrl:3:36", "body of PROTO `Column` has no node"]);
}

#[test]
fn syntax_errors_say_what_was_expected_and_found() {
    let e = err("#VRML V2.0 utf8\nShape {\n  geometry IndexedFaceSet { coord [ }\n}\n");
    assert_has(&e, &["t.wrl:3:37", "expected a value or the `]`", "found `}`"]);
    let e = err("#VRML V2.0 utf8\nShape {\n");
    assert_has(&e, &["t.wrl:3:1", "expected a field name", "the end of the file", "2:1"]);
    let e = err("#VRML V2.0 utf8\nShape { appearance \"x }\n");
    assert_has(&e, &["t.wrl:2:20", "closing `\"`"]);
    let e = err("#VRML V2.0 utf8\nTransform { translation 1.2.3 }\n");
    assert_has(&e, &["t.wrl:2:25", "expected a number, found `1.2.3`"]);
    let e = err("#VRML V2.0 utf8\n[ ]\n");
    assert_has(&e, &["t.wrl:2:1", "expected a node, found `[`"]);
}

#[test]
fn bad_content_is_refused_with_its_place() {
    let e = err(&one_face("0 1 7", "0 0 0, 1 0 0, 0 1 0", ""));
    assert_has(
        &e,
        &["t.wrl:4:19", "coordIndex 7", "has 3 points", "shape `shape1`", "fix the index"],
    );
    let e = err(&one_face("0 1 2 -1 0 1 -1", "0 0 0, 1 0 0, 0 1 0", ""));
    assert_has(&e, &["t.wrl:4:24", "face 1 of shape `shape1` has 2 vertices", "at least 3"]);
    let e = err(&one_face("0 1 2", "0 0 0, 1 1e999 0, 0 1 0", ""));
    assert_has(&e, &["t.wrl:3:38", "not a finite number", "point 1"]);
    let e = err("#VRML V2.0 utf8\nGroup { children [\n  USE pillar\n] }\n");
    assert_has(&e, &["t.wrl:3:7", "USE `pillar`", "DEF pillar"]);
    let e = err(
        "#VRML V2.0 utf8\nWorldInfo { title \"empty\" }\nShape { geometry Text { string \"x\" } }\n",
    );
    assert_has(&e, &["t.wrl", "the file has no triangles to draw", "Text (line 3)"]);
    let e = err(&(one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "")
        .replace("Shape", "Transform { translation 1 2 children Shape")
        + "}"));
    assert_has(
        &e,
        &["t.wrl: 2:13: `translation` of Transform at 2:1", "expected 3 numbers, found 2"],
    );
    let e = err(&one_face("0 1 2", "0 0 0, 1 0 0, 0 1 0", "ccw 1"));
    assert_has(&e, &["`ccw`", "TRUE or FALSE"]);
}

#[test]
fn limits_depth_and_triangles() {
    let deep =
        format!("#VRML V2.0 utf8\n{}{}", "Group { children [\n".repeat(300), "] }\n".repeat(300));
    let e = err(&deep);
    let fine = format!(
        "#VRML V2.0 utf8\n{}{}{}",
        "Transform { children [\n".repeat(MAX_DEPTH - 3),
        one_face("0 1 2", "0 0 0 1 0 0 0 1 0", "").trim_start_matches("#VRML V2.0 utf8"),
        "] }\n".repeat(MAX_DEPTH - 3)
    );
    assert_eq!(ok(&fine).mesh.triangles.len(), 1);
    assert_has(&e, &["t.wrl", "nesting depth", "over the limit of 256", "flatten"]);
    // USE copies count towards the depth too.
    let mut chain = "#VRML V2.0 utf8\nDEF g0 Group { }\n".to_string();
    for k in 1..=300 {
        chain += &format!("DEF g{k} Group {{ children [ USE g{} ] }}\n", k - 1);
    }
    chain += "Group { children [ Group { children [ USE g300 ] } ] }\n".repeat(2).as_str();
    assert_has(&err(&chain), &["nesting depth", "limit of 256"]);
    // Five copies of a two-triangle quad (1 + 2 in q2 + 2 in USE q2) make 10 triangles.
    let text = one_face("0 1 2 3", "0 0 0, 1 0 0, 1 1 0, 0 1 0", "").replacen(
        "Shape",
        "DEF q Transform { children Shape",
        1,
    ) + "}\nDEF q2 Group { children [ USE q USE q ] }\nUSE q2\n";
    assert_eq!(ok(&text).mesh.triangles.len(), 10);
    let five = Limits { max_triangles: 5, ..Limits::default() };
    let e = match parse_limited(&text, Path::new(PATH), &five) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("limit not applied"),
    };
    assert_has(&e, &["t.wrl", "triangles", "limit of 5", "simplify"]);
}

#[test]
fn every_prefix_is_an_answer_not_a_panic() {
    let inputs =
        [NESTED.to_string(), one_face(CUBE_FACES, CUBE_POINTS, "creaseAngle 2 convex FALSE")];
    for text in &inputs {
        let mut cut = 0;
        while cut <= text.len() {
            if text.is_char_boundary(cut) {
                let _ = parse(&text[..cut], Path::new(PATH));
            }
            cut += 5;
        }
    }
}

#[test]
fn load_reports_missing_files() {
    let e = load(Path::new("/nonexistent/restauro/x.wrl")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert_has(&e.to_string(), &["x.wrl"]);
}
