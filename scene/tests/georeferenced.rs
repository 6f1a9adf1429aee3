//! Meshes in survey coordinates (5 000 000 m east, 4 000 000 m north), in every format
//! restauro reads: with the scene's `origin`, a step of 1 mm survives into the placed mesh,
//! where 32 bits at that distance resolve only 0.5 m.

use restauro_scene::load::{Limits, LoadedScene, load_folder};

const EAST_M: f64 = 5_000_000.3;
const NORTH_M: f64 = 4_000_000.7;
/// The rectangle's corners: two of them 1 mm east of the other two.
const CORNERS: [[f64; 3]; 4] = [
    [EAST_M, NORTH_M, 0.0],
    [EAST_M + 0.001, NORTH_M, 0.0],
    [EAST_M + 0.001, NORTH_M + 1.0, 0.0],
    [EAST_M, NORTH_M + 1.0, 0.0],
];

fn load(mesh_name: &str, mesh: &[u8], extra: &str) -> LoadedScene {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(mesh_name), mesh).unwrap();
    let toml = format!(
        "format = 1\norigin = [5000000.0, 4000000.0, 0.0]\n\
         [camera]\nposition = [{EAST_M}, {}, 1.6]\ntarget = [{EAST_M}, {NORTH_M}, 0.0]\nwidth = 8\nheight = 6\n\
         [spectra]\ngrey = {{ constant = 0.5 }}\nsun = {{ illuminant = \"D65\" }}\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"step\"\nmesh = \"{mesh_name}\"\nmaterial = \"grey\"\n{extra}\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nelevation_deg = 45.0\nazimuth_deg = 0.0\nspectrum = \"sun\"\n",
        NORTH_M - 10.0
    );
    std::fs::write(dir.path().join("scene.toml"), toml).unwrap();
    load_folder(&dir.path().join("scene.toml"), &Limits::default()).unwrap()
}

/// The placed mesh's x coordinates (recentred), lowest first, with the step between the two
/// distinct ones.
fn step_m(scene: &LoadedScene) -> f64 {
    let mut xs: Vec<f64> =
        scene.objects[0].mesh.positions.iter().map(|p| f64::from(p[0])).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    assert_eq!(xs.len(), 2, "{xs:?}");
    assert!((xs[0] - 0.3).abs() < 1e-6, "{xs:?}");
    xs[1] - xs[0]
}

fn assert_millimetre(scene: &LoadedScene, format: &str) {
    let step = step_m(scene);
    assert!((step - 0.001).abs() < 1e-6, "{format}: a step of {step} m, not 1 mm");
    // The camera moved with the mesh.
    let c = scene.camera.pose.position;
    assert!((c[0] - 0.3).abs() < 1e-9 && (c[1] + 9.3).abs() < 1e-9, "{format}: camera at {c:?}");
}

#[test]
fn obj_ply_and_vrml_keep_a_millimetre_at_five_million_metres() {
    let obj: String =
        CORNERS.iter().map(|[x, y, z]| format!("v {x} {y} {z}\n")).collect::<String>()
            + "f 1 2 3 4\n";
    assert_millimetre(&load("step.obj", obj.as_bytes(), ""), "OBJ");

    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
             property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut ascii = header("ascii");
    ascii += &obj.lines().take(4).map(|l| format!("{}\n", &l[2..])).collect::<String>();
    ascii += "4 0 1 2 3\n";
    assert_millimetre(&load("step.ply", ascii.as_bytes(), ""), "PLY (ASCII)");

    let mut binary = header("binary_little_endian").into_bytes();
    for c in CORNERS.iter().flatten() {
        binary.extend(c.to_le_bytes());
    }
    binary.push(4);
    for i in 0..4i32 {
        binary.extend(i.to_le_bytes());
    }
    assert_millimetre(&load("step.ply", &binary, ""), "PLY (binary)");

    // VRML: the survey offset in a Transform, as georeferenced VRML worlds carry it; Y up.
    let points: Vec<String> = CORNERS
        .iter()
        .map(|[x, y, z]| format!("{} {z} {}", x - 5_000_000.0, -(y - 4_000_000.0)))
        .collect();
    let wrl = format!(
        "#VRML V2.0 utf8\nTransform {{ translation 5000000 0 -4000000 children [ Shape {{ geometry \
         IndexedFaceSet {{ coord Coordinate {{ point [ {} ] }} coordIndex [ 0 1 2 3 -1 ] solid FALSE }} }} ] }}\n",
        points.join(", ")
    );
    assert_millimetre(&load("step.wrl", wrl.as_bytes(), ""), "VRML");
}

/// glTF holds positions in 32 bits by its format; a georeferenced glTF keeps the survey offset
/// in a node's translation (whole metres here), and restauro composes the nodes in 64 bits.
#[test]
fn gltf_with_its_survey_offset_in_a_node_keeps_a_millimetre() {
    // Y up: file (x, y, z) is world (x, −z, y); the node moves by the whole metres.
    let local: Vec<f32> = CORNERS
        .iter()
        .flat_map(|[x, y, z]| [(x - 5_000_000.0) as f32, *z as f32, -(y - 4_000_000.0) as f32])
        .collect();
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut buffer: Vec<u8> = local.iter().flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    use base64::Engine as _;
    let data = base64::engine::general_purpose::STANDARD.encode(&buffer);
    let (min, max) = (
        [0.3f32, 0.0, -1.7].map(|v| v.to_string()).join(","),
        [0.301f32, 0.0, -0.7].map(|v| v.to_string()).join(","),
    );
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0,"translation":[5000000,0,-4000000]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{data}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[{min}],"max":[{max}]}},
                     {{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        buffer.len()
    );
    assert_millimetre(&load("step.gltf", gltf.as_bytes(), ""), "glTF");
}

/// Everything the file places moves with the origin, and a second load of the loaded file
/// would not move it again.
#[test]
fn every_position_moves_with_the_origin_once() {
    let obj: String =
        CORNERS.iter().map(|[x, y, z]| format!("v {x} {y} {z}\n")).collect::<String>()
            + "f 1 2 3 4\n";
    let extra = format!(
        "[[views]]\nname = \"door\"\nposition = [{EAST_M}, {NORTH_M}, 1.6]\ntarget = [{EAST_M}, 4000010.0, 1.6]\n\
         [[grids]]\nname = \"g\"\norigin = [{EAST_M}, {NORTH_M}, 0.0]\nu = [1, 0, 0]\nv = [0, 1, 0]\ndivisions = [1, 1]\n"
    );
    let scene = load("step.obj", obj.as_bytes(), &extra);
    assert_eq!(scene.file.origin, None);
    let view = &scene.file.views[0];
    assert!((view.position[0] - 0.3).abs() < 1e-9 && (view.position[1] - 0.7).abs() < 1e-9);
    let centre = scene.grids[0].points[0];
    assert!((centre[0] - 0.8).abs() < 1e-9 && (centre[1] - 1.2).abs() < 1e-9, "{centre:?}");
    let back = restauro_scene::origin::to_file(centre, scene.origin_m);
    assert!((back[0] - (EAST_M + 0.5)).abs() < 1e-6, "{back:?}");
}
