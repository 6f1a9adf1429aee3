//! Chromatic adaptation transforms: a colour seen under one white, expressed as the
//! corresponding colour under another (CIE 160:2004; von Kries 1902). Each transform scales the
//! three cone-like responses by the ratio of the two whites in its own cone space.
//!
//! The cone spaces are also the channel spaces of the Retinex stage (the paper's l, m, s).

use crate::colorimetry::Xyz;
use crate::error::Error;
use glam::{DMat3, DVec3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// A cone (or sharpened cone) space, given by its matrix from XYZ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ConeSpace {
    /// Hunt–Pointer–Estévez cone fundamentals, normalised to equal-energy white: the classic
    /// von Kries transform.
    VonKries,
    /// The Bradford transform (Lam 1985), used by ICC profiles.
    #[default]
    Bradford,
    /// CAT02, the transform of CIECAM02 (CIE 159:2004).
    Cat02,
    /// CAT16, the transform of CAM16 (Li et al., "Comprehensive color solutions: CAM16, CAT16,
    /// and CAM16-UCS", Color Research & Application 42(6), 2017).
    Cat16,
}

impl ConeSpace {
    /// The matrix from XYZ to the cone responses, as published (rows are L, M, S).
    pub fn matrix(self) -> DMat3 {
        let rows: [[f64; 3]; 3] = match self {
            ConeSpace::VonKries => {
                [[0.40024, 0.70760, -0.08081], [-0.22630, 1.16532, 0.04570], [0.0, 0.0, 0.91822]]
            }
            ConeSpace::Bradford => {
                [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]
            }
            ConeSpace::Cat02 => {
                [[0.7328, 0.4296, -0.1624], [-0.7036, 1.6975, 0.0061], [0.0030, 0.0136, 0.9834]]
            }
            ConeSpace::Cat16 => [
                [0.401288, 0.650173, -0.051461],
                [-0.250268, 1.204414, 0.045854],
                [-0.002079, 0.048952, 0.953127],
            ],
        };
        DMat3::from_cols_array_2d(&rows).transpose()
    }
}

impl fmt::Display for ConeSpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(match self {
            ConeSpace::VonKries => "von-kries",
            ConeSpace::Bradford => "bradford",
            ConeSpace::Cat02 => "cat02",
            ConeSpace::Cat16 => "cat16",
        })
    }
}

impl FromStr for ConeSpace {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.to_ascii_lowercase().as_str() {
            "von-kries" | "vonkries" | "hpe" => Ok(ConeSpace::VonKries),
            "bradford" => Ok(ConeSpace::Bradford),
            "cat02" => Ok(ConeSpace::Cat02),
            "cat16" => Ok(ConeSpace::Cat16),
            _ => Err(Error::UnknownChoice {
                kind: "chromatic adaptation",
                name: s.to_owned(),
                choices: "von-kries, bradford, cat02 or cat16",
            }),
        }
    }
}

pub(crate) fn to_vec(xyz: Xyz) -> DVec3 {
    DVec3::new(xyz.x, xyz.y, xyz.z)
}

pub(crate) fn from_vec(v: DVec3) -> Xyz {
    Xyz::new(v.x, v.y, v.z)
}

/// The 3×3 matrix that carries XYZ seen under `source_white` to the corresponding XYZ under
/// `destination_white`: M⁻¹ · diag(ρ_d/ρ_s, γ_d/γ_s, β_d/β_s) · M.
pub fn adaptation_matrix(source_white: Xyz, destination_white: Xyz, space: ConeSpace) -> DMat3 {
    let m = space.matrix();
    let s = m * to_vec(source_white);
    let d = m * to_vec(destination_white);
    m.inverse() * DMat3::from_diagonal(d / s) * m
}

/// `xyz` seen under `source_white`, adapted to `destination_white`.
pub fn adapt(xyz: Xyz, source_white: Xyz, destination_white: Xyz, space: ConeSpace) -> Xyz {
    from_vec(adaptation_matrix(source_white, destination_white, space) * to_vec(xyz))
}

#[cfg(test)]
mod tests {
    use super::*;

    const D65: Xyz = Xyz::new(0.95047, 1.0, 1.08883);
    const D50: Xyz = Xyz::new(0.96422, 1.0, 0.82521);

    #[test]
    fn white_goes_to_white() {
        for space in [ConeSpace::VonKries, ConeSpace::Bradford, ConeSpace::Cat02, ConeSpace::Cat16]
        {
            let w = adapt(D65, D65, D50, space);
            assert!(
                (w.x - D50.x).abs() < 1e-12
                    && (w.y - D50.y).abs() < 1e-12
                    && (w.z - D50.z).abs() < 1e-12
            );
        }
    }

    /// The Bradford D65 → D50 matrix as published by Lindbloom ("Chromatic Adaptation",
    /// brucelindbloom.com), with the whites above.
    #[test]
    fn bradford_d65_to_d50_matches_the_published_matrix() {
        let expect = [
            [1.0478112, 0.0228866, -0.0501270],
            [0.0295424, 0.9904844, -0.0170491],
            [-0.0092345, 0.0150436, 0.7521316],
        ];
        let m = adaptation_matrix(D65, D50, ConeSpace::Bradford).transpose().to_cols_array_2d();
        for r in 0..3 {
            for c in 0..3 {
                assert!(
                    (m[r][c] - expect[r][c]).abs() < 2e-7,
                    "[{r}][{c}] {} vs {}",
                    m[r][c],
                    expect[r][c]
                );
            }
        }
    }

    #[test]
    fn the_round_trip_is_the_identity() {
        let x = Xyz::new(0.3, 0.4, 0.2);
        for space in [ConeSpace::VonKries, ConeSpace::Bradford, ConeSpace::Cat02] {
            let back = adapt(adapt(x, D65, D50, space), D50, D65, space);
            assert!((back.x - x.x).abs() < 1e-12 && (back.z - x.z).abs() < 1e-12);
        }
    }

    #[test]
    fn names_parse() {
        assert_eq!("CAT02".parse::<ConeSpace>().unwrap(), ConeSpace::Cat02);
        assert!("xyz".parse::<ConeSpace>().is_err());
    }
}
