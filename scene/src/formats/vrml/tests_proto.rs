//! Prototypes (ISO/IEC 14772-1 §4.8, §4.9): expansion, scopes, recursion and limits.

use std::path::Path;
use std::time::{Duration, Instant};

use super::tests::{assert_has, close3, err, ok};
use super::*;
use crate::mesh::{Bounds, Mesh};

fn world(body: &str) -> VrmlScene {
    ok(&format!("#VRML V2.0 utf8\n{body}\n"))
}

/// The bounds of the triangles of one group.
fn group_bounds(mesh: &Mesh, name: &str) -> Bounds {
    let g = mesh.groups.iter().position(|g| g.name == name).expect(name) as u32;
    let mut part = mesh.clone();
    let keep: Vec<bool> = mesh.triangle_group.iter().map(|&t| t == g).collect();
    let mut k = keep.iter();
    part.triangles.retain(|_| *k.next().unwrap());
    part.bounds().unwrap()
}

const COLUMN: &str = "PROTO Column [
  field SFFloat h 2
  field SFColor c 1 0 0
  exposedField SFVec3f at 0 0 0
  eventIn SFVec3f set_at
] {
  Transform {
    translation IS at
    set_translation IS set_at
    children Shape {
      appearance Appearance { material Material { diffuseColor IS c } }
      geometry Cylinder { radius 0.5 height IS h }
    }
  }
  DEF unused Shape { geometry Box { } }
}";

#[test]
fn an_instance_takes_its_values_or_the_defaults() {
    let scene = world(&format!(
        "{COLUMN}\nColumn {{ }}\nColumn {{ h 4 at 5 0 0 c 0 0 1 }}\nDEF west Column {{ at -5 0 0 }}"
    ));
    let mesh = &scene.mesh;
    // Three columns of 32 sides and two caps; the body's second node is not drawn (§4.8.3).
    assert_eq!(mesh.groups.len(), 3, "{:?}", mesh.groups);
    let cylinder = 2 * 32 + 2 * 30;
    assert_eq!(mesh.triangles.len(), 3 * cylinder);
    let names: Vec<&str> = mesh.groups.iter().map(|g| g.name.as_str()).collect();
    assert!(names.contains(&"west"), "{names:?}");
    let by_colour = |c: [f32; 3]| mesh.groups.iter().filter(|g| g.colour == Some(c)).count();
    assert_eq!(by_colour([1.0, 0.0, 0.0]), 2, "the default colour twice");
    assert_eq!(by_colour([0.0, 0.0, 1.0]), 1);
    let blue = mesh.groups.iter().find(|g| g.colour == Some([0.0, 0.0, 1.0])).unwrap();
    let b = group_bounds(mesh, &blue.name.clone());
    assert!(close3(b.min, [4.5, -2.0, -0.5]) && close3(b.max, [5.5, 2.0, 0.5]), "{b:?}");
    let b = group_bounds(mesh, "west");
    assert!(close3(b.min, [-5.5, -1.0, -0.5]) && close3(b.max, [-4.5, 1.0, 0.5]), "{b:?}");
}

#[test]
fn nested_prototypes_with_their_own_scopes_and_defs() {
    let text =
        "PROTO Block [ field SFVec3f size 1 1 1 ] { Shape { geometry Box { size IS size } } }
PROTO Wall [ field SFVec3f blockSize 1 1 1 ] {
  PROTO Inner [ field SFVec3f s 1 1 1 ] { Block { size IS s } }
  Group { children [
    DEF first Transform { children Inner { s IS blockSize } }
    Transform { translation 3 0 0 children USE first }
  ] }
}
Wall { blockSize 2 2 2 }
Transform { translation 0 10 0 children Wall { } }
Inner { }";
    let scene = world(text);
    let b = scene.mesh.bounds().unwrap();
    // Two blocks of 2 at x 0 and 3; two of 1 at x 0 and 3, y 10. If the second Wall's USE
    // reached the first Wall's DEF, its blocks would be of 2.
    assert!(close3(b.min, [-1.0, -1.0, -1.0]) && close3(b.max, [4.0, 10.5, 1.0]), "{b:?}");
    let top = scene.mesh.positions.iter().filter(|p| p[1] > 5.0);
    assert!(top.clone().all(|p| (p[1] - 10.0).abs() <= 0.5 + 1e-6));
    assert_eq!(scene.mesh.triangles.len(), 4 * 12);
    // Inner is declared inside Wall's body: outside it, it is an unknown node, noted.
    assert_has(&scene.notes.join("\n"), &["t.wrl:12: Inner is not a VRML97 node"]);
    // A body sees only its own DEFs.
    let e = err(
        "#VRML V2.0 utf8\nDEF box Shape { geometry Box { } }\nPROTO P [ ] { Group { children USE box } }\nP { }\n",
    );
    assert_has(
        &e,
        &["t.wrl:3:36", "USE `box`", "a PROTO body sees only the names DEF'd inside it"],
    );
}

#[test]
fn a_prototype_that_contains_itself_is_refused() {
    let e = err("#VRML V2.0 utf8\nPROTO A [ ] {\n  Group { children A { } }\n}\n");
    assert_has(&e, &["t.wrl:3:20", "PROTO `A` (declared at 2:1)", "inside its own body"]);
    let e =
        err("#VRML V2.0 utf8\nPROTO A [ ] { PROTO B [ ] { Group { children A { } } } B { } }\n");
    assert_has(&e, &["PROTO `A`", "cannot contain itself"]);
    let e = err(
        "#VRML V2.0 utf8\nEXTERNPROTO B [ ] \"#A\"\nPROTO A [ ] { Group { children B { } } }\n",
    );
    assert_has(&e, &["t.wrl:3:32", "through EXTERNPROTO `B`", "cannot contain itself"]);
}

#[test]
fn an_externproto_is_resolved_only_to_a_proto_of_the_file() {
    let text = "PROTO Post [ field SFFloat r 1 ] { Shape { geometry Sphere { radius IS r } } }
EXTERNPROTO Pillar [ field SFFloat r ] [ \"lib.wrl#Pillar\" \"#Post\" ]
Pillar { r 2 }
EXTERNPROTO Statue [ field SFVec3f at ] \"http://example.org/statue.wrl\"
Statue { at 1 2 3 }
Group { children Statue { } }";
    let scene = world(text);
    for p in &scene.mesh.positions {
        let r = p.iter().map(|c| c * c).sum::<f32>().sqrt();
        assert!((r - 2.0).abs() < 1e-5, "the Pillar is a Post of radius 2: {p:?}");
    }
    assert_eq!(scene.notes.len(), 1, "{:?}", scene.notes);
    assert_has(
        &scene.notes[0],
        &[
            "t.wrl:6: EXTERNPROTO `Statue` (declared at line 5)",
            "\"http://example.org/statue.wrl\"",
            "inline the PROTO",
            "2 such nodes",
        ],
    );
}

#[test]
fn is_and_instance_fields_are_checked() {
    let e = err("#VRML V2.0 utf8\nTransform { translation IS at }\n");
    assert_has(&e, &["t.wrl:2:13", "IS is used outside a PROTO body"]);
    let e =
        err("#VRML V2.0 utf8\nPROTO P [ field SFFloat h 1 ] { Transform { translation IS at } }\n");
    assert_has(&e, &["t.wrl:2:60", "IS `at`", "declares no field `at`", "it has: h"]);
    let e = err(&format!("#VRML V2.0 utf8\n{COLUMN}\nColumn {{ height 3 }}\n"));
    assert_has(
        &e,
        &["t.wrl:18:10", "`height`", "PROTO `Column`", "has no such field", "h, c, at, set_at"],
    );
}

/// Prototypes P0 … P`levels`, each using the one before twice, and one instance of the last.
fn doubling(levels: usize, is: bool) -> String {
    let pass = if is { "{ s IS s }" } else { "{ }" };
    let mut text = "#VRML V2.0 utf8\nPROTO P0 [ field SFVec3f s 1 1 1 ] { Shape { geometry Box { size IS s } } }\n".to_string();
    for k in 1..=levels {
        text += &format!(
            "PROTO P{k} [ field SFVec3f s 1 1 1 ] {{ Group {{ children [ P{j} {pass} P{j} {pass} ] }} }}\n",
            j = k - 1
        );
    }
    text + &format!("P{levels} {{ }}\n")
}

#[test]
fn prototypes_that_double_at_each_level_are_refused_at_once() {
    let start = Instant::now();
    let e = err(&doubling(40, true));
    assert_has(&e, &["nodes made by expanding PROTO instances", "--max-instances"]);
    // Without IS, the levels share their bodies: counted as instances, still at once.
    assert_has(
        &err(&doubling(40, false)),
        &["node instances (counting USE copies)", "--max-instances"],
    );
    assert!(start.elapsed() < Duration::from_secs(10), "{:?}", start.elapsed());
    // Six levels copy 2 (2 + 5 + … + 95) nodes for the bodies and 191 for the instance;
    // nine, over 3000.
    let limits = Limits { max_instances: 16_000, ..Limits::default() };
    let six = parse_limited(&doubling(6, true), Path::new("t.wrl"), &limits).unwrap();
    assert_eq!(six.mesh.triangles.len(), 12 << 6);
    let e = parse_limited(&doubling(9, true), Path::new("t.wrl"), &limits).unwrap_err();
    assert_has(&e.to_string(), &["limit of 1000"]);
}
