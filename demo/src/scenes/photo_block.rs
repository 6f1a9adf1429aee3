//! The demo's photo-textured block: four blocks of the facade's pudding stone in a row, under
//! its summer afternoon's sun and sky: the flat material as found and cleaned, then the same
//! measured spectra with a photograph of a conglomerate surface as luminance detail, as found
//! and cleaned. One render shows what a photo adds to a measured spectrum, and that cleaning
//! keeps it.
//!
//! The photograph (`PHOTO`) is CC0: "Gravel04" from CC0Textures (now ambientCG), as scikit-image
//! ships it (`skimage/data/gravel.png`); provenance in `data/README.md`.

use std::fmt::Write as _;

/// The photo, a 512 × 512 grey PNG.
pub const PHOTO: &[u8] = include_bytes!("../../../data/textures/gravel04.png");

/// The file name the scene gives the photo, beside it.
pub const PHOTO_FILE: &str = "textures/conglomerate.png";

/// The blocks, left to right: object name, material, the state the demo's variant gives it, and
/// its label.
pub const BLOCKS: [(&str, &str, &str, &str); 4] = [
    ("flat-found", "flat", "degraded", "flat, as found"),
    ("flat-cleaned", "flat", "cleaned", "flat, cleaned"),
    ("photo-found", "photo", "degraded", "photo detail, as found"),
    ("photo-cleaned", "photo", "cleaned", "photo detail, cleaned"),
];

/// The variant that puts each block in its state.
pub const VARIANT: &str = "demo";

pub struct PhotoBlockScene {
    pub scene_toml: String,
    /// One OBJ per block (`blocks/<name>.obj`), by name.
    pub blocks: Vec<(String, String)>,
}

/// A block's width, height and depth (m), and the gap between blocks.
const SIZE_M: [f64; 3] = [0.9, 0.6, 0.45];
const GAP_M: f64 = 0.25;

/// The scene, `width` × `height` pixels at `spp` samples per pixel.
pub fn generate(width: u32, height: u32, spp: u32) -> PhotoBlockScene {
    let step = SIZE_M[0] + GAP_M;
    let x0 = -1.5 * step - SIZE_M[0] / 2.0;
    let blocks = BLOCKS
        .iter()
        .enumerate()
        .map(|(i, b)| (b.0.to_owned(), block_obj(x0 + step * i as f64)))
        .collect();
    PhotoBlockScene { scene_toml: scene_toml(width, height, spp), blocks }
}

/// A box on the ground, its front face towards −Y (south), with texture coordinates on every
/// face laying the photo at 1 m per image width (so the stones keep their size from face to
/// face).
fn block_obj(x: f64) -> String {
    let [w, h, d] = SIZE_M;
    let mut s = String::from("# A block of pudding stone, written by restauro's demo.\n");
    // Each face: four corners (counter-clockwise seen from outside) and their (u, v) in metres.
    let faces: [[[f64; 3]; 4]; 5] = [
        [[x, 0.0, 0.0], [x + w, 0.0, 0.0], [x + w, 0.0, h], [x, 0.0, h]], // front, −Y
        [[x + w, d, 0.0], [x, d, 0.0], [x, d, h], [x + w, d, h]],         // back, +Y
        [[x, d, 0.0], [x, 0.0, 0.0], [x, 0.0, h], [x, d, h]],             // left, −X
        [[x + w, 0.0, 0.0], [x + w, d, 0.0], [x + w, d, h], [x + w, 0.0, h]], // right, +X
        [[x, 0.0, h], [x + w, 0.0, h], [x + w, d, h], [x, d, h]],         // top, +Z
    ];
    for (f, corners) in faces.iter().enumerate() {
        let (e1, e2) = (sub(corners[1], corners[0]), sub(corners[3], corners[0]));
        for c in corners {
            let r = sub(*c, corners[0]);
            let _ = writeln!(s, "v {:.4} {:.4} {:.4}", c[0], c[1], c[2]);
            // u along the face's first edge, v down its second (from the top of the image).
            let _ = writeln!(s, "vt {:.4} {:.4}", dot(r, unit(e1)), dot(r, unit(e2)));
        }
        let k = 4 * f + 1;
        let _ = writeln!(s, "f {0}/{0} {1}/{1} {2}/{2} {3}/{3}", k, k + 1, k + 2, k + 3);
    }
    s
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|c| c / l)
}

fn scene_toml(width: u32, height: u32, spp: u32) -> String {
    let mut s = format!(
        "# restauro demo: the facade's pudding stone, flat and with a photograph as detail, as found\n\
         # and cleaned. Written by `restauro demo`.\nformat = 1\n\n\
         [camera]\n# A person 4 m in front of the blocks, eyes a little above them.\n\
         position = [0.0, -4.2, 1.6]\ntarget = [0.0, 0.2, 0.1]\nvertical_fov_deg = 26.0\n\
         width = {width}\nheight = {height}\n\n\
         [render]\nintegrator = \"path\"\nsamples_per_pixel = {spp}\nmax_depth = 3\nseed = 1\n\n\
         [spectra]\n{}\nsunlight = {{ illuminant = \"D55\" }}\nskylight = {{ illuminant = \"daylight:12000\" }}\n\
         paving = \"limestone_weathered_surface__usgs_CU02-11A\"\n\n\
         [materials.flat]\nmodel = \"lambert\"\nreflectance = \"puddinga\"\n\
         degraded = {{ reflectance = \"puddinga_soiled\" }}\ncleaned = {{ reflectance = \"puddinga\" }}\n\n\
         [materials.photo]\n# The same measured spectra; the photograph varies them by its relative luminance.\n\
         model = \"lambert\"\nreflectance = \"puddinga\"\ntexture = \"{PHOTO_FILE}\"\ndetail = \"luminance\"\n\
         degraded = {{ reflectance = \"puddinga_soiled\" }}\ncleaned = {{ reflectance = \"puddinga\" }}\n\n\
         [materials.paving]\nmodel = \"lambert\"\nreflectance = \"paving\"\n\n",
        super::aosta::STONE_SPECTRA
    );
    for (name, material, _, _) in BLOCKS {
        let _ = writeln!(
            s,
            "[[objects]]\nname = \"{name}\"\nmesh = \"blocks/{name}.obj\"\nmaterial = \"{material}\"\n"
        );
    }
    s += "[[objects]]\nname = \"ground\"\nmesh = \"blocks/ground.obj\"\nmaterial = \"paving\"\n\n";
    s += super::aosta::SUMMER_AFTERNOON;
    let states: Vec<String> =
        BLOCKS.iter().map(|(n, _, st, _)| format!("\"{n}\" = \"{st}\"")).collect();
    let _ = write!(
        s,
        "\n[variants.{VARIANT}]\n# Each block in its own state.\nstate = \"base\"\nstates = {{ {} }}\n",
        states.join(", ")
    );
    s
}

/// The paving under the blocks.
pub const GROUND_OBJ: &str = "# The paving, written by restauro's demo.\n\
    v -40 -40 0\nv 40 -40 0\nv 40 40 0\nv -40 40 0\nf 1 2 3 4\n";

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene loads with its files, and the photo block's faces all carry coordinates.
    #[test]
    fn the_scene_loads_with_its_photo() {
        let dir = tempfile::tempdir().unwrap();
        let g = generate(64, 32, 1);
        std::fs::create_dir_all(dir.path().join("blocks")).unwrap();
        std::fs::create_dir_all(dir.path().join("textures")).unwrap();
        for (name, obj) in &g.blocks {
            std::fs::write(dir.path().join(format!("blocks/{name}.obj")), obj).unwrap();
        }
        std::fs::write(dir.path().join("blocks/ground.obj"), GROUND_OBJ).unwrap();
        std::fs::write(dir.path().join(PHOTO_FILE), PHOTO).unwrap();
        std::fs::write(dir.path().join("blocks.toml"), &g.scene_toml).unwrap();
        let scene =
            restauro_scene::load::load_folder(&dir.path().join("blocks.toml"), &Default::default())
                .unwrap();
        assert_eq!(scene.textures[PHOTO_FILE].width, 512);
        assert_eq!(scene.state_of(VARIANT, "photo-found", "default"), Some("degraded"));
    }
}
