//! `restauro retinex` and `restauro display` as a user runs them, on EXR files written for the
//! test.

mod common;
use common::*;

use restauro_bench::mondrian;
use restauro_image::image_files::{MAX_PIXELS, XyzImage, read_exr, write_exr, write_xyz_exr};
use restauro_spectral::appearance::{ChannelSpace, d65_white};
use std::path::{Path, PathBuf};

fn png_info(path: &Path) -> (u32, u32, png::BitDepth, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut buf).unwrap();
    (frame.width, frame.height, frame.bit_depth, buf)
}

/// A 96×64 test card in absolute XYZ (cd/m²), and its path.
fn card(dir: &Path) -> PathBuf {
    let (w, h) = (96, 64);
    let pixels = mondrian(w, h, 3);
    let path = dir.join("card.exr");
    write_xyz_exr(
        &path,
        &XyzImage { width: w, height: h, pixels, emitter: None, lit_by: None, white: None },
        &[],
    )
    .unwrap();
    path
}

#[test]
fn retinex_writes_png_and_exr_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let input = card(dir.path());
    let (png_a, png_b, exr) =
        (dir.path().join("a.png"), dir.path().join("b.png"), dir.path().join("r.exr"));
    let args = |out: &Path| {
        vec![
            "retinex".to_owned(),
            input.display().to_string(),
            "--out".to_owned(),
            out.display().to_string(),
            "--paths".to_owned(),
            "8".to_owned(),
            "--seed".to_owned(),
            "5".to_owned(),
        ]
    };
    let mut first = args(&png_a);
    first.extend(["--exr".to_owned(), exr.display().to_string()]);
    let text = ok(&first.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(text.contains("8 samples per pixel at least"), "{text}");
    assert!(text.contains(&format!("wrote {}", png_a.display())), "{text}");
    ok(&args(&png_b).iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(
        std::fs::read(&png_a).unwrap(),
        std::fs::read(&png_b).unwrap(),
        "same seed, same image"
    );
    let (w, h, depth, _) = png_info(&png_a);
    assert_eq!((w, h, depth), (96, 64, png::BitDepth::Eight));
    // The EXR holds XYZ relative to a D65 white: the brightest areas are near 1 in every cone
    // channel (not exactly: the card's light is shaded, and a path that climbs a gradient in
    // steps below the threshold does not reset), and almost nothing is above it (only what
    // the cleaned image smoothed away can be: here the edges between patches a few % apart).
    let result = read_exr(&exr, MAX_PIXELS).unwrap();
    let space = ChannelSpace::default();
    let white = d65_white();
    let white_lms = space.from_xyz(&[[white.x as f32, white.y as f32, white.z as f32]])[0];
    let lms = space.from_xyz(&result.pixels);
    for c in 0..3 {
        let mut values: Vec<f32> = lms.iter().map(|p| p[c] / white_lms[c]).collect();
        values.sort_by(f32::total_cmp);
        let (p99, max) = (values[values.len() * 99 / 100], values[values.len() - 1]);
        assert!(p99 <= 1.0 + 1e-3, "channel {c}: 99th percentile {p99}");
        assert!(max > 0.95 && max < 1.05, "channel {c}: {max}");
    }
}

#[test]
fn display_modes_and_sixteen_bits() {
    let dir = tempfile::tempdir().unwrap();
    let input = card(dir.path());
    let inp = input.to_str().unwrap();
    let out = dir.path().join("d.png");
    let o = out.to_str().unwrap();
    ok(&["display", inp, "--out", o, "--exposure", "auto", "--bits", "16", "--display", "p3"]);
    let (w, h, depth, _) = png_info(&out);
    assert_eq!((w, h, depth), (96, 64, png::BitDepth::Sixteen));
    // A very high white luminance makes the image nearly black; a tiny one makes it white.
    ok(&["display", inp, "--out", o, "--exposure", "absolute:1e9"]);
    assert!(png_info(&out).3.iter().all(|&v| v <= 1));
    ok(&["display", inp, "--out", o, "--exposure", "absolute:1e-6"]);
    assert!(png_info(&out).3.iter().all(|&v| v == 255));
}

/// A render's `lit_by` channel makes the sunlit and the shadowed half frameworks of their own:
/// a white card in the blue shadow is seen white (`--frameworks lights`, the default), blue with
/// one white for all (`none`).
#[test]
fn the_light_mask_of_a_render_makes_frameworks() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (80usize, 40usize);
    let shadow = [0.3f32, 0.35, 0.6];
    let mut img = XyzImage {
        width: w,
        height: h,
        pixels: Vec::with_capacity(w * h),
        emitter: None,
        lit_by: Some(Vec::with_capacity(w * h)),
        white: None,
    };
    for p in 0..w * h {
        let (x, y) = (p % w, p / w);
        let sunlit = x < w / 2;
        // A large card: the paths that miss a small one take the whites of other surfaces, a
        // different one per channel, in the shadow as anywhere.
        let inside = (10..30).contains(&(x % (w / 2))) && (10..30).contains(&y);
        let reflectance = if inside { 0.9 } else { 0.3 };
        let light = if sunlit { [1.0; 3] } else { shadow };
        // The lights as factors on the CAT02 cone responses of a D65 white.
        let cones = [light.map(|l| l * reflectance)];
        let xyz = ChannelSpace::default().to_xyz(&cones)[0];
        img.pixels.push(xyz.map(|v| 100.0 * v));
        img.lit_by.as_mut().unwrap().push(u32::from(sunlit));
    }
    let input = dir.path().join("render.exr");
    write_xyz_exr(&input, &img, &[]).unwrap();
    let card = |frameworks: &str| {
        let exr = dir.path().join(format!("{frameworks}.exr"));
        let png = dir.path().join("x.png");
        let text = ok(&[
            "retinex",
            input.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
            "--frameworks",
            frameworks,
        ]);
        let xyz = read_exr(&exr, MAX_PIXELS).unwrap().pixels[20 * w + w / 2 + 20];
        (text, xyz[2] / xyz[0])
    };
    let (text, apart) = card("lights");
    assert!(text.contains("2 frameworks of illumination"), "{text}");
    let (text, together) = card("none");
    assert!(text.contains("1 framework of illumination"), "{text}");
    // D65's Z/X is 1.146; the shadow's light makes it half as much again with one white.
    let d65 = d65_white().z / d65_white().x;
    assert!((f64::from(apart) / d65 - 1.0).abs() < 0.03, "apart, the card is white: Z/X {apart}");
    assert!(f64::from(together) / d65 > 1.5, "with one white, the card is blue: Z/X {together}");
    let e = refused(&["retinex", input.to_str().unwrap(), "--out", "x.png", "--frameworks", "all"]);
    assert!(e.contains("--frameworks `all`: use lights"), "{e}");
    let e =
        refused(&["retinex", input.to_str().unwrap(), "--out", "x.png", "--framework-weight", "2"]);
    assert!(e.contains("framework weight"), "{e}");
}

#[test]
fn an_rgb_exr_with_emitters_and_the_white_options() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40usize, 30usize);
    // A grey scene with a white card and a lamp a hundred times brighter.
    let mut img = XyzImage {
        width: w,
        height: h,
        pixels: vec![[50.0; 3]; w * h],
        emitter: Some(vec![false; w * h]),
        lit_by: None,
        white: None,
    };
    for y in 0..6 {
        for x in 0..6 {
            img.pixels[y * w + x] = [100.0; 3];
            img.pixels[y * w + x + 30] = [10_000.0; 3];
            img.emitter.as_mut().unwrap()[y * w + x + 30] = true;
        }
    }
    let input = dir.path().join("lamp.exr");
    write_xyz_exr(&input, &img, &[]).unwrap();
    let inp = input.to_str().unwrap();
    let mid = |light_sources: &str| {
        let exr = dir.path().join(format!("{light_sources}.exr"));
        let png = dir.path().join("x.png");
        ok(&[
            "retinex",
            inp,
            "--out",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
            "--light-sources",
            light_sources,
        ]);
        read_exr(&exr, MAX_PIXELS).unwrap().pixels[15 * w + 20][1]
    };
    // Kept, the lamp is an area like any other and the paths that reach it take it as white.
    assert!(mid("keep") < 0.25, "the lamp is the white");
    // Passed over (the file marks it), the card is the white.
    let pass = mid("pass");
    assert!((pass - 0.5).abs() < 0.05, "the card is the white: {pass}");
    // A file without the emitter channel has nothing to pass over, and works.
    let plain = dir.path().join("plain.exr");
    write_exr(
        &plain,
        2,
        2,
        vec![("R".into(), vec![1.0; 4]), ("G".into(), vec![1.0; 4]), ("B".into(), vec![2.0; 4])],
        &[],
    )
    .unwrap();
    let png = dir.path().join("p.png");
    // An RGB file works.
    ok(&["retinex", plain.to_str().unwrap(), "--out", png.to_str().unwrap()]);
}

#[test]
fn bad_input_is_refused_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let input = card(dir.path());
    let inp = input.to_str().unwrap();
    let png = dir.path().join("o.png");
    let o = png.to_str().unwrap();
    let not_exr = dir.path().join("photo.exr");
    std::fs::write(&not_exr, "JFIF").unwrap();
    let err = refused(&["retinex", not_exr.to_str().unwrap(), "--out", o]);
    assert!(err.contains(&format!("{}: not a readable OpenEXR file", not_exr.display())), "{err}");
    let err = refused(&["retinex", inp, "--out", o, "--paths", "0"]);
    assert!(err.contains("Retinex paths = 0 is out of range: 1 to 4096"), "{err}");
    let err = refused(&["retinex", inp, "--out", o, "--white", "brightest"]);
    assert!(err.contains("use area (the default) or paper"), "{err}");
    let err = refused(&["retinex", inp, "--out", o, "--reach", "0"]);
    assert!(err.contains("Retinex reach = 0 is out of range: 0.01 to 4 image diagonals"), "{err}");
    let err = refused(&["retinex", inp, "--out", o, "--light-sources", "hide"]);
    assert!(err.contains("use pass (the default) or keep"), "{err}");
    let err = refused(&["display", inp, "--out", o, "--exposure", "absolute:-3"]);
    assert!(err.contains("-3 cd/m²: use a luminance above 0"), "{err}");
    let missing = dir.path().join("missing.exr");
    let err = refused(&["display", missing.to_str().unwrap(), "--out", o]);
    assert!(err.contains("missing.exr"), "{err}");
    assert!(!png.exists(), "nothing written on failure");
}

/// A Lambertian plane of reflectance 0.5 under a sun at the zenith of 100 000 lux has luminance
/// ρE/π = 15 915.5 cd/m² everywhere. In false colour on a linear scale of 0 to twice that, in
/// four bands, every pixel is viridis at 0.5 (#21918c, matplotlib's) with no isoline across the
/// even plane, and a legend strip is added below; ranges that cannot be drawn are refused.
#[test]
fn false_colour_places_a_known_luminance_on_its_scale() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("plane.obj"),
        "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        d.join("scene.toml"),
        "format = 1\n[camera]\nposition = [0.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         width = 16\nheight = 12\n[render]\nintegrator = \"whitted\"\nsamples_per_pixel = 1\n\
         [spectra]\nhalf = { constant = 0.5 }\nsun = { illuminant = \"D65\" }\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"half\"\n\
         [[objects]]\nname = \"plane\"\nmesh = \"plane.obj\"\nmaterial = \"grey\"\n\
         [[lights]]\nkind = \"sun\"\nilluminance_lux = 100000.0\nazimuth_deg = 0.0\nelevation_deg = 90.0\nspectrum = \"sun\"\n",
    )
    .unwrap();
    let out = d.join("out");
    ok(&[
        "render",
        d.join("scene.toml").to_str().unwrap(),
        "--in-process",
        "--out",
        out.to_str().unwrap(),
    ]);
    let exr = out.join("scene.exr");
    let luminance = 0.5 * 100_000.0 / std::f64::consts::PI;
    let png = d.join("false.png");
    let range = format!("0:{}", 2.0 * luminance);
    let said = ok(&[
        "display",
        exr.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--false-colour",
        "luminance",
        "--scale",
        "linear",
        "--range",
        &range,
        "--bands",
        "4",
    ]);
    assert!(said.contains("linear scale from 0 to 31830.9"), "{said}");
    let (w, h, _, rgb) = png_info(&png);
    assert_eq!((w, h), (16, 12 + restauro_image::false_colour::LEGEND_PX as u32));
    for p in rgb[..16 * 12 * 3].chunks(3) {
        assert_eq!(p, [0x21, 0x91, 0x8c], "a pixel of the plane");
    }
    let e = exr.to_str().unwrap();
    let o = png.to_str().unwrap();
    for (args, words) in [
        (vec!["--range", "5:1"], "give MIN:MAX with 0 ≤ MIN < MAX"),
        (vec!["--range", "0:10"], "a log scale starts above 0"),
        (vec!["--range", "lots"], "--range `lots`: give MIN:MAX"),
    ] {
        let mut all = vec!["display", e, "--out", o, "--false-colour", "luminance"];
        all.extend(args);
        let err = refused(&all);
        assert!(err.contains(words), "{err}");
    }
    // A scale without a false colour is a usage error (clap's exit status 2).
    let usage = restauro(&["display", e, "--out", o, "--scale", "linear"]);
    assert_eq!(usage.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&usage.stderr).contains("--false-colour"));
}
