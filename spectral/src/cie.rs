//! The CIE tables, built into the crate from `data/cie/` (see `data/README.md` for provenance):
//! the CIE 1931 2° and CIE 1964 10° colour-matching functions, the photopic luminous efficiency
//! V(λ), illuminants A, B, C, D50, D55, D65, D75, E and F1–F12, and the daylight basis
//! S0, S1, S2. All are CIE 15:2004 / ISO/CIE 11664 tables at 5 nm, taken at the 81 grid
//! wavelengths without interpolation. Beside them, the constant that turns them into
//! photometric units, K_m = 683 lm/W.
//!
//! The tables are parsed from the embedded text the first time one is used. They are the
//! program's own data, checked by the tests below, so a malformed table is a build defect and
//! stops the program with a message rather than being reported as bad input.

use crate::grid::{BANDS, band_of};
use crate::spectrum::Spectrum;
use std::sync::LazyLock;

/// The maximum luminous efficacy of photopic vision, K_m = 683 lm/W (the paper's K_max; the SI
/// definition of the candela fixes 683 lm/W at 540 THz, CIE 15:2004 §7.1).
pub const K_M_LM_PER_W: f64 = 683.0;

const CMF_1931: &str = include_str!("../../data/cie/cie1931_2deg_xyz_cmf_5nm_380-780.csv");
const CMF_1964: &str = include_str!("../../data/cie/cie1964_10deg_xyz_cmf_5nm_380-780.csv");
const PHOTOPIC_V: &str = include_str!("../../data/cie/cie1924_photopic_V_5nm_380-780.csv");
const SCOTOPIC_V: &str = include_str!("../../data/cie/cie1951_scotopic_Vprime_5nm_380-780.csv");
const ILLUMINANTS: &str =
    include_str!("../../data/cie/cie_illuminants_A_B_C_D50_D55_D65_D75_E_5nm_380-780.csv");
const FLUORESCENT: &str = include_str!("../../data/cie/cie_fluorescent_FL1-FL12_5nm_380-780.csv");
const DAYLIGHT_BASIS: &str = include_str!("../../data/cie/cie_daylight_basis_S0_S1_S2.csv");

/// The columns of an embedded table, each as a spectrum on the grid. Rows at wavelengths off the
/// grid (the daylight basis runs 300–830 nm) are skipped; every grid wavelength must be present.
fn columns(name: &str, text: &str) -> (Vec<String>, Vec<Spectrum>) {
    let mut rows = text.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<String> = rows
        .next()
        .unwrap_or_else(|| panic!("embedded CIE table {name} is empty"))
        .split(',')
        .skip(1)
        .map(|s| s.trim().to_owned())
        .collect();
    let mut out = vec![Spectrum::ZERO; header.len()];
    let mut seen = [false; BANDS];
    for row in rows {
        let mut fields = row.split(',').map(|s| {
            s.trim()
                .parse::<f64>()
                .unwrap_or_else(|_| panic!("embedded CIE table {name}: bad row {row}"))
        });
        let wavelength =
            fields.next().unwrap_or_else(|| panic!("embedded CIE table {name}: empty row"));
        let Some(band) = band_of(wavelength) else {
            continue;
        };
        seen[band] = true;
        for (column, value) in out.iter_mut().zip(fields) {
            column[band] = value as f32;
        }
    }
    assert!(seen.iter().all(|&s| s), "embedded CIE table {name} misses grid wavelengths");
    (header, out)
}

/// A parsed table whose columns are taken by name.
struct Table {
    name: &'static str,
    header: Vec<String>,
    data: Vec<Spectrum>,
}

impl Table {
    fn parse(name: &'static str, text: &str) -> Self {
        let (header, data) = columns(name, text);
        Self { name, header, data }
    }

    fn column(&self, wanted: &str) -> Spectrum {
        let i =
            self.header.iter().position(|h| h == wanted).unwrap_or_else(|| {
                panic!("embedded CIE table {} has no column {wanted}", self.name)
            });
        self.data[i]
    }
}

pub(crate) struct Tables {
    pub cmf_1931: [Spectrum; 3],
    pub cmf_1964: [Spectrum; 3],
    pub photopic_v: Spectrum,
    pub a: Spectrum,
    pub b: Spectrum,
    pub c: Spectrum,
    pub d50: Spectrum,
    pub d55: Spectrum,
    pub d65: Spectrum,
    pub d75: Spectrum,
    pub e: Spectrum,
    pub scotopic_v: Spectrum,
    pub f: [Spectrum; 12],
    pub s0: Spectrum,
    pub s1: Spectrum,
    pub s2: Spectrum,
}

pub(crate) static TABLES: LazyLock<Tables> = LazyLock::new(|| {
    let cmf = |name, text| {
        let (_, c) = columns(name, text);
        [c[0], c[1], c[2]]
    };
    // Each table is parsed once and its columns taken by name.
    let illuminants = Table::parse("illuminants", ILLUMINANTS);
    let illuminant = |col| illuminants.column(col);
    let fluorescents = Table::parse("fluorescent", FLUORESCENT);
    let fluorescent = |i: usize| fluorescents.column(&format!("F{i}"));
    let daylight_basis = Table::parse("daylight basis", DAYLIGHT_BASIS);
    let basis = |col| daylight_basis.column(col);
    Tables {
        cmf_1931: cmf("CIE 1931 2°", CMF_1931),
        cmf_1964: cmf("CIE 1964 10°", CMF_1964),
        photopic_v: Table::parse("V(λ)", PHOTOPIC_V).column("photopic_V"),
        scotopic_v: Table::parse("V′(λ)", SCOTOPIC_V).column("scotopic_Vprime"),
        a: illuminant("A"),
        b: illuminant("B"),
        c: illuminant("C"),
        d50: illuminant("D50"),
        d55: illuminant("D55"),
        d65: illuminant("D65"),
        d75: illuminant("D75"),
        e: illuminant("E"),
        f: std::array::from_fn(|i| fluorescent(i + 1)),
        s0: basis("S0"),
        s1: basis("S1"),
        s2: basis("S2"),
    }
});

/// The CIE 1924 photopic luminous efficiency function V(λ) (CIE 15:2004 Table T.1; identical to
/// ȳ(λ) of the 1931 observer).
pub fn photopic_v() -> &'static Spectrum {
    &TABLES.photopic_v
}

/// The CIE 1951 scotopic luminous efficiency function V′(λ) (CIE 15:2004 Table T.2), the
/// rods' spectral sensitivity.
pub fn scotopic_v() -> &'static Spectrum {
    &TABLES.scotopic_v
}

/// K′_m, the maximum scotopic luminous efficacy (lm/W): 683 / V′(555 nm), so that 1 W at
/// 555 nm is 683 lm photopic and scotopic alike (the convention of CIE 191:2010, whose
/// V′(λ₀) = 683/1699; the table's V′(555 nm) = 0.402 gives 1699).
pub fn scotopic_efficacy_lm_per_w() -> f64 {
    let at_555 = TABLES.scotopic_v.at_nm(555.0).expect("555 nm is on the grid");
    K_M_LM_PER_W / at_555
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::wavelength_nm;

    #[test]
    fn scotopic_v_peaks_at_507_nm_and_gives_k_m_prime_1699() {
        let v = scotopic_v();
        let peak = (0..crate::grid::BANDS).max_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap();
        assert_eq!(wavelength_nm(peak), 505.0, "the 5 nm sample nearest the 507 nm peak");
        assert!((scotopic_efficacy_lm_per_w() - 1699.0).abs() < 1.0);
    }

    #[test]
    fn tables_load_with_known_values() {
        let t = &*TABLES;
        // CIE 15:2004 Table T.1 at 555 nm: ȳ = 1 and V = 1; at 600 nm x̄ = 1.0622.
        assert_eq!(t.cmf_1931[1][35], 1.0);
        assert_eq!(t.photopic_v[35], 1.0);
        assert_eq!(t.cmf_1931[0][44], 1.0622);
        assert_eq!(wavelength_nm(44), 600.0);
        // A and the D illuminants are normalised to 100 at 560 nm (B and C keep their historical
        // scale, 102.8 and 105.3 there); E is 100 everywhere.
        assert_eq!((t.b[36], t.c[36]), (102.8, 105.3));
        for s in [t.a, t.d50, t.d55, t.d65, t.d75] {
            assert!((s[36] - 100.0).abs() < 1e-3, "{}", s[36]);
        }
        assert_eq!(t.e, Spectrum::splat(100.0));
        // Table values at 380 nm, CIE 15:2004 Tables T.1 and T.2.
        assert_eq!(t.a[0], 9.7951);
        assert_eq!(t.d65[0], 49.9755);
        assert_eq!(t.s0[0], 63.4);
        // F2 and F11 peak near their mercury lines.
        assert!(t.f[1].max_value() > 30.0 && t.f[10].max_value() > 50.0);
    }

    #[test]
    fn photopic_v_is_ybar_1931() {
        assert_eq!(*photopic_v(), TABLES.cmf_1931[1]);
    }

    #[test]
    fn equal_energy_sums_are_equal() {
        // The 1931 functions are normalised so that an equal-energy stimulus has X = Y = Z
        // (CIE 15:2004 §7.1); over 380–780 nm at 5 nm the sums agree to the table rounding.
        for cmf in [TABLES.cmf_1931, TABLES.cmf_1964] {
            let sums: Vec<f64> = cmf.iter().map(|c| c.integral()).collect();
            assert!((sums[0] - sums[1]).abs() / sums[1] < 2e-4, "{sums:?}");
            assert!((sums[2] - sums[1]).abs() / sums[1] < 2e-4, "{sums:?}");
        }
    }
}
