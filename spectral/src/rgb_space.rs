//! Display RGB colour spaces, each defined by its primaries, white point and transfer function.
//! The XYZ ↔ RGB matrices are computed from the primaries (SMPTE RP 177-1993), not typed in, so
//! a new display is one table row.

use crate::adaptation::{from_vec, to_vec};
use crate::colorimetry::{Chromaticity, Xyz};
use crate::error::Error;
use glam::{DMat3, DVec3};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// How linear values are encoded for the display.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transfer {
    /// The sRGB piecewise curve of IEC 61966-2-1 (also used by Display P3).
    Srgb,
    /// A pure power law V = L^(1/γ): Adobe RGB (γ = 563/256), or BT.1886 displays (γ = 2.4).
    Gamma(f64),
}

impl Transfer {
    /// Linear light (0..1) to the encoded signal (0..1). Values outside 0..1 are clipped.
    pub fn encode(self, linear: f64) -> f64 {
        let l = linear.clamp(0.0, 1.0);
        match self {
            Transfer::Srgb => {
                if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                }
            }
            Transfer::Gamma(g) => l.powf(1.0 / g),
        }
    }

    /// The encoded signal (0..1) to linear light.
    pub fn decode(self, encoded: f64) -> f64 {
        let v = encoded.clamp(0.0, 1.0);
        match self {
            Transfer::Srgb => {
                if v <= 0.040_45 {
                    v / 12.92
                } else {
                    ((v + 0.055) / 1.055).powf(2.4)
                }
            }
            Transfer::Gamma(g) => v.powf(g),
        }
    }
}

/// The display spaces restauro writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RgbSpace {
    /// sRGB, IEC 61966-2-1:1999.
    #[default]
    Srgb,
    /// Display P3 (DCI-P3 primaries, D65 white, sRGB transfer).
    DisplayP3,
    /// ITU-R BT.2020 primaries, D65, encoded for a BT.1886 display (γ 2.4).
    Rec2020,
    /// Adobe RGB (1998).
    AdobeRgb,
}

impl RgbSpace {
    pub const ALL: [RgbSpace; 4] =
        [RgbSpace::Srgb, RgbSpace::DisplayP3, RgbSpace::Rec2020, RgbSpace::AdobeRgb];

    /// Red, green and blue primaries.
    pub fn primaries(self) -> [Chromaticity; 3] {
        let c = Chromaticity::new;
        match self {
            RgbSpace::Srgb => [c(0.64, 0.33), c(0.30, 0.60), c(0.15, 0.06)],
            RgbSpace::DisplayP3 => [c(0.680, 0.320), c(0.265, 0.690), c(0.150, 0.060)],
            RgbSpace::Rec2020 => [c(0.708, 0.292), c(0.170, 0.797), c(0.131, 0.046)],
            RgbSpace::AdobeRgb => [c(0.64, 0.33), c(0.21, 0.71), c(0.15, 0.06)],
        }
    }

    /// The white point, Y = 1. All four use D65 as its standards round it: x = 0.3127,
    /// y = 0.3290.
    pub fn white(self) -> Xyz {
        Chromaticity::new(0.3127, 0.3290).to_xyz(1.0)
    }

    pub fn transfer(self) -> Transfer {
        match self {
            RgbSpace::Srgb | RgbSpace::DisplayP3 => Transfer::Srgb,
            RgbSpace::Rec2020 => Transfer::Gamma(2.4),
            RgbSpace::AdobeRgb => Transfer::Gamma(563.0 / 256.0),
        }
    }

    /// The matrix from linear RGB to XYZ (Y = 1 for white): the columns are the primaries' XYZ,
    /// each scaled so that R = G = B = 1 gives the white point (SMPTE RP 177-1993 §3.3).
    pub fn rgb_to_xyz(self) -> DMat3 {
        self.rgb_to_xyz_with_white(self.white())
    }

    /// The matrix from linear RGB to XYZ for these primaries with another white: R = G = B = 1
    /// gives `white`, on its scale. For a white that the standard rounds (sRGB's D65 is
    /// x = 0.3127, y = 0.3290) but a computation sums exactly, e.g. D65 over restauro's grid.
    pub fn rgb_to_xyz_with_white(self, white: Xyz) -> DMat3 {
        let [r, g, b] = self.primaries().map(|p| to_vec(p.to_xyz(1.0)));
        let unscaled = DMat3::from_cols(r, g, b);
        let s = unscaled.inverse() * to_vec(white);
        DMat3::from_cols(r * s.x, g * s.y, b * s.z)
    }

    /// The matrix from XYZ (Y = 1 for white) to linear RGB.
    pub fn xyz_to_rgb(self) -> DMat3 {
        self.rgb_to_xyz().inverse()
    }

    /// Linear RGB of `xyz` (Y = 1 for the display white), unclipped: components outside 0..1 are
    /// out of gamut.
    pub fn linear_from_xyz(self, xyz: Xyz) -> [f64; 3] {
        (self.xyz_to_rgb() * to_vec(xyz)).to_array()
    }

    /// XYZ of linear RGB.
    pub fn xyz_from_linear(self, rgb: [f64; 3]) -> Xyz {
        from_vec(self.rgb_to_xyz() * DVec3::from_array(rgb))
    }
}

impl fmt::Display for RgbSpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(match self {
            RgbSpace::Srgb => "srgb",
            RgbSpace::DisplayP3 => "p3",
            RgbSpace::Rec2020 => "rec2020",
            RgbSpace::AdobeRgb => "adobe-rgb",
        })
    }
}

impl FromStr for RgbSpace {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.to_ascii_lowercase().as_str() {
            "srgb" => Ok(RgbSpace::Srgb),
            "p3" | "display-p3" => Ok(RgbSpace::DisplayP3),
            "rec2020" | "bt2020" => Ok(RgbSpace::Rec2020),
            "adobe-rgb" | "adobergb" | "adobe" => Ok(RgbSpace::AdobeRgb),
            _ => Err(Error::UnknownChoice {
                kind: "colour space",
                name: s.to_owned(),
                choices: "srgb, p3, rec2020 or adobe-rgb",
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(m: DMat3) -> [[f64; 3]; 3] {
        m.transpose().to_cols_array_2d()
    }

    /// IEC 61966-2-1:1999 Eq. (F.7) and (F.8) give the matrices to four decimals; ours, computed
    /// from the primaries, round to the forward matrix. The published inverse was computed
    /// from the rounded forward matrix, so it agrees only to 5e-4.
    #[test]
    fn srgb_matrices_match_iec_61966_2_1() {
        let forward =
            [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]];
        let inverse =
            [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]];
        let (f, i) = (rows(RgbSpace::Srgb.rgb_to_xyz()), rows(RgbSpace::Srgb.xyz_to_rgb()));
        for r in 0..3 {
            for c in 0..3 {
                assert!((f[r][c] - forward[r][c]).abs() <= 5e-5, "M[{r}][{c}] = {}", f[r][c]);
                assert!((i[r][c] - inverse[r][c]).abs() <= 5e-4, "M⁻¹[{r}][{c}] = {}", i[r][c]);
            }
        }
    }

    /// ITU-R BT.2087 / SMPTE RP 431-2 and BT.2020 publish their luminance rows; check Y weights.
    #[test]
    fn luminance_rows_of_p3_and_rec2020() {
        let p3 = rows(RgbSpace::DisplayP3.rgb_to_xyz())[1];
        assert!(
            (p3[0] - 0.2290).abs() < 1e-4
                && (p3[1] - 0.6917).abs() < 1e-4
                && (p3[2] - 0.0793).abs() < 1e-4,
            "{p3:?}"
        );
        // ITU-R BT.2020 Table 4: Y' = 0.2627 R + 0.6780 G + 0.0593 B.
        let r2020 = rows(RgbSpace::Rec2020.rgb_to_xyz())[1];
        assert!(
            (r2020[0] - 0.2627).abs() < 1e-4
                && (r2020[1] - 0.6780).abs() < 1e-4
                && (r2020[2] - 0.0593).abs() < 1e-4,
            "{r2020:?}"
        );
    }

    #[test]
    fn white_maps_to_one_and_primaries_to_their_chromaticities() {
        for space in RgbSpace::ALL {
            let rgb = space.linear_from_xyz(space.white());
            for v in rgb {
                assert!((v - 1.0).abs() < 1e-12, "{space}: {rgb:?}");
            }
            for (k, p) in space.primaries().iter().enumerate() {
                let mut unit = [0.0; 3];
                unit[k] = 1.0;
                let c = space.xyz_from_linear(unit).chromaticity().unwrap();
                assert!((c.x - p.x).abs() < 1e-12 && (c.y - p.y).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn srgb_transfer_function() {
        // IEC 61966-2-1: the curve is continuous at the break point and encodes 0.18 as 0.4614.
        assert!((Transfer::Srgb.encode(0.18) - 0.461_356).abs() < 1e-6);
        assert!((Transfer::Srgb.encode(0.003_130_8) - 0.040_45).abs() < 1e-6);
        assert!((Transfer::Srgb.encode(1.0) - 1.0).abs() < 1e-15);
        assert_eq!(Transfer::Srgb.encode(-0.5), 0.0);
        for k in 0..=100 {
            let v = f64::from(k) / 100.0;
            assert!((Transfer::Srgb.decode(Transfer::Srgb.encode(v)) - v).abs() < 1e-12);
            assert!(
                (Transfer::Gamma(2.2).decode(Transfer::Gamma(2.2).encode(v)) - v).abs() < 1e-12
            );
        }
    }
}
