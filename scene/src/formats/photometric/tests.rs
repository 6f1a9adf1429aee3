//! The readers against hand-written distributions, the published real files and every
//! refusal.

use super::eulumdat::*;
use super::ies::*;
use super::*;

#[test]
fn the_luminaire_frame_points_its_nadir_at_the_aim_with_c0_towards_east() {
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
    // Hung pointing down: the file's own frame, C = 0 east.
    let [x, y, z] = luminaire_frame([1.0, 2.0, 5.0], None);
    assert!(close(x, [1.0, 0.0, 0.0]) && close(y, [0.0, 1.0, 0.0]) && close(z, [0.0, 0.0, 1.0]));
    // Aimed north and level: the nadir (−z) points north, C = 0 still east, and C = 90°
    // (y = z × x, a right-handed frame) up.
    let [x, y, z] = luminaire_frame([0.0, 0.0, 1.0], Some([0.0, 10.0, 1.0]));
    assert!(close(z, [0.0, -1.0, 0.0]) && close(x, [1.0, 0.0, 0.0]), "{x:?} {z:?}");
    assert!(close(y, [0.0, 0.0, 1.0]), "{y:?}");
    // Aimed east: C = 0 falls back to north.
    let [x, _, z] = luminaire_frame([0.0, 0.0, 1.0], Some([3.0, 0.0, 1.0]));
    assert!(close(z, [-1.0, 0.0, 0.0]) && close(x, [0.0, 1.0, 0.0]), "{x:?} {z:?}");
}
use std::path::PathBuf;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/photometric");
const ASA: &str = "luxcore_ASA_15M_R2.ies";
const SPEC: &str = "lidrs_iesna2002_spec_example_tilt_include.ies";
const BEGA_ROUND: &str = "threejs_BEGA_50975.6K3_007cfb11e343e2f42e3b476be4ab684e.ies";
const BEGA_24: &str = "threejs_BEGA_50899.2K3_06b4cfdc8805709e767b5e2e904be8ad.ies";
const DT106: &str = "threejs_LightLab_DT106_absolute_1a936937a49c63374e6d4fbed9252b29.ies";
const PROLICHT: &str = "lidrs_prolicht_E30-0019_example.ldt";
const ISOTROPIC: &str = "isotropic_1000cd.ies";
const LAMBERT: &str = "lambertian_cos_1000cd.ies";
const ASYMMETRIC: &str = "asymmetric_24_planes.ies";

/// The flux of the distribution the table defines, interpolated linearly in γ and in C (the
/// C planes wrap round the circle; one plane is rotationally symmetric), computed in closed
/// form from the table alone and not by `flux_lm`: over a band [γ₀, γ₁] where
/// I = I₀ + s(γ − γ₀), ∫ I sin γ dγ = I₀(cos γ₀ − cos γ₁) + s(sin γ₁ − sin γ₀ − (γ₁ − γ₀) cos γ₁),
/// and a linear interpolation round the circle averages as the trapezoid rule does.
fn bilinear_flux_lm(p: &Photometry) -> f64 {
    let gammas: Vec<f64> = p.gamma_deg.iter().map(|g| g.to_radians()).collect();
    let plane_integral = |row: &[f64]| -> f64 {
        (1..gammas.len())
            .map(|k| {
                let (g0, g1) = (gammas[k - 1], gammas[k]);
                let slope = (row[k] - row[k - 1]) / (g1 - g0);
                row[k - 1] * (g0.cos() - g1.cos())
                    + slope * (g1.sin() - g0.sin() - (g1 - g0) * g1.cos())
            })
            .sum()
    };
    let planes: Vec<f64> = p.candela.iter().map(|row| plane_integral(row)).collect();
    if planes.len() == 1 {
        return 2.0 * PI * planes[0];
    }
    let c = &p.c_deg;
    (0..planes.len())
        .map(|k| {
            let next = (k + 1) % planes.len();
            let width_deg = if next == 0 { 360.0 - c[k] + c[0] } else { c[next] - c[k] };
            width_deg.to_radians() * 0.5 * (planes[k] + planes[next])
        })
        .sum()
}

fn data(name: &str) -> PathBuf {
    Path::new(DATA).join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn ies(name: &str) -> IesFile {
    read_ies(&text(name), &data(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn ldt(name: &str) -> LdtFile {
    read_ldt(&text(name), &data(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// The error of parsing `source` as IES, as text (the test fails if it parses).
fn ies_error(source: &str) -> (SceneError, String) {
    match read_ies(source, Path::new("bad.ies")) {
        Ok(_) => panic!("parsed, but should have been refused:\n{source}"),
        Err(e) => {
            let message = e.to_string();
            (e, message)
        }
    }
}

fn ldt_error(source: &str) -> (SceneError, String) {
    match read_ldt(source, Path::new("bad.ldt")) {
        Ok(_) => panic!("parsed, but should have been refused"),
        Err(e) => {
            let message = e.to_string();
            (e, message)
        }
    }
}

fn assert_close(actual: f64, expected: f64, relative: f64) {
    let tolerance = relative * expected.abs().max(1e-300);
    assert!(
        (actual - expected).abs() <= tolerance,
        "{actual} differs from {expected} by more than {relative} relative"
    );
}

fn assert_contains(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "message lacks '{part}': {message}");
    }
}

/// Replaces exactly one occurrence of `from` (the test data must contain it once).
fn edit(source: &str, from: &str, to: &str) -> String {
    assert_eq!(source.matches(from).count(), 1, "'{from}' must occur once");
    source.replacen(from, to, 1)
}

// ---- ideal distributions written by hand ----------------------------------------------

#[test]
fn isotropic_source_is_1000_cd_everywhere_and_4_pi_klm() {
    let p = ies(ISOTROPIC).photometry;
    let directions = [
        [0.0, 0.0, -1.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, -3.0, 0.0],
        [1.0, 1.0, 1.0],
        [-0.3, 0.7, -0.2],
        [5.0, -2.0, 9.0],
        [1e-200, 1e-200, -1e-200],
        [1e200, -1e200, 1e200],
    ];
    for d in directions {
        assert_close(p.intensity_cd(d), 1000.0, 1e-12);
    }
    for (c, g) in [(0.0, 0.0), (17.0, 33.3), (359.9, 179.9), (-45.0, 90.0), (720.5, 180.0)] {
        assert_close(p.intensity_at(c, g), 1000.0, 1e-12);
    }
    assert_close(p.flux_lm(), 4.0 * PI * 1000.0, 1e-3);
    assert_eq!(p.peak_cd(), 1000.0);
}

#[test]
fn lambertian_downlight_gives_pi_times_i0() {
    let p = ies(LAMBERT).photometry;
    // ∫ I0 cos γ dΩ over the lower hemisphere = 2π · I0 · ½ = π · I0.
    let flux = p.flux_lm();
    eprintln!("Lambertian I0 = 1000 cd at 2.5° steps: {flux} lm, π·I0 = {}", PI * 1000.0);
    assert_close(flux, PI * 1000.0, 1e-3);
    assert_eq!(p.intensity_at(0.0, 60.0), 500.0); // "500.000000" in the file
    let d60 = [60f64.to_radians().sin(), 0.0, -60f64.to_radians().cos()];
    assert_close(p.intensity_cd(d60), 500.0, 1e-9);
    assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 0.0);
}

/// The beam (50 % of the peak, as an equivalent cone): a Lambertian downlight I0 cos γ is
/// at half its peak at γ = 60°, so its beam is 120°; an isotropic source fills the sphere.
#[test]
fn beam_angles_of_ideal_distributions() {
    let lambert = ies(LAMBERT).photometry.beam_angle_deg();
    assert!((lambert - 120.0).abs() < 0.5, "Lambertian beam {lambert}°");
    let sphere = ies(ISOTROPIC).photometry.beam_angle_deg();
    assert!((sphere - 360.0).abs() < 0.5, "isotropic beam {sphere}°");
}

#[test]
fn flux_of_a_web_that_is_linear_in_gamma_is_exact() {
    // Plane k (C = 15k) holds 100(k+1) + γ/45° at γ = 0, 45, …, 180, which is linear in γ,
    // so ∫ I sin γ dγ = 2·100(k+1) + 4 exactly, each of the 24 sectors is 15° = π/12 wide
    // (the wrap 345°→360° included), and the flux is (π/12)·Σ(200(k+1) + 4) = 5008π.
    let p = ies(ASYMMETRIC).photometry;
    assert_close(p.flux_lm(), 5008.0 * PI, 1e-12);
}

// ---- interpolation ----------------------------------------------------------------------

#[test]
fn halfway_between_gamma_samples_is_the_mean() {
    let p = ies(ASYMMETRIC).photometry;
    // Plane C = 15 (k = 1): 200 at γ = 0, 201 at γ = 45.
    assert_eq!(p.intensity_at(15.0, 22.5), (200.0 + 201.0) / 2.0);
    let asa = ies(ASA).photometry;
    // ASA 15M, plane C = 0: 1666 cd at γ = 0, 1817 cd at γ = 2.5.
    assert_eq!(asa.intensity_at(0.0, 1.25), (1666.0 + 1817.0) / 2.0);
}

#[test]
fn c_wraps_around_360() {
    let p = ies(ASYMMETRIC).photometry;
    assert_eq!(p.c_deg.len(), 24);
    // C = 359 lies 14/15 of the way from the 345° plane (2400 at γ = 0) to 0°/360° (100).
    let expected = (2400.0 + 14.0 * 100.0) / 15.0;
    assert_close(p.intensity_at(359.0, 0.0), expected, 1e-12);
    assert_close(p.intensity_at(-1.0, 0.0), expected, 1e-12);
    assert_close(p.intensity_at(719.0, 0.0), expected, 1e-12);
    // Halfway across the wrap at γ = 45: mean of 2401 and 101.
    assert_close(p.intensity_at(352.5, 45.0), 1251.0, 1e-12);
    // Real file: BEGA 50899 has planes 0..345 without a 360° plane, all 2160.3 at γ = 0.
    let bega = ies(BEGA_24).photometry;
    assert_close(bega.intensity_at(359.0, 0.0), 2160.3, 1e-12);
}

#[test]
fn directions_map_to_type_c_angles() {
    let p = ies(ASYMMETRIC).photometry;
    // 100(k+1) + g with k = C/15 and g the γ index (γ = 90 → g = 2).
    assert_eq!(p.intensity_cd([1.0, 0.0, 0.0]), 102.0); // C 0, γ 90
    assert_eq!(p.intensity_cd([0.0, 2.0, 0.0]), 702.0); // C 90 (+Y)
    assert_eq!(p.intensity_cd([-1.0, 0.0, 0.0]), 1302.0); // C 180
    assert_eq!(p.intensity_cd([0.0, -1.0, 0.0]), 1902.0); // C 270
    assert_eq!(p.intensity_cd([0.0, 0.0, -4.0]), 100.0); // nadir, −Z
    assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 104.0); // zenith
    let c30 = [30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0];
    assert_close(p.intensity_cd(c30), 302.0, 1e-12);
    // 45° below the horizon in the C = 90 plane: γ = 45.
    assert_close(p.intensity_cd([0.0, 1.0, -1.0]), 701.0, 1e-12);
    assert_eq!(p.intensity_cd([0.0, 0.0, 0.0]), 0.0);
    assert_eq!(p.intensity_cd([f64::NAN, 1.0, 0.0]), 0.0);
    assert_eq!(p.intensity_cd([f64::INFINITY, 1.0, 0.0]), 0.0);
    assert_eq!(p.intensity_at(f64::NAN, 10.0), 0.0);
}

// ---- the real files ---------------------------------------------------------------------

#[test]
fn asa_15m_street_light() {
    let file = ies(ASA);
    let p = &file.photometry;
    assert_eq!(file.version, IesVersion::Lm2002);
    assert_eq!((file.lamps, file.lumens_per_lamp, file.scale), (1.0, 13000.0, 1.0));
    assert!(file.tilt.is_none());
    assert_contains(&p.description, &["MANUFAC: American Electric Lighting", "LUMCAT: ASA 15M R2"]);
    assert_eq!(p.gamma_deg.len(), 37);
    // 0–180 bilateral: 73 planes 0..180 and their 71 mirror images 182.5..357.5.
    assert_eq!(p.c_deg.len(), 144);
    assert_eq!(p.c_deg.last(), Some(&357.5));
    // Values in the file (multiplier, ballast factor and lamp factor all 1).
    assert_eq!(p.intensity_at(0.0, 0.0), 1666.0);
    assert_eq!(p.intensity_at(0.0, 2.5), 1817.0);
    assert_eq!(p.intensity_at(2.5, 5.0), 2019.0);
    assert_eq!(p.intensity_at(180.0, 2.5), 1548.0);
    assert_eq!(p.intensity_at(180.0, 87.5), 3.0);
    assert_eq!(p.intensity_at(177.5, 2.5), 1559.0);
    // The mirror images about the 0–180 plane.
    assert_eq!(p.intensity_at(357.5, 5.0), 2019.0);
    assert_eq!(p.intensity_at(182.5, 2.5), 1559.0);
    // Measured only up to γ = 90°: nothing above.
    assert_eq!(p.intensity_at(0.0, 90.5), 0.0);
    assert_eq!(p.intensity_cd([0.0, 0.0, 1.0]), 0.0);
    let lamp_lumens = file.lamps * file.lumens_per_lamp;
    let flux = p.flux_lm();
    eprintln!(
        "ASA 15M R2: integrated {flux:.1} lm, lamp {lamp_lumens} lm, ratio {:.4}, peak {} cd",
        flux / lamp_lumens,
        p.peak_cd()
    );
    assert!(flux > 0.0 && flux < lamp_lumens * 1.01, "{flux} lm");
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

#[test]
fn spec_example_reads_its_inline_tilt_table_and_quadrant_symmetry() {
    let file = ies(SPEC);
    let tilt = file.tilt.as_ref().expect("TILT=INCLUDE");
    assert_eq!(tilt.geometry, 1);
    let angles: Vec<f64> = (0..13).map(|i| 15.0 * f64::from(i)).collect();
    assert_eq!(tilt.angles, angles);
    let factors = [1.0, 0.95, 0.94, 0.90, 0.88, 0.87, 0.98, 0.87, 0.88, 0.90, 0.94, 0.95, 1.0];
    assert_eq!(tilt.factors, factors);
    assert_eq!(tilt.factor, 1.0);
    let p = &file.photometry;
    assert_contains(&p.description, &["MANUFAC: Aardvark lighting Inc.", "LAMP: 400 Watt"]);
    assert_eq!(p.gamma_deg, [0.0, 22.5, 45.0, 67.5, 90.0]);
    assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
    assert_eq!(p.intensity_at(0.0, 22.5), 50000.0);
    assert_eq!(p.intensity_at(45.0, 22.5), 35000.0);
    assert_eq!(p.intensity_at(90.0, 90.0), 1000.0);
    // Quadrant symmetry: 135 ↔ 45, 180 ↔ 0, 225 ↔ 45, 270 ↔ 90, 315 ↔ 45.
    assert_eq!(p.intensity_at(135.0, 22.5), 35000.0);
    assert_eq!(p.intensity_at(180.0, 22.5), 50000.0);
    assert_eq!(p.intensity_at(225.0, 45.0), 16000.0);
    assert_eq!(p.intensity_at(270.0, 90.0), 1000.0);
    assert_eq!(p.intensity_at(315.0, 67.5), 8000.0);
    let lamp = file.lamps * file.lumens_per_lamp;
    let flux = p.flux_lm();
    // A made-up example (100 000 cd at the nadir from a 50 000 lm lamp): its integrated
    // flux exceeds the lamp lumens, so it is checked against the table's own flux.
    eprintln!(
        "LM-63-2002 spec example: integrated {flux:.0} lm, lamp {lamp} lm, ratio {:.4}",
        flux / lamp
    );
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

#[test]
fn tilt_factor_at_zero_is_applied_and_interpolated() {
    let source = text(SPEC);
    let halved = edit(&source, "1.0 .95 .94", "0.5 .95 .94");
    let p = read_ies(&halved, Path::new("halved.ies")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.photometry.intensity_at(0.0, 0.0), 50000.0);
    // A table from −10° (0.8) to 10° (1.0): 0.9 at 0°.
    let between = edit(
        &source,
        "13\n0 15 30 45 60 75 90 105 120 135 150 165 180\n\
         1.0 .95 .94 .90 .88 .87 .98 .87 .88 .90 .94 .95 1.0",
        "2\n-10 10\n0.8 1.0",
    );
    let p = read_ies(&between, Path::new("between.ies")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.tilt.as_ref().map(|t| t.factor), Some((0.5 * 0.8) + (0.5 * 1.0)));
    assert_close(p.photometry.intensity_at(0.0, 0.0), 90000.0, 1e-12);
}

#[test]
fn bega_50975_rotationally_symmetric_absolute() {
    let file = ies(BEGA_ROUND);
    let p = &file.photometry;
    assert_eq!(file.version, IesVersion::Lm1995);
    assert_eq!(file.lumens_per_lamp, -1.0);
    assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (1, 73));
    assert_eq!(p.intensity_at(0.0, 0.0), 330.8);
    assert_eq!(p.intensity_at(0.0, 22.5), 302.1);
    assert_eq!(p.intensity_at(123.0, 22.5), 302.1);
    assert_eq!(p.intensity_at(250.0, 180.0), 0.0);
    let flux = p.flux_lm();
    // Absolute photometry: the luminaire's own flux, as its [LAMP] line gives it.
    eprintln!("BEGA 50975.6K3 (absolute): integrated {flux:.1} lm; [LAMP] says 321 lm");
    assert_close(flux, 321.0, 5e-3);
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

#[test]
fn bega_50899_full_circle_without_closing_plane() {
    let file = ies(BEGA_24);
    let p = &file.photometry;
    assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (24, 19));
    assert_eq!(p.c_deg.last(), Some(&345.0));
    assert_eq!(p.intensity_at(0.0, 0.0), 2160.3);
    assert_eq!(p.intensity_at(345.0, 40.0), 284.6);
    assert_eq!(p.intensity_at(90.0, 90.0), 0.0);
    let flux = p.flux_lm();
    eprintln!("BEGA 50899.2K3 (absolute): integrated {flux:.1} lm; [LAMP] says 1221 lm");
    assert_close(flux, 1221.0, 5e-3);
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

#[test]
fn dt106_candela_multiplier_is_applied() {
    let file = ies(DT106);
    let p = &file.photometry;
    assert_eq!(file.scale, 1.498);
    assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (1, 181));
    assert_eq!(p.intensity_at(0.0, 0.0), 9769.798 * 1.498);
    assert_eq!(p.intensity_at(0.0, 0.5), 9766.099 * 1.498);
    assert_eq!(p.intensity_at(200.0, 10.0), 3310.188 * 1.498);
    assert_eq!(p.intensity_at(0.0, 90.0), 0.0);
    assert_eq!(p.peak_cd(), 9769.798 * 1.498);
    let flux = p.flux_lm();
    // The report states no flux: the table's own, times the multiplier.
    eprintln!("DT106 (absolute, ×1.498): integrated {flux:.1} lm");
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

#[test]
fn prolicht_eulumdat() {
    let file = ldt(PROLICHT);
    let p = &file.photometry;
    assert_eq!((file.isym, file.mc, file.ng), (0, 20, 37));
    assert_eq!((file.lamps, file.lamp_flux_lm, file.conversion_factor), (1, 5134.0, 1.0));
    assert_eq!((file.dff_percent, file.lor_percent), (100.0, 100.0));
    assert_eq!((p.c_deg.len(), p.gamma_deg.len()), (20, 37));
    assert_eq!(p.c_deg.get(19), Some(&342.0));
    assert_contains(&p.description, &["Ingemann", "Prolicht E30-0019"]);
    // cd/klm × 5134 lm / 1000 (conversion factor 1.0).
    let klm = 1.0 * 5134.0 / 1000.0;
    assert_eq!(p.intensity_at(0.0, 0.0), 270.1222 * klm);
    assert_eq!(p.intensity_at(0.0, 5.0), 273.82946 * klm);
    assert_eq!(p.intensity_at(18.0, 15.0), 274.09588 * klm);
    assert_eq!(p.intensity_at(342.0, 90.0), 5.36604 * klm);
    assert_eq!(p.intensity_at(342.0, 180.0), 97.45574 * klm);
    // Wrap between C342 and C360 = C0 at γ = 0, both 270.1222.
    assert_close(p.intensity_at(351.0, 0.0), 270.1222 * klm, 1e-12);
    let flux = p.flux_lm();
    let declared = file.lamp_flux_lm * file.lor_percent / 100.0;
    let downward: f64 = {
        let lower = Photometry {
            gamma_deg: p.gamma_deg.iter().copied().filter(|&g| g <= 90.0).collect(),
            c_deg: p.c_deg.clone(),
            candela: p.candela.iter().map(|r| r.iter().take(19).copied().collect()).collect(),
            description: String::new(),
        };
        lower.flux_lm()
    };
    eprintln!(
        "Prolicht E30-0019: integrated {flux:.1} lm; lamp flux {} lm × LOR {} % = {declared} \
         lm; ratio {:.4}; downward {:.1} % (DFF says {} %)",
        file.lamp_flux_lm,
        file.lor_percent,
        flux / declared,
        100.0 * downward / flux,
        file.dff_percent
    );
    // The light output ratio of 100 % says the luminaire emits the lamp's whole flux.
    assert_close(flux, declared, 2e-3);
    assert_close(flux, bilinear_flux_lm(p), 1e-3);
}

// ---- symmetries -------------------------------------------------------------------------

#[test]
fn ies_bilateral_about_90_270() {
    let p = ies("bilateral_90_270.ies").photometry;
    assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
    // C ↔ 180 − C: 0 ↔ 180 (30), 45 ↔ 135 (20), 315 ↔ 225 (40).
    assert_eq!(p.intensity_at(0.0, 0.0), 30.0);
    assert_eq!(p.intensity_at(45.0, 90.0), 21.0);
    assert_eq!(p.intensity_at(315.0, 180.0), 42.0);
    assert_eq!(p.intensity_at(270.0, 0.0), 50.0);
    assert_eq!(p.intensity_at(22.5, 0.0), 25.0);
}

#[test]
fn eulumdat_isym_3_stores_c270_through_c0_to_c90() {
    let file = ldt("ldt_isym3_c90_c270.ldt");
    let p = &file.photometry;
    assert_eq!(p.c_deg, [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]);
    // Stored C270 50.., C315 40.., C0 10.., C45 20.., C90 30.., × 2000 lm / 1000 (field
    // 26c is the total of the 2 lamps, not multiplied again).
    assert_eq!(p.intensity_at(270.0, 0.0), 100.0);
    assert_eq!(p.intensity_at(315.0, 0.0), 80.0);
    assert_eq!(p.intensity_at(0.0, 0.0), 20.0);
    assert_eq!(p.intensity_at(45.0, 0.0), 40.0);
    assert_eq!(p.intensity_at(90.0, 0.0), 60.0);
    // Mirrors C ↔ 180 − C: 135 ↔ 45, 180 ↔ 0, 225 ↔ 315.
    assert_eq!(p.intensity_at(135.0, 0.0), 40.0);
    assert_eq!(p.intensity_at(180.0, 90.0), 22.0);
    assert_eq!(p.intensity_at(225.0, 180.0), 84.0);
}

#[test]
fn eulumdat_isym_4_and_2() {
    let p = ldt("ldt_isym4_quadrant.ldt").photometry;
    assert_eq!(p.c_deg.len(), 8);
    let expected = [20.0, 40.0, 60.0, 40.0, 20.0, 40.0, 60.0, 40.0];
    for (c, e) in p.c_deg.iter().zip(expected) {
        assert_eq!(p.intensity_at(*c, 0.0), e, "C {c}");
    }
    let p = ldt("ldt_isym2_c0_c180.ldt").photometry;
    assert_eq!(p.c_deg.len(), 8);
    let expected = [20.0, 40.0, 60.0, 80.0, 100.0, 80.0, 60.0, 40.0];
    for (c, e) in p.c_deg.iter().zip(expected) {
        assert_eq!(p.intensity_at(*c, 0.0), e, "C {c}");
    }
}

#[test]
fn eulumdat_isym_1_with_negative_lamp_count() {
    let file = ldt("ldt_isym1_absolute.ldt");
    assert_eq!(file.lamps, -1);
    let p = &file.photometry;
    assert_eq!(p.c_deg, [0.0]);
    // 100, 50, 0 cd/klm × conversion factor 2 × 1000 lm / 1000.
    assert_eq!(p.intensity_at(0.0, 0.0), 200.0);
    assert_eq!(p.intensity_at(77.0, 90.0), 100.0);
    assert_eq!(p.intensity_at(300.0, 45.0), 150.0);
}

#[test]
fn lm63_1986_and_its_ballast_lamp_factor() {
    let source = text("lm63_1986_no_version_line.ies");
    let file = read_ies(&source, Path::new("old.ies")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(file.version, IesVersion::Lm1986);
    assert_contains(&file.photometry.description, &["LM-63-1986 layout"]);
    // 2 × 0.5 × 0.9.
    assert_close(file.photometry.intensity_at(0.0, 0.0), 90.0, 1e-12);
    // Quadrant symmetry: 315 ↔ 45 (40 × 0.9), 270 ↔ 90 (30 × 0.9).
    assert_close(file.photometry.intensity_at(315.0, 45.0), 36.0, 1e-12);
    assert_close(file.photometry.intensity_at(270.0, 45.0), 27.0, 1e-12);
    // In an LM-63-2002 file the same field is "future use" and is not applied.
    let file = read_ies(&format!("IESNA:LM-63-2002\n{source}"), Path::new("new.ies"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(file.photometry.intensity_at(0.0, 0.0), 100.0);
}

// ---- load -------------------------------------------------------------------------------

#[test]
fn load_dispatches_on_the_extension() {
    assert_eq!(
        load(&data(ISOTROPIC)).map(|p| p.peak_cd()).unwrap_or_else(|e| panic!("{e}")),
        1000.0
    );
    assert_eq!(load(&data(PROLICHT)).map(|p| p.c_deg.len()).unwrap_or_else(|e| panic!("{e}")), 20);
    let upper =
        std::env::temp_dir().join(format!("restauro_photometric_{}.LDT", std::process::id()));
    std::fs::write(&upper, text("ldt_isym1_absolute.ldt")).unwrap_or_else(|e| panic!("{e}"));
    let loaded = load(&upper);
    let _ = std::fs::remove_file(&upper);
    assert_eq!(loaded.map(|p| p.peak_cd()).unwrap_or_else(|e| panic!("{e}")), 200.0);

    let message = load(Path::new("lamp.xyz")).map(|_| ()).unwrap_err().to_string();
    assert_contains(&message, &["lamp.xyz", "'.xyz'", ".ies", ".ldt"]);
    let message = load(Path::new("lamp")).map(|_| ()).unwrap_err().to_string();
    assert_contains(&message, &["no extension"]);
    assert!(matches!(load(Path::new("/nonexistent/lamp.ies")), Err(SceneError::Io { .. })));
    assert_eq!(decode_text(vec![b'A', 0xE9]), "Aé");
}

// ---- refusals ---------------------------------------------------------------------------

#[test]
fn refuses_a_candela_count_that_does_not_match_the_angles() {
    let source = text(ISOTROPIC);
    let (_, message) = ies_error(source.trim_end().strip_suffix(" 1000").unwrap_or(""));
    assert_contains(&message, &["bad.ies", "expected 13, found 12", "1 horizontal × 13 vertical"]);
    let (e, message) = ies_error(&format!("{source} 1000 7\n"));
    assert_contains(&message, &["expected 13, found 15", "'1000'"]);
    assert!(matches!(e, SceneError::Syntax { line: 12, column: 2, .. }), "{e:?}");
    let (_, message) = ldt_error(&format!("{}5\n", text("ldt_isym4_quadrant.ldt")));
    assert_contains(&message, &["bad.ldt", "expected 9, found 10"]);
    let (_, message) =
        ldt_error(text("ldt_isym4_quadrant.ldt").trim_end().strip_suffix("32").unwrap_or(""));
    assert_contains(&message, &["expected 9, found 8"]);
}

#[test]
fn refuses_angles_not_increasing_or_out_of_range() {
    let source = text(ISOTROPIC);
    let (e, message) = ies_error(&edit(&source, "0 15 30 45", "0 15 45 30"));
    assert_contains(&message, &["bad.ies:9:9", "vertical angle 4 of 13 is 30°", "increasing"]);
    assert!(matches!(e, SceneError::Syntax { line: 9, column: 9, .. }));
    let (_, message) = ies_error(&edit(&source, "165 180", "165 190"));
    assert_contains(&message, &["vertical angle 13 of 13 is 190°", "outside 0..180"]);
    let (_, message) = ies_error(&edit(&source, "0 15 30 45", "-5 15 30 45"));
    assert_contains(&message, &["vertical angle 1 of 13 is -5°"]);
    let ldt_source = text("ldt_isym4_quadrant.ldt");
    let (_, message) = ldt_error(&edit(&ldt_source, "\n0\n90\n180\n10\n", "\n0\n190\n180\n10\n"));
    assert_contains(&message, &["γ angle (field 29) 2 of 3 is 190°", "outside 0..180"]);
    let (_, message) = ldt_error(&edit(&ldt_source, "\n45\n90\n135\n", "\n45\n40\n135\n"));
    assert_contains(&message, &["C-angle (field 28) 3 of 8 is 40°", "not greater"]);
    let (_, message) = ies_error(&edit(&text(ASYMMETRIC), "\n195 210", "\n150 210"));
    assert_contains(&message, &["bad.ies:11:1", "horizontal angle 14 of 24 is 150°", "(180°)"]);
}

#[test]
fn refuses_horizontal_ranges_that_are_no_lm63_symmetry() {
    let source = text("bilateral_90_270.ies");
    let (e, message) = ies_error(&edit(&source, "90 135 180 225 270", "90 135 180 225 260"));
    assert!(matches!(e, SceneError::Invalid { .. }));
    assert_contains(&message, &["horizontal angles (from line 10:1)", "90° to 260°", "re-export"]);
}

#[test]
fn refuses_negative_or_non_finite_intensities_and_multipliers() {
    let source = text(ISOTROPIC);
    let last_row = "1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000";
    let (_, message) = ies_error(&edit(
        &source,
        last_row,
        "1000 1000 -5 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000",
    ));
    assert_contains(&message, &["bad.ies:11:11", "C = 0°, γ = 30°", "-5, negative"]);
    let (_, message) = ies_error(&edit(
        &source,
        last_row,
        "1000 nan 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000",
    ));
    assert_contains(&message, &["'nan', not a finite number"]);
    let lamp_line = "1 -1 1 13 1 1 2 0 0 0";
    let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 -2 13 1 1 2 0 0 0"));
    assert_contains(&message, &["bad.ies:7:6", "candela multiplier is -2", "negative multiplier"]);
    let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 inf 13 1 1 2 0 0 0"));
    assert_contains(&message, &["candela multiplier is 'inf', not a finite number"]);
    let (_, message) = ies_error(&edit(&source, "\n1 1 0\n", "\n-0.5 1 0\n"));
    assert_contains(&message, &["ballast factor is -0.5"]);
    let (_, message) = ies_error(&edit(&source, lamp_line, "1 -7 1 13 1 1 2 0 0 0"));
    assert_contains(&message, &["lumens per lamp is -7", "-1 for absolute photometry"]);
    let (_, message) = ies_error(&edit(&text(SPEC), "1.0 .95 .94", "1.0 -.95 .94"));
    assert_contains(&message, &["tilt multiplying factor 2 of 13 is -0.95"]);
    let ldt_source = text("ldt_isym1_absolute.ldt");
    let (_, message) = ldt_error(&edit(&ldt_source, "\n100\n50\n0\n", "\n100\n-50\n0\n"));
    assert_contains(&message, &["bad.ldt:48:1", "γ = 90°", "-50, negative"]);
    let (_, message) = ldt_error(&edit(&ldt_source, "\n2.0\n", "\n-2.0\n"));
    assert_contains(&message, &["bad.ldt:24:1", "conversion factor", "-2"]);
    let (_, message) = ldt_error(&edit(&ldt_source, "\n1000\n", "\n0\n"));
    assert_contains(&message, &["bad.ldt:29:1", "field 26c", "is 0 lm"]);
}

#[test]
fn refuses_a_missing_tilt_line_and_external_tilt_files() {
    let source = text(ISOTROPIC);
    let (e, message) = ies_error(&edit(&source, "TILT=NONE\n", ""));
    assert!(matches!(e, SceneError::Invalid { .. }));
    assert_contains(&message, &["bad.ies", "no TILT= line", "TILT=NONE"]);
    let (e, message) = ies_error(&edit(&source, "TILT=NONE", "TILT=aardvark.tlt"));
    assert_contains(&message, &["bad.ies:6:6", "TILT=aardvark.tlt", "inline", "TILT=INCLUDE"]);
    assert!(matches!(e, SceneError::Syntax { line: 6, .. }));
    let (_, message) = ies_error(&edit(&source, "TILT=NONE", "TILT="));
    assert_contains(&message, &["TILT= has no value"]);
    let (_, message) = ies_error(&edit(&text(SPEC), "TILT=INCLUDE\n1\n", "TILT=INCLUDE\n7\n"));
    assert_contains(&message, &["lamp-to-luminaire geometry '7'"]);
}

#[test]
fn refuses_truncated_files() {
    let source = text(ASA);
    let cut = source.get(..source.len() / 2).unwrap_or("");
    let (_, message) = ies_error(cut);
    assert_contains(&message, &["expected 2701", "truncated", "73 horizontal × 37 vertical"]);
    let header_only = source.get(..source.find("TILT=NONE").unwrap_or(0) + 10).unwrap_or("");
    let (_, message) = ies_error(header_only);
    assert_contains(&message, &["ends before the number of lamps", "truncated"]);
    let (_, message) = ies_error(&edit(
        &text(ISOTROPIC),
        "0 15 30 45 60 75 90 105 120 135 150 165 180\n0\n1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000 1000\n",
        "0 15 30\n",
    ));
    assert_contains(&message, &["ends before vertical angle 4 of 13"]);
    let ldt_source = text(PROLICHT);
    let (e, message) = ldt_error(&ldt_source.lines().take(20).collect::<Vec<_>>().join("\n"));
    assert_contains(&message, &["bad.ldt:20:", "before line 21", "C270 (field 21)", "truncated"]);
    assert!(matches!(e, SceneError::Syntax { line: 20, .. }));
    let (_, message) = ldt_error(&ldt_source.lines().take(500).collect::<Vec<_>>().join("\n"));
    assert_contains(&message, &["expected 740, found 401", "truncated"]);
    let (_, message) = ies_error("");
    assert_contains(&message, &["no TILT= line"]);
    let (_, message) = ldt_error("");
    assert_contains(&message, &["truncated"]);
}

#[test]
fn refuses_unknown_and_unsupported_photometric_types() {
    let source = text(ISOTROPIC);
    let lamp_line = "1 -1 1 13 1 1 2 0 0 0";
    let (e, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 4 2 0 0 0"));
    assert_contains(&message, &["bad.ies:7:13", "photometric type '4' is unknown"]);
    assert!(matches!(e, SceneError::Syntax { line: 7, column: 13, .. }));
    let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 2 2 0 0 0"));
    assert_contains(&message, &["photometric type 2 (type B", "re-export the file as type C"]);
    let (_, message) = ies_error(&edit(&source, lamp_line, "1 -1 1 13 1 3 2 0 0 0"));
    assert_contains(&message, &["photometric type 3 (type A", "re-export the file as type C"]);
    let (_, message) =
        ldt_error(&edit(&text("ldt_isym4_quadrant.ldt"), "\n3\n4\n8\n", "\n3\n5\n8\n"));
    assert_contains(&message, &["bad.ldt:3:1", "symmetry indicator Isym", "is 5"]);
}

#[test]
fn refuses_more_than_100000_angles() {
    let source = text(ISOTROPIC);
    let (e, message) =
        ies_error(&edit(&source, "1 -1 1 13 1 1 2 0 0 0", "1 -1 1 200000 1 1 2 0 0 0"));
    assert!(matches!(e, SceneError::Limit { value: 200_000, limit: 100_000, .. }), "{e:?}");
    assert_contains(
        &message,
        &["number of vertical angles (line 7:8) is 200000", "limit of 100000"],
    );
    let (e, _) =
        ies_error(&edit(&source, "1 -1 1 13 1 1 2 0 0 0", "1 -1 1 100000 100000 1 2 0 0 0"));
    assert!(matches!(e, SceneError::Limit { value: 10_000_000_000, .. }), "{e:?}");
    let (e, message) =
        ldt_error(&edit(&text("ldt_isym4_quadrant.ldt"), "\n4\n8\n45\n", "\n4\n800000\n45\n"));
    assert!(matches!(e, SceneError::Limit { value: 800_000, .. }), "{e:?}");
    assert_contains(&message, &["number of C-planes Mc"]);
}

#[test]
fn refuses_text_where_a_number_belongs() {
    let (e, message) = ies_error(&edit(&text(ISOTROPIC), "\n1 1 0\n", "\n1 one 0\n"));
    assert_contains(&message, &["bad.ies:8:3", "'one'", "future use"]);
    assert!(matches!(e, SceneError::Syntax { line: 8, column: 3, .. }));
    let (_, message) =
        ldt_error(&edit(&text("ldt_isym4_quadrant.ldt"), "\n100\n100\n50\n", "\n100\nwide\n50\n"));
    assert_contains(&message, &["bad.ldt:14:1", "width of luminaire (field 14) is 'wide'"]);
    let (_, message) =
        ldt_error(&edit(&text("ldt_isym3_c90_c270.ldt"), "\n3\n8\n45\n", "\n3\n6\n45\n"));
    assert_contains(&message, &["Mc (field 4) is 6", "divisible by 4"]);
}

#[test]
fn accepts_decimal_commas_and_cr_line_ends_in_eulumdat() {
    let source = edit(&text("ldt_isym1_absolute.ldt"), "\n2.0\n", "\n2,0\n").replace('\n', "\r");
    let p = read_ldt(&source, Path::new("comma.ldt")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.photometry.intensity_at(0.0, 0.0), 200.0);
}

#[test]
fn never_panics_on_truncated_or_mangled_input() {
    for name in [SPEC, ISOTROPIC, "bilateral_90_270.ies", "ldt_isym3_c90_c270.ldt"] {
        let source = text(name);
        for (end, _) in source.char_indices() {
            let prefix = source.get(..end).unwrap_or("");
            let _ = read_ies(prefix, Path::new("cut.ies"));
            let _ = read_ldt(prefix, Path::new("cut.ldt"));
        }
    }
    // Replace single characters with troublesome ones, deterministically.
    let source = text(SPEC);
    let replacements = ["", "-", "9e999", "0", "\n", "x", "é", ",", "180", "1e5", "NaN"];
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    for _ in 0..3000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let positions: Vec<usize> = source.char_indices().map(|(i, _)| i).collect();
        let at = positions.get((state % positions.len() as u64) as usize).copied().unwrap_or(0);
        let with = replacements.get((state >> 32) as usize % replacements.len()).unwrap_or(&"");
        let mut mangled = String::from(source.get(..at).unwrap_or(""));
        mangled.push_str(with);
        mangled.push_str(source.get(at + 1..).unwrap_or(""));
        if let Ok(file) = read_ies(&mangled, Path::new("mangled.ies")) {
            let p = file.photometry;
            let _ = (p.flux_lm(), p.peak_cd(), p.intensity_cd([0.3, -0.2, -1.0]));
        }
    }
    // A hand-built, inconsistent Photometry must not panic either.
    let odd = Photometry {
        gamma_deg: vec![0.0, 90.0, 45.0],
        c_deg: vec![10.0, 5.0, 400.0],
        candela: vec![vec![1.0], vec![]],
        description: String::new(),
    };
    for c in [-10.0, 0.0, 7.0, 200.0, 399.0] {
        for g in [0.0, 30.0, 60.0, 89.0] {
            let _ = odd.intensity_at(c, g);
        }
    }
    let _ = (odd.flux_lm(), odd.peak_cd());
    let empty = Photometry {
        gamma_deg: vec![],
        c_deg: vec![],
        candela: vec![],
        description: String::new(),
    };
    assert_eq!((empty.flux_lm(), empty.peak_cd(), empty.intensity_at(0.0, 0.0)), (0.0, 0.0, 0.0));
}
