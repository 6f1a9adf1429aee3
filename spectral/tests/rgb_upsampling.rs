//! Jakob & Hanika (2019) RGB upsampling against its own colorimetry and against colour-science.
//!
//! `tests/data/jakob2019/reference.csv` was made by colour-science 0.4.7
//! (`tests/data/jakob2019/make.py`, see the README there): for 37 linear sRGB colours (the 24
//! ColorChecker patches, four greys, six saturated colours and the three sRGB primaries) it holds
//! colour-science's fitted spectrum on restauro's grid and that spectrum's XYZ under D65.

use restauro_spectral::colorimetry::{Observer, relative_xyz};
use restauro_spectral::illuminant::Illuminant;
use restauro_spectral::rgb_space::RgbSpace;
use restauro_spectral::rgb_upsampling::{RGB_EPSILON, fit, linear_srgb_of_xyz};
use restauro_spectral::{Spectrum, Xyz};

const REFERENCE: &str = include_str!("data/jakob2019/reference.csv");

struct Reference {
    name: String,
    rgb: [f64; 3],
    /// colour-science's CIE 1976 difference between its fit and the target.
    delta_e: f64,
    /// colour-science's XYZ of its spectrum, Y = 1 for white.
    xyz: [f64; 3],
    spectrum: [f64; 81],
}

fn references() -> Vec<Reference> {
    let mut lines = REFERENCE.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 14 + 81);
    assert_eq!((header[14], header[94]), ("380", "780"));
    let rows: Vec<Reference> = lines
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            let numbers: Vec<f64> = fields[1..].iter().map(|f| f.parse().unwrap()).collect();
            Reference {
                name: fields[0].to_owned(),
                rgb: [numbers[0], numbers[1], numbers[2]],
                delta_e: numbers[6],
                xyz: [numbers[10], numbers[11], numbers[12]],
                spectrum: std::array::from_fn(|i| numbers[13 + i]),
            }
        })
        .collect();
    assert_eq!(rows.len(), 37);
    rows
}

/// XYZ of a reflectance under D65 with the CIE 1931 2° observer, restauro's colorimetry, on the
/// scale Y = 1 for the perfect reflector.
fn xyz_of(reflectance: &Spectrum) -> Xyz {
    let d65 = Illuminant::D65.spd().unwrap();
    relative_xyz(reflectance, &d65, Observer::Cie1931TwoDegree).scale(0.01)
}

/// The 5×5×5 grid over the sRGB cube, 0, 0.25 … 1 per channel (clamped by the fit to
/// [1e-4, 1 − 1e-4]).
fn cube() -> Vec<[f64; 3]> {
    let levels = [0.0, 0.25, 0.5, 0.75, 1.0];
    let mut out = Vec::new();
    for r in levels {
        for g in levels {
            for b in levels {
                out.push([r, g, b]);
            }
        }
    }
    out
}

fn clamped(rgb: [f64; 3]) -> [f64; 3] {
    rgb.map(|v| v.clamp(RGB_EPSILON, 1.0 - RGB_EPSILON))
}

/// RGB → fit → spectrum → XYZ (restauro's colorimetry) → linear sRGB gives the input back.
///
/// Through restauro's IEC 61966-2-1 sRGB matrix ([`RgbSpace::Srgb`]) to 1e-3 per channel: that
/// matrix's white is D65 rounded to x, y = 0.3127, 0.3290, the fit's is D65 summed over the grid
/// (0.31272, 0.32903), which alone moves a channel by up to 2.7e-4. Through the fit's own
/// matrix (same primaries, the grid's white) to 1e-5, which tests the fit itself: it converges
/// to ΔE*ab ≤ 1e-8 and the f32 rounding of coefficients and spectrum costs about 1e-6.
#[test]
fn round_trip_recovers_the_colour() {
    let mut inputs: Vec<(String, [f64; 3])> =
        references().into_iter().map(|r| (r.name, r.rgb)).collect();
    inputs.extend(cube().into_iter().map(|rgb| (format!("cube {rgb:?}"), clamped(rgb))));
    let (mut worst_iec, mut worst_own) = (0.0f64, 0.0f64);
    for (name, rgb) in &inputs {
        let spectrum = fit(*rgb).unwrap_or_else(|e| panic!("{name}: {e}")).spectrum();
        let xyz = xyz_of(&spectrum);
        let iec = RgbSpace::Srgb.linear_from_xyz(xyz);
        let own = linear_srgb_of_xyz(xyz);
        for k in 0..3 {
            worst_iec = worst_iec.max((iec[k] - rgb[k]).abs());
            worst_own = worst_own.max((own[k] - rgb[k]).abs());
            assert!((iec[k] - rgb[k]).abs() <= 1e-3, "{name}: {rgb:?} came back as {iec:?}");
            assert!((own[k] - rgb[k]).abs() <= 1e-5, "{name}: {rgb:?} came back as {own:?}");
        }
    }
    eprintln!(
        "round trip of {} colours: largest channel error {worst_iec:.2e} through the IEC sRGB \
         matrix, {worst_own:.2e} through the fit's own",
        inputs.len()
    );
}

/// restauro's spectrum against colour-science's, band by band.
///
/// Both minimise the same objective, ΔE*ab under D65 (CIE 1931 2°, the same CIE tables, the same
/// 5 nm sums), whose minimum is a unique spectrum with ΔE*ab = 0 for every colour here. Both use
/// t = (λ − 380)/400, and any other affine normalisation of λ would span the same spectra (a
/// quadratic in t is one in λ): it changes the coefficients, not the fitted spectrum. What
/// separates the two, measured when this was written:
///
/// 1. restauro holds the CIE tables in f32 (every [`Spectrum`] does), 3e-8 of each value: the
///    objective moves by up to 1e-6 ΔE*ab, and re-running colour-science's own error function on
///    f32-rounded tables moves its converged spectrum by up to 2.8e-6 (the sRGB blue at 765 nm:
///    near the gamut's edge, where the colour-matching functions vanish, the colour hardly
///    constrains the spectrum, so a small change of objective moves it most);
/// 2. colour-science stops at ΔE*ab ≤ 1e-7 (make.py asks for that; each row records its value),
///    restauro at 1e-8: less than (1);
/// 3. restauro's coefficients and evaluation are f32: the coefficients (|c| ≤ 150 here) rounded to
///    2⁻²⁴ of their size and the Horner steps shift the sigmoid's argument by a few 1e-6, the
///    reflectance by at most S′ ≤ 1/2 of that, a few 1e-6 again.
///
/// Together under 1e-5, the tolerance; the largest difference is printed (5.6e-6 when written).
///
/// The colorimetry is checked first: restauro's XYZ of colour-science's spectrum must be
/// colour-science's XYZ to 1e-7 (the f32 of the spectrum and of the tables), else the two would
/// not be fitting the same thing.
#[test]
fn spectra_match_colour_science() {
    let mut worst = (0.0f64, String::new(), 0);
    for reference in references() {
        assert!(reference.delta_e <= 1e-7, "{}: {}", reference.name, reference.delta_e);
        let theirs = Spectrum(reference.spectrum.map(|v| v as f32));
        let xyz = xyz_of(&theirs).to_array();
        for k in 0..3 {
            // The f32 of the spectrum costs 6e-8 of each band.
            assert!(
                (xyz[k] - reference.xyz[k]).abs() <= 1e-7,
                "{}: restauro's XYZ of colour-science's spectrum {xyz:?} vs {:?}",
                reference.name,
                reference.xyz
            );
        }
        let ours = fit(reference.rgb).unwrap().spectrum();
        for (band, (&a, &b)) in ours.0.iter().zip(&reference.spectrum).enumerate() {
            let difference = (f64::from(a) - b).abs();
            if difference > worst.0 {
                worst = (difference, reference.name.clone(), band);
            }
            assert!(
                difference <= 1e-5,
                "{}, band {band}: restauro {a} vs colour-science {b}",
                reference.name
            );
        }
    }
    eprintln!(
        "largest difference from colour-science: {:.2e} ({}, {} nm)",
        worst.0,
        worst.1,
        380 + 5 * worst.2
    );
}

/// A grey is the flat spectrum of its value: the fit's white is the grid's D65, so the flat
/// spectrum has exactly the grey's colour. To 1e-6, tighter than the 1e-4 asked: what is left is
/// the f32 of the result.
#[test]
fn grey_gives_a_flat_spectrum() {
    for g in [0.0f64, 1e-3, 0.02, 0.18, 0.5, 0.9, 1.0] {
        let expected = g.clamp(RGB_EPSILON, 1.0 - RGB_EPSILON);
        let spectrum = fit([g; 3]).unwrap().spectrum();
        for (band, &v) in spectrum.0.iter().enumerate() {
            assert!((f64::from(v) - expected).abs() <= 1e-6, "grey {g}, band {band}: {v}");
        }
    }
}

/// Every fitted spectrum is a reflectance strictly inside (0, 1), in f32 as stored, for the
/// reference colours and the cube, corners included.
#[test]
fn fitted_spectra_lie_strictly_between_zero_and_one() {
    let mut inputs: Vec<[f64; 3]> = references().iter().map(|r| r.rgb).collect();
    inputs.extend(cube());
    for rgb in inputs {
        let spectrum = fit(rgb).unwrap().spectrum();
        assert!(
            spectrum.min_value() > 0.0 && spectrum.max_value() < 1.0,
            "{rgb:?}: {} … {}",
            spectrum.min_value(),
            spectrum.max_value()
        );
    }
}

/// The same colour always gives the same coefficients, bit for bit.
#[test]
fn fit_is_deterministic() {
    for rgb in cube() {
        assert_eq!(fit(rgb).unwrap(), fit(rgb).unwrap(), "{rgb:?}");
    }
}

/// Time per fit, printed (`cargo test --release -p restauro-spectral --test rgb_upsampling --
/// --ignored --nocapture fit_timing`). A benchmark, not a test: nothing is asserted, since a shared
/// machine's clock proves nothing, so it runs only when asked for.
#[test]
#[ignore = "a benchmark: run it with --ignored --nocapture"]
fn fit_timing() {
    let colours: Vec<[f64; 3]> = references().iter().map(|r| r.rgb).chain(cube()).collect();
    let repeats = 20;
    let start = std::time::Instant::now();
    let mut checksum = 0.0f32;
    for _ in 0..repeats {
        for &rgb in &colours {
            checksum += std::hint::black_box(fit(std::hint::black_box(rgb)).unwrap()).c[2];
        }
    }
    let per_fit = start.elapsed() / (repeats * colours.len()) as u32;
    eprintln!("{} fits, {per_fit:?} per fit (checksum {checksum})", repeats * colours.len());

    // And the evaluation the tracer does per hit: all 81 bands of a fitted spectrum.
    let fitted: Vec<_> = colours.iter().map(|&rgb| fit(rgb).unwrap()).collect();
    let repeats = 2000;
    let start = std::time::Instant::now();
    for _ in 0..repeats {
        for p in &fitted {
            checksum += std::hint::black_box(std::hint::black_box(p).spectrum())[40];
        }
    }
    let per_spectrum = start.elapsed() / (repeats * fitted.len()) as u32;
    eprintln!("{per_spectrum:?} per 81-band spectrum (checksum {checksum})");
}
