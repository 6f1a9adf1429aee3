//! Light sources by name: the CIE standard and CIE illuminants (A, B, C, D50, D55, D65, D75, E,
//! F1–F12), a CIE daylight of any correlated colour temperature from the S0, S1, S2 basis, and a
//! black body of any temperature. Each gives a relative spectral power distribution on the grid,
//! on the CIE's tabulated scale (100 at 560 nm for A, the D series and black bodies; B and C keep
//! their historical scale).

use crate::cie::TABLES;
use crate::colorimetry::Chromaticity;
use crate::error::{Error, Result};
use crate::planck::blackbody_spd;
use crate::spectrum::Spectrum;
use std::fmt;
use std::str::FromStr;

/// A named light source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Illuminant {
    A,
    B,
    C,
    D50,
    D55,
    D65,
    D75,
    E,
    /// CIE fluorescent illuminant F1 … F12.
    F(u8),
    /// CIE daylight at a correlated colour temperature, 4000–25000 K (CIE 15:2004 §3.1).
    Daylight {
        cct_k: f64,
    },
    /// A Planckian radiator.
    Blackbody {
        temperature_k: f64,
    },
}

/// The standard names, for listings and suggestions.
pub const NAMES: [&str; 20] = [
    "A", "B", "C", "D50", "D55", "D65", "D75", "E", "F1", "F2", "F3", "F4", "F5", "F6", "F7", "F8",
    "F9", "F10", "F11", "F12",
];

impl fmt::Display for Illuminant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Illuminant::A => f.write_str("A"),
            Illuminant::B => f.write_str("B"),
            Illuminant::C => f.write_str("C"),
            Illuminant::D50 => f.write_str("D50"),
            Illuminant::D55 => f.write_str("D55"),
            Illuminant::D65 => f.write_str("D65"),
            Illuminant::D75 => f.write_str("D75"),
            Illuminant::E => f.write_str("E"),
            Illuminant::F(n) => write!(f, "F{n}"),
            Illuminant::Daylight { cct_k } => write!(f, "daylight:{cct_k}"),
            Illuminant::Blackbody { temperature_k } => write!(f, "blackbody:{temperature_k}"),
        }
    }
}

impl FromStr for Illuminant {
    type Err = Error;

    /// Names are case-insensitive: `D65`, `f11`, `daylight:5600`, `blackbody:2700`.
    fn from_str(name: &str) -> Result<Self> {
        let upper = name.trim().to_ascii_uppercase();
        let kelvin = |text: &str| text.trim().trim_end_matches('K').trim().parse::<f64>().ok();
        let parsed = match upper.as_str() {
            "A" => Some(Illuminant::A),
            "B" => Some(Illuminant::B),
            "C" => Some(Illuminant::C),
            "D50" => Some(Illuminant::D50),
            "D55" => Some(Illuminant::D55),
            "D65" => Some(Illuminant::D65),
            "D75" => Some(Illuminant::D75),
            "E" => Some(Illuminant::E),
            _ => {
                if let Some(n) = upper.strip_prefix('F').and_then(|n| n.parse::<u8>().ok()) {
                    (1..=12).contains(&n).then_some(Illuminant::F(n))
                } else if let Some(t) = upper.strip_prefix("DAYLIGHT:") {
                    kelvin(t).map(|cct_k| Illuminant::Daylight { cct_k })
                } else if let Some(t) = upper.strip_prefix("BLACKBODY:") {
                    kelvin(t).map(|temperature_k| Illuminant::Blackbody { temperature_k })
                } else {
                    None
                }
            }
        };
        let unknown = || Error::UnknownIlluminant {
            name: name.to_owned(),
            suggestions: NAMES
                .iter()
                .filter(|n| strsim::jaro_winkler(&n.to_ascii_uppercase(), &upper) > 0.8)
                .map(|n| n.to_string())
                .collect(),
        };
        let illuminant = parsed.ok_or_else(unknown)?;
        // Check the range now, so that a bad temperature is refused where it is written.
        illuminant.spd()?;
        Ok(illuminant)
    }
}

impl Illuminant {
    /// The relative spectral power distribution on the grid, on the CIE's tabulated scale.
    pub fn spd(&self) -> Result<Spectrum> {
        let t = &*TABLES;
        Ok(match *self {
            Illuminant::A => t.a,
            Illuminant::B => t.b,
            Illuminant::C => t.c,
            Illuminant::D50 => t.d50,
            Illuminant::D55 => t.d55,
            Illuminant::D65 => t.d65,
            Illuminant::D75 => t.d75,
            Illuminant::E => t.e,
            Illuminant::F(n) if (1..=12).contains(&n) => t.f[usize::from(n) - 1],
            Illuminant::F(n) => {
                return Err(Error::OutOfRange {
                    quantity: "fluorescent illuminant number",
                    value: f64::from(n),
                    expected: "F1 to F12",
                });
            }
            Illuminant::Daylight { cct_k } => daylight_spd(cct_k)?,
            Illuminant::Blackbody { temperature_k } => blackbody_spd(temperature_k)?,
        })
    }
}

/// The chromaticity of CIE daylight at a correlated colour temperature (CIE 15:2004 Eqs. 3.3 and
/// 3.4), valid 4000–25000 K.
pub fn daylight_chromaticity(cct_k: f64) -> Result<Chromaticity> {
    if !(cct_k.is_finite() && (4000.0..=25000.0).contains(&cct_k)) {
        return Err(Error::OutOfRange {
            quantity: "daylight correlated colour temperature (K)",
            value: cct_k,
            expected: "4000 K to 25000 K, where the CIE daylight formula holds",
        });
    }
    let t = cct_k;
    let x = if t <= 7000.0 {
        -4.6070e9 / t.powi(3) + 2.9678e6 / t.powi(2) + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t.powi(3) + 1.9018e6 / t.powi(2) + 0.24748e3 / t + 0.237040
    };
    let y = -3.000 * x * x + 2.870 * x - 0.275;
    Ok(Chromaticity::new(x, y))
}

/// The relative spectral power of CIE daylight at `cct_k` from the basis functions:
/// S(λ) = S0(λ) + M1·S1(λ) + M2·S2(λ) (CIE 15:2004 Eqs. 3.5–3.7), with M1 and M2 rounded to
/// three decimals as CIE 15:2004 §3.1 prescribes, so that daylight at 6504 K rebuilds the
/// tabulated D65.
pub fn daylight_spd(cct_k: f64) -> Result<Spectrum> {
    let Chromaticity { x, y } = daylight_chromaticity(cct_k)?;
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    let round3 = |v: f64| (v * 1000.0).round() / 1000.0;
    let m1 = round3((-1.3515 - 1.7703 * x + 5.9114 * y) / m) as f32;
    let m2 = round3((0.0300 - 31.4424 * x + 30.0717 * y) / m) as f32;
    let t = &*TABLES;
    Ok(t.s0 + t.s1 * m1 + t.s2 * m2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::{Observer, white_point};
    use crate::grid::BANDS;

    #[test]
    fn names_parse_and_print() {
        for name in NAMES {
            let i: Illuminant = name.parse().unwrap();
            assert_eq!(i.to_string(), name);
        }
        assert_eq!("d65".parse::<Illuminant>().unwrap(), Illuminant::D65);
        assert_eq!(
            "daylight:5600K".parse::<Illuminant>().unwrap(),
            Illuminant::Daylight { cct_k: 5600.0 }
        );
        assert_eq!(
            "blackbody:2700".parse::<Illuminant>().unwrap(),
            Illuminant::Blackbody { temperature_k: 2700.0 }
        );
    }

    #[test]
    fn unknown_names_are_refused_with_suggestions() {
        let err = "D56".parse::<Illuminant>().unwrap_err().to_string();
        assert!(err.contains("unknown illuminant `D56`"), "{err}");
        assert!(err.contains("did you mean"), "{err}");
        assert!("F13".parse::<Illuminant>().is_err());
        let err = "daylight:3000".parse::<Illuminant>().unwrap_err().to_string();
        assert!(err.contains("4000 K to 25000 K"), "{err}");
    }

    /// CIE 15:2004 §3.1 notes D65 is CIE daylight at 6500 × 1.4388/1.4380 ≈ 6504 K.
    #[test]
    fn d65_rebuilt_from_the_daylight_basis() {
        let rebuilt = daylight_spd(6504.0).unwrap();
        let table = Illuminant::D65.spd().unwrap();
        for i in 0..BANDS {
            // The table is given to a few decimals; the basis reproduces it to 0.05.
            assert!(
                (rebuilt[i] - table[i]).abs() < 0.05,
                "band {i}: {} vs {}",
                rebuilt[i],
                table[i]
            );
        }
        let c = daylight_chromaticity(6504.0).unwrap();
        assert!((c.x - 0.31271).abs() < 1e-5 && (c.y - 0.32912).abs() < 1e-5, "{c:?}");
        // The same for D50 (5003 K) and D75 (7504 K), across the two branches of Eq. 3.3.
        for (cct, table) in [(5003.0, Illuminant::D50), (7504.0, Illuminant::D75)] {
            let rebuilt = daylight_spd(cct).unwrap();
            let table = table.spd().unwrap();
            for i in 0..BANDS {
                assert!((rebuilt[i] - table[i]).abs() < 0.06, "{cct} band {i}");
            }
        }
    }

    #[test]
    fn daylight_white_point_follows_its_chromaticity() {
        for cct in [4000.0, 5500.0, 6500.0, 9000.0, 25000.0] {
            let w = white_point(&daylight_spd(cct).unwrap(), Observer::Cie1931TwoDegree);
            let c = w.chromaticity().unwrap();
            let expect = daylight_chromaticity(cct).unwrap();
            assert!(
                (c.x - expect.x).abs() < 5e-4 && (c.y - expect.y).abs() < 5e-4,
                "{cct}: {c:?} vs {expect:?}"
            );
        }
    }
}
