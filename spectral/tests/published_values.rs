//! restauro's colorimetry against values published by others: the CIE's own white points
//! (CIE 15:2004 Table T.3), the white points named in the issue, and the plausibility catalogue
//! computed independently with colour-science for every shipped stone spectrum.

use restauro_spectral::colorimetry::{Observer, relative_xyz, white_point};
use restauro_spectral::illuminant::Illuminant;
use restauro_spectral::rgb_space::RgbSpace;
use restauro_spectral::{Lab, Spectrum, library};

fn white(name: &str, observer: Observer) -> restauro_spectral::Xyz {
    white_point(&name.parse::<Illuminant>().unwrap().spd().unwrap(), observer)
}

/// 5 nm summation over 380–780 nm of the CIE tables: D65 (95.043, 100, 108.880),
/// A (109.849, 100, 35.582), C (98.072, 100, 118.225), each to the three decimals given.
#[test]
fn white_points_by_5nm_summation() {
    for (name, expect) in [
        ("D65", [95.043, 100.0, 108.880]),
        ("A", [109.849, 100.0, 35.582]),
        ("C", [98.072, 100.0, 118.225]),
    ] {
        let w = white(name, Observer::Cie1931TwoDegree);
        for (got, want) in w.to_array().iter().zip(expect) {
            assert!((got - want).abs() <= 5e-4, "{name}: {w:?} vs {expect:?}");
        }
    }
}

/// CIE 15:2004 Table T.3, chromaticities of the CIE illuminants, 2° and 10° observers.
#[test]
fn chromaticities_match_cie_15_table_t3() {
    let two = Observer::Cie1931TwoDegree;
    let ten = Observer::Cie1964TenDegree;
    for (name, observer, x, y) in [
        ("A", two, 0.44757, 0.40745),
        ("B", two, 0.34842, 0.35161),
        ("C", two, 0.31006, 0.31616),
        ("D50", two, 0.34567, 0.35851),
        ("D55", two, 0.33243, 0.34744),
        ("D65", two, 0.31272, 0.32903),
        ("D75", two, 0.29903, 0.31488),
        ("E", two, 1.0 / 3.0, 1.0 / 3.0),
        ("A", ten, 0.45117, 0.40594),
        ("C", ten, 0.31039, 0.31905),
        ("D50", ten, 0.34773, 0.35952),
        ("D65", ten, 0.31382, 0.33100),
    ] {
        let c = white(name, observer).chromaticity().unwrap();
        assert!(
            (c.x - x).abs() < 3e-5 && (c.y - y).abs() < 3e-5,
            "{name} {observer}: {c:?} vs ({x}, {y})"
        );
    }
}

/// The helper that collected the spectra computed Y, L*a*b* and the 8-bit sRGB colour of every
/// file under D65 with the 2° observer using colour-science 0.4.7 (`data/spectra/_catalog.csv`),
/// from its own 5 nm resampling (mean of the samples within ±2.5 nm, first value held below the
/// data). Ours must agree to the catalogue's rounding plus the small difference between the two
/// resampling rules.
#[test]
fn every_stone_agrees_with_the_colour_science_catalogue() {
    let catalogue = include_str!("../../data/spectra/_catalog.csv");
    let mut rows = catalogue.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (c_file, c_y, c_l, c_a, c_b, c_hex) =
        (col("file"), col("Y_D65_2deg"), col("L*"), col("a*"), col("b*"), col("sRGB8_D65"));
    let d65 = Illuminant::D65.spd().unwrap();
    let observer = Observer::Cie1931TwoDegree;
    let white = white_point(&d65, observer);
    let mut checked = 0;
    for row in rows.filter(|r| !r.trim().is_empty()) {
        // Some descriptive fields hold commas inside quotes; the numeric fields are at the end.
        let fields = split_csv(row);
        let stem = fields[c_file].trim_end_matches(".csv");
        let loaded = library::load_reflectance(stem).unwrap();
        let xyz = relative_xyz(&loaded.spectrum, &d65, observer);
        let lab = Lab::from_xyz(xyz, white);
        let y: f64 = fields[c_y].parse().unwrap();
        let expect = Lab::new(
            fields[c_l].parse().unwrap(),
            fields[c_a].parse().unwrap(),
            fields[c_b].parse().unwrap(),
        );
        assert!((xyz.y / 100.0 - y).abs() < 1.5e-3, "{stem}: Y {} vs {y}", xyz.y / 100.0);
        for (got, want) in [(lab.l, expect.l), (lab.a, expect.a), (lab.b, expect.b)] {
            assert!((got - want).abs() < 0.3, "{stem}: {lab:?} vs {expect:?}");
        }
        let rgb = RgbSpace::Srgb.linear_from_xyz(xyz.scale(0.01));
        let hex = fields[c_hex].trim_start_matches('#');
        for (k, v) in rgb.iter().enumerate() {
            let ours = (RgbSpace::Srgb.transfer().encode(*v) * 255.0).round() as i32;
            let theirs = i32::from_str_radix(&hex[2 * k..2 * k + 2], 16).unwrap();
            assert!((ours - theirs).abs() <= 1, "{stem}: channel {k} {ours} vs {theirs}");
        }
        checked += 1;
    }
    assert_eq!(checked, library::names().count(), "every shipped spectrum is in the catalogue");
}

fn split_csv(row: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    for ch in row.chars() {
        match ch {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(String::new()),
            _ => fields.last_mut().unwrap().push(ch),
        }
    }
    fields
}

/// The perfect white has Y = 100 and L* = 100 under every illuminant, and a spectrally flat grey
/// is achromatic (a* = b* = 0) under every illuminant: CIELAB normalises by the white.
#[test]
fn flat_spectra_are_neutral_under_every_light() {
    for name in ["A", "B", "C", "D50", "D65", "F11", "daylight:9000", "blackbody:2000"] {
        let spd = name.parse::<Illuminant>().unwrap().spd().unwrap();
        for observer in [Observer::Cie1931TwoDegree, Observer::Cie1964TenDegree] {
            let w = white_point(&spd, observer);
            assert!((w.y - 100.0).abs() < 1e-9);
            let grey = Lab::from_xyz(relative_xyz(&Spectrum::splat(0.18), &spd, observer), w);
            assert!(
                (grey.l - 49.496).abs() < 1e-3 && grey.a.abs() < 1e-4 && grey.b.abs() < 1e-4,
                "{name}: {grey:?}"
            );
        }
    }
}
