//! The studio's preview of a scene as GLB: read back by the glTF reader (the `gltf` crate
//! validates it against the specification), the scene as it is in the world; a big model with a
//! coarse copy for the view in motion; a part's photo or scan colours as detail.

use restauro_scene::load::{Limits, LoadedScene, load_folder};
use restauro_studio::gltf_export::scene_glb;
use std::path::Path;

/// The wall fixture: two parts, stone and a glazed joint, under the sun.
const WALL_SCENE: &str = include_str!("../../scene/tests/data/wall/scene.toml");
const QUAD_OBJ: &str = include_str!("../../scene/tests/data/wall/meshes/wall.obj");

/// The wall scene with `obj` as its mesh, loaded (the folder is kept while the scene is used).
fn wall(obj: &str) -> (tempfile::TempDir, LoadedScene) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/wall.obj"), obj).unwrap();
    std::fs::write(dir.path().join("scene.toml"), WALL_SCENE).unwrap();
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    (dir, scene)
}

/// The studio's preview GLB, read back by the glTF reader (the `gltf` crate validates it against
/// the specification): the same triangles, in the same world places once its offset is added
/// back and its Y-up turned Z-up, with each part's material and the colour given for it.
#[test]
fn the_preview_glb_holds_the_scene_as_it_is_in_the_world() {
    // A survey far from the origin: its centimetres must survive.
    let far = "v 500000.00 5000000.00 0\nv 500004.00 5000000.00 0\nv 500004.00 5000000.00 3.01\n\
               v 500000.00 5000000.00 3.01\nusemtl stone\nf 1 2 3 4\nusemtl joint\nf 1 3 4\n";
    let (_dir, scene) = wall(far);
    let colour = |m: &str| if m == "stone" { [0.5, 0.4, 0.3] } else { [0.1, 0.2, 0.3] };
    let preview = scene_glb(&scene, colour);
    assert_eq!(preview.triangles, 3);
    let offset = preview.offset_m;
    assert!((offset[0] - 500002.0).abs() < 0.01 && (offset[2] - 1.505).abs() < 1e-3, "{offset:?}");
    let none =
        |uri: &str| -> restauro_scene::Result<Vec<u8>> { panic!("no external buffer {uri}") };
    let (mesh, _) = restauro_scene::formats::gltf::mesh::parse_with_cameras(
        &preview.glb,
        Path::new("preview.glb"),
        &Limits::default(),
        &none,
    )
    .unwrap();
    assert_eq!(mesh.triangles.len(), 3);
    // Back to the world: glTF (x, y, z) is world (x, −z, y), plus the offset.
    let world = |p: [f32; 3]| {
        [f64::from(p[0]) + offset[0], -f64::from(p[2]) + offset[1], f64::from(p[1]) + offset[2]]
    };
    let original = &scene.objects[0].mesh;
    for (t, u) in mesh.triangles.iter().zip(&original.triangles) {
        for (&a, &b) in t.iter().zip(u) {
            let (got, want) = (world(mesh.positions[a as usize]), original.positions[b as usize]);
            for k in 0..3 {
                assert!((got[k] - f64::from(want[k])).abs() < 0.01, "{got:?} vs {want:?}");
            }
        }
    }
    // Parts are named by their scene material, coloured as asked.
    let by_name: std::collections::BTreeMap<_, _> =
        mesh.groups.iter().map(|g| (g.name.clone(), g.colour)).collect();
    assert_eq!(by_name.get("stone"), Some(&Some([0.5, 0.4, 0.3])), "{by_name:?}");
    assert_eq!(by_name.get("glaze"), Some(&Some([0.1, 0.2, 0.3])), "{by_name:?}");
}

/// A model of more than 200 000 triangles carries a coarse copy for the view in motion: one
/// more node per object, marked, about 100 000 triangles that index the model's own vertices
/// (no second vertex buffer); a small model carries none.
#[test]
fn a_big_preview_carries_a_coarse_copy_on_the_same_vertices() {
    let n = 330; // 2 × 330² = 217 800 triangles over 33 m × 33 m, and one joint.
    let mut obj = String::new();
    for y in 0..=n {
        for x in 0..=n {
            obj += &format!(
                "v {} {} {}\n",
                f64::from(x) * 0.1,
                f64::from(y) * 0.1,
                (f64::from(x) * 0.3).sin()
            );
        }
    }
    obj += "usemtl stone\n";
    let at = |x: u32, y: u32| y * (n + 1) + x + 1;
    for y in 0..n {
        for x in 0..n {
            obj += &format!(
                "f {} {} {}\nf {} {} {}\n",
                at(x, y),
                at(x + 1, y),
                at(x + 1, y + 1),
                at(x, y),
                at(x + 1, y + 1),
                at(x, y + 1)
            );
        }
    }
    obj += "usemtl joint\nf 1 2 3\n";
    let (_dir, scene) = wall(&obj);
    let preview = scene_glb(&scene, |_| [0.5; 3]);
    assert_eq!(preview.triangles, 2 * 330 * 330 + 1);
    assert!((50_000..=150_000).contains(&preview.coarse_triangles), "{}", preview.coarse_triangles);
    // The GLB's JSON chunk (§4.4.3): the coarse node's primitives use the model's positions.
    let length = u32::from_le_bytes(preview.glb[12..16].try_into().unwrap()) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&preview.glb[20..20 + length]).unwrap();
    let nodes = doc["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 2, "{nodes:?}");
    assert_eq!(nodes[1]["extras"]["restauro_coarse"], true);
    let primitives = |node: &serde_json::Value| {
        doc["meshes"][node["mesh"].as_u64().unwrap() as usize]["primitives"].clone()
    };
    let (full, coarse) = (primitives(&nodes[0]), primitives(&nodes[1]));
    assert_eq!(coarse[0]["attributes"], full[0]["attributes"]);
    assert_eq!(coarse[0]["extras"], full[0]["extras"]);
    let count: u64 = coarse
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            doc["accessors"][p["indices"].as_u64().unwrap() as usize]["count"].as_u64().unwrap()
        })
        .sum();
    assert_eq!(count, 3 * preview.coarse_triangles as u64);

    let (_small_dir, small) = wall(QUAD_OBJ);
    assert_eq!(scene_glb(&small, |_| [0.5; 3]).coarse_triangles, 0);
}

/// What the preview carries of a part's detail: a laser scan's vertex colours as COLOR_0 (in
/// colour for chromatic detail), a photogrammetry export's photo as its baseColorTexture (in
/// grey for luminance detail, the default), each with the linear mean the viewer divides the
/// part's colour by; nothing for `detail = "none"`.
#[test]
fn the_preview_carries_photos_and_vertex_colours_as_detail() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scans");
    for file in ["weathered-patch.ply", "weathered-patch.glb"] {
        std::fs::copy(data.join(file), dir.path().join(file)).unwrap();
    }
    let toml = "format = 1\n[camera]\nposition = [0.0, -3.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nwidth = 8\nheight = 8\n\
        [spectra]\nday = { illuminant = \"D65\" }\ngrey = { constant = 0.4 }\n\
        [materials.coloured]\nmodel = \"lambert\"\nreflectance = \"grey\"\ndetail = \"chromatic\"\n\
        [materials.photo]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
        [materials.plain]\nmodel = \"lambert\"\nreflectance = \"grey\"\ndetail = \"none\"\n\
        [[objects]]\nname = \"scan\"\nmesh = \"weathered-patch.ply\"\nup_axis = \"y\"\nmaterial = \"coloured\"\n\
        [[objects]]\nname = \"photo\"\nmesh = \"weathered-patch.glb\"\nmaterial = \"photo\"\ntransform = { translate = [1.0, 0.0, 0.0] }\n\
        [[objects]]\nname = \"plain\"\nmesh = \"weathered-patch.ply\"\nup_axis = \"y\"\nmaterial = \"plain\"\ntransform = { translate = [-1.0, 0.0, 0.0] }\n\
        [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 180.0\nelevation_deg = 30.0\nspectrum = \"day\"\n";
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    let scene = load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap();
    let preview = scene_glb(&scene, |_| [0.5; 3]);
    // The document, from the GLB's JSON chunk (§4.4).
    let length = u32::from_le_bytes(preview.glb[12..16].try_into().unwrap()) as usize;
    let document: serde_json::Value =
        serde_json::from_slice(&preview.glb[20..20 + length]).unwrap();
    let primitive = |object: &str| {
        let mesh =
            document["meshes"].as_array().unwrap().iter().find(|m| m["name"] == object).unwrap();
        mesh["primitives"][0].clone()
    };
    let (scan, photo, plain) = (primitive("scan"), primitive("photo"), primitive("plain"));
    assert!(
        scan["attributes"]["COLOR_0"].is_u64() && scan["attributes"]["TEXCOORD_0"].is_null(),
        "{scan}"
    );
    assert!(
        photo["attributes"]["TEXCOORD_0"].is_u64() && photo["attributes"]["COLOR_0"].is_null(),
        "{photo}"
    );
    assert!(
        plain["attributes"]["COLOR_0"].is_null() && plain["extras"]["detail_mean"].is_null(),
        "{plain}"
    );
    let textured = &document["materials"][photo["material"].as_u64().unwrap() as usize];
    assert_eq!(textured["name"], "photo");
    assert!(textured["pbrMetallicRoughness"]["baseColorTexture"]["index"].is_u64(), "{textured}");

    // Read back by restauro's own reader: the scan's colours as the PLY has them, the photo
    // in grey at its own size (256 texels, under the preview's bound).
    let none = |uri: &str| -> restauro_scene::Result<Vec<u8>> { panic!("no external file {uri}") };
    let (back, _) = restauro_scene::formats::gltf::mesh::parse_with_cameras(
        &preview.glb,
        Path::new("preview.glb"),
        &Limits::default(),
        &none,
    )
    .unwrap();
    let source = scene.objects[0].mesh.colours.as_ref().unwrap();
    let colours = back.colours.as_ref().expect("COLOR_0 read back");
    // The scan's vertices come first (its node first); the same linear colours.
    for (got, want) in colours.iter().zip(source) {
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-6, "{got:?} against {want:?}");
        }
    }
    let mean = scan["extras"]["detail_mean"].as_array().unwrap();
    let mean: Vec<f64> = mean.iter().map(|v| v.as_f64().unwrap()).collect();
    assert!(mean.iter().all(|m| *m > 0.05 && *m < 1.0) && mean[0] > mean[2], "{mean:?}");
    let group = back.groups.iter().find(|g| g.name == "photo").unwrap();
    let image = group.photo.as_ref().expect("the photo read back");
    assert_eq!((image.width, image.height), (256, 256));
    assert!(image.texels.iter().all(|t| t[0] == t[1] && t[1] == t[2]), "in grey");
    let photo_mean = photo["extras"]["detail_mean"].as_array().unwrap();
    assert_eq!(photo_mean[0], photo_mean[2]);
}
