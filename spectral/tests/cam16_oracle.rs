//! The seen image against an independent oracle: colour-science's CAM16 (`data/cam16/`, made by
//! `data/cam16/make.py` with colour-science 0.4.7). For uniform scenes — a flat field of one
//! stone under one light at one luminance, nothing else in view — the seen colour should be
//! CAM16's corresponding colour under D65 for the same viewing conditions, or differ for a
//! reason named here:
//!
//! * **The blue bias.** restauro's degree of adaptation is CAM16's times 1 − β·Δ, Δ the light's
//!   distance from the bluish daylight locus (`restauro_spectral::seen::degree`): under a warm
//!   or a coloured light a white keeps more of its cast than CAM16 says. Under D65, D50 and a
//!   10 000 K daylight the two agree within ΔE00 1; under A, 3000 K and F2 they differ by what
//!   the lower D makes, and no more (CAM16 with restauro's D agrees within 0.25).
//! * **Mesopic vision.** Below 5 cd/m² of adapting luminance restauro weakens colour by CIE
//!   191's coefficient m; CAM16 does not. Compared here with the mesopic stage off, and the
//!   mesopic stage checked for what it does: hue kept, chroma scaled by m.

use restauro_spectral::appearance::d65_white;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::retinex::RetinexParams;
use restauro_spectral::seen::degree::{self, chromatic_term, luminance_term, to_d65};
use restauro_spectral::seen::mesopic::adaptation_coefficient;
use restauro_spectral::seen::{SeenParams, seen};
use restauro_spectral::{Lab, Xyz};

const STONES: &str = include_str!("../../data/cam16/cam16_stones.csv");

struct Row {
    stone: String,
    light: String,
    white_cd_m2: f64,
    la_cd_m2: f64,
    xyz: Xyz,
    white: Xyz,
    cam16: Xyz,
    d_cam16: f64,
}

fn rows() -> Vec<Row> {
    STONES
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("stone,"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let n = |i: usize| f[i].parse::<f64>().unwrap();
            Row {
                stone: f[0].to_owned(),
                light: f[1].to_owned(),
                white_cd_m2: n(2),
                la_cd_m2: n(3),
                xyz: Xyz::new(n(4), n(5), n(6)),
                white: Xyz::new(n(7), n(8), n(9)),
                cam16: Xyz::new(n(10), n(11), n(12)),
                d_cam16: n(13),
            }
        })
        .collect()
}

fn lab(x: Xyz) -> Lab {
    Lab::from_xyz(x, d65_white())
}

/// The seen colour of a flat field of `row`'s stone at its luminance (24 × 16 pixels, the
/// renderer's white uniform), mean over the field.
fn seen_field(row: &Row, mesopic: bool) -> Xyz {
    let (w, h) = (24, 16);
    let l = row.white_cd_m2;
    let stone = [row.xyz.x * l, row.xyz.y * l, row.xyz.z * l].map(|v| v as f32);
    // The scotopic luminance of the white: its S/P ratio does not matter with the mesopic stage
    // off; with it on, a daylight's 2.4.
    let white = [row.white.x * l, row.white.y * l, row.white.z * l, 2.4 * l].map(|v| v as f32);
    let params = SeenParams {
        retinex: RetinexParams { seed: 5, ..Default::default() },
        mesopic,
        ..Default::default()
    };
    let (out, _) =
        seen(&vec![stone; w * h], &vec![white; w * h], (w, h), &params, &|_, _| {}).unwrap();
    let n = out.len() as f64;
    let s = out.iter().fold([0.0; 3], |a, p| {
        [a[0] + f64::from(p[0]), a[1] + f64::from(p[1]), a[2] + f64::from(p[2])]
    });
    Xyz::new(s[0] / n, s[1] / n, s[2] / n)
}

/// The oracle's own premise: its D is CAM16's, which restauro computes alike.
#[test]
fn the_luminance_term_is_the_oracles() {
    for r in rows() {
        assert!((luminance_term(r.la_cd_m2) - r.d_cam16).abs() < 1e-9, "{}", r.la_cd_m2);
    }
}

/// With CAM16's own D, restauro's corresponding colour (its linear CAT16 form) is CAM16's
/// within ΔE00 0.25 for every stone, light and luminance: CAM16's non-linear stages, run forward
/// and back at the same L_A, add almost nothing.
#[test]
fn with_cam16s_degree_the_corresponding_colour_is_cam16s() {
    let mut worst = 0.0f64;
    for r in rows() {
        let m = to_d65(r.white, r.d_cam16);
        let v = m * glam::DVec3::new(r.xyz.x, r.xyz.y, r.xyz.z) / r.white.y;
        let de = ciede2000(lab(Xyz::new(v.x, v.y, v.z)), lab(r.cam16));
        worst = worst.max(de);
        assert!(
            de < 0.25,
            "{} under {} at {} cd/m²: ΔE00 {de:.3}",
            r.stone,
            r.light,
            r.white_cd_m2
        );
    }
    eprintln!("largest ΔE00 of the linear form against CAM16: {worst:.3}");
}

/// A flat field seen through the whole pipeline (the paths, the adapting white, D with its
/// blue bias), mesopic stage off: within ΔE00 1 of CAM16 under the daylights; under the warm
/// and coloured lights the difference is the blue bias's, so restauro's seen field agrees with
/// CAM16 run at restauro's D.
#[test]
fn a_flat_field_is_seen_as_cam16_sees_it() {
    eprintln!(
        "{:<52} {:<15} {:>7} {:>6} {:>6} {:>9}",
        "stone", "light", "cd/m²", "D", "D_cam", "ΔE00"
    );
    let mut by_light: std::collections::BTreeMap<String, f64> = Default::default();
    for r in rows() {
        let ours = seen_field(&r, false);
        let de = ciede2000(lab(ours), lab(r.cam16));
        let d = luminance_term(degree::ADAPTING_SHARE_OF_WHITE * r.white_cd_m2)
            * chromatic_term(r.white);
        eprintln!(
            "{:<52} {:<15} {:>7} {:>6.3} {:>6.3} {:>9.2}",
            r.stone, r.light, r.white_cd_m2, d, r.d_cam16, de
        );
        let worst = by_light.entry(r.light.clone()).or_default();
        *worst = worst.max(de);
        if ["D65", "D50", "daylight:10000"].contains(&r.light.as_str()) {
            assert!(de < 1.0, "{} under {}: ΔE00 {de:.2}", r.stone, r.light);
        }
        // Every light: the seen field is CAM16's corresponding colour at restauro's D.
        let m = to_d65(r.white, d);
        let v = m * glam::DVec3::new(r.xyz.x, r.xyz.y, r.xyz.z) / r.white.y;
        let own = ciede2000(lab(ours), lab(Xyz::new(v.x, v.y, v.z)));
        assert!(own < 0.3, "{} under {}: ΔE00 {own:.2} from CAM16 at D = {d:.3}", r.stone, r.light);
    }
    for (light, worst) in &by_light {
        eprintln!("largest ΔE00 from CAM16 under {light}: {worst:.2}");
    }
}

/// With the mesopic stage, a field at 2.5 cd/m² (L_A 0.5) keeps its hue within 2° and has its
/// chroma scaled by CIE 191's m, relative to the same field without it; at 500 cd/m² nothing
/// changes.
#[test]
fn night_weakens_colour_and_keeps_hue() {
    for r in rows().iter().filter(|r| r.light == "A" && r.stone.starts_with("brick")) {
        let (day, night) = (lab(seen_field(r, false)), lab(seen_field(r, true)));
        let m = adaptation_coefficient(r.la_cd_m2, 2.4 * r.la_cd_m2);
        let dh = ((day.hue_deg() - night.hue_deg() + 540.0) % 360.0 - 180.0).abs();
        eprintln!(
            "{} cd/m²: m {m:.3}, C* {:.2} → {:.2}, h {:.1} → {:.1}",
            r.white_cd_m2,
            day.chroma(),
            night.chroma(),
            day.hue_deg(),
            night.hue_deg()
        );
        assert!(dh < 2.0, "hue moved {dh:.2}°");
        assert!(
            (night.chroma() / day.chroma() - m).abs() < 0.03,
            "{} against m {m}",
            night.chroma() / day.chroma()
        );
        if r.white_cd_m2 >= 500.0 {
            assert!(m == 1.0 && ciede2000(day, night) < 1e-6);
        }
    }
}
