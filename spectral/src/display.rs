//! The display pipeline: absolute (or relative) XYZ → display RGB through M⁻¹ computed from the
//! display's primaries → exposure → gamut mapping → the display's transfer function → 8- or
//! 16-bit code values.
//!
//! Exposure modes:
//! * **absolute**: a given luminance (cd/m²) maps to the display's white, as a camera with a
//!   fixed exposure;
//! * **automatic**: the log-average luminance maps to a key value of the white (Reinhard et al.,
//!   "Photographic tone reproduction", SIGGRAPH 2002, Eq. 1–2), as a camera on auto-exposure;
//! * **relative**: the image is already relative to its white (Y = 1), as the Retinex output is.
//!
//! Colours outside the display's gamut are mapped, not wrapped or clipped per channel: the
//! colour moves towards the grey of the same luminance along a straight line in linear RGB, so
//! that luminance and hue are kept and only chroma is given up (and a colour brighter than the
//! white becomes the white).

use crate::rgb_space::RgbSpace;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How absolute luminance becomes display luminance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum Exposure {
    /// This luminance (cd/m²) is shown as the display's white.
    Absolute { white_cd_m2: f64 },
    /// The log-average luminance is shown at `key` of the white (0.18 is middle grey).
    Automatic { key: f64 },
    /// The image is relative already: Y = 1 is white.
    Relative,
}

impl Default for Exposure {
    /// Automatic, with middle grey at 0.18 of the white.
    fn default() -> Self {
        Exposure::Automatic { key: 0.18 }
    }
}

impl Exposure {
    /// The exposure if its number is usable: finite and above 0 (and a key at most 1).
    pub fn checked(self) -> Result<Self, String> {
        match self {
            Exposure::Automatic { key } if !(key.is_finite() && key > 0.0 && key <= 1.0) => Err(
                format!("an automatic exposure's key of {key}: use a number above 0, at most 1"),
            ),
            Exposure::Absolute { white_cd_m2 }
                if !(white_cd_m2.is_finite() && white_cd_m2 > 0.0 && white_cd_m2 < 1e12) =>
            {
                Err(format!(
                    "an absolute exposure's white of {white_cd_m2} cd/m²: use a luminance above 0"
                ))
            }
            ok => Ok(ok),
        }
    }
}

/// `auto`, `auto:<key>`, `absolute:<cd/m²>` or `relative` (the command line's form).
impl std::str::FromStr for Exposure {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let lower = text.trim().to_ascii_lowercase();
        let number = |s: &str| s.parse::<f64>().map_err(|_| format!("`{s}` is not a number"));
        let exposure = match lower.as_str() {
            "auto" => Exposure::default(),
            "relative" => Exposure::Relative,
            _ => {
                if let Some(k) = lower.strip_prefix("auto:") {
                    Exposure::Automatic { key: number(k)? }
                } else if let Some(l) = lower.strip_prefix("absolute:") {
                    Exposure::Absolute { white_cd_m2: number(l)? }
                } else {
                    return Err(format!(
                        "exposure `{text}`: use auto, auto:<key>, absolute:<cd/m²> or relative"
                    ));
                }
            }
        };
        exposure.checked().map_err(|e| format!("exposure `{text}`: {e}"))
    }
}

/// The log-average luminance exp(mean ln(δ + Y)) (Reinhard et al. 2002, Eq. 1) over the pixels
/// that receive any light, with δ a millionth of the largest luminance. Pixels of luminance 0 —
/// an empty sky in a scene without sky light, the background of a test card — are left out:
/// they carry no exposure information and would otherwise pull the average to black.
pub fn log_average_luminance(xyz: &[[f32; 3]]) -> f64 {
    let max = xyz.iter().map(|p| f64::from(p[1])).fold(0.0, f64::max);
    if max <= 0.0 {
        return 0.0;
    }
    let delta = max * 1e-6;
    let (sum, n) = xyz
        .iter()
        .map(|p| f64::from(p[1]))
        .filter(|&y| y > 0.0)
        .fold((0.0, 0usize), |(s, n), y| (s + (delta + y).ln(), n + 1));
    (sum / n as f64).exp()
}

/// The factor that takes image luminance to display luminance (white = 1).
pub fn exposure_scale(xyz: &[[f32; 3]], exposure: Exposure) -> f64 {
    match exposure {
        Exposure::Absolute { white_cd_m2 } => 1.0 / white_cd_m2,
        Exposure::Automatic { key } => {
            let average = log_average_luminance(xyz);
            if average > 0.0 { key / average } else { 1.0 }
        }
        Exposure::Relative => 1.0,
    }
}

/// Map a linear RGB colour into the unit cube, keeping its luminance Y = `luminance` · rgb and
/// its hue: move it along the line towards the grey (Y, Y, Y) just far enough.
pub fn gamut_map(rgb: [f64; 3], luminance: [f64; 3]) -> [f64; 3] {
    let y = luminance[0] * rgb[0] + luminance[1] * rgb[1] + luminance[2] * rgb[2];
    if !y.is_finite() || y <= 0.0 {
        return [0.0; 3];
    }
    if y >= 1.0 {
        return [1.0; 3];
    }
    let (lo, hi) = (
        rgb.iter().copied().fold(f64::INFINITY, f64::min),
        rgb.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    // The largest t in [0, 1] with every component of Y + t(rgb − Y) inside [0, 1].
    let mut t: f64 = 1.0;
    if lo < 0.0 {
        t = t.min(y / (y - lo));
    }
    if hi > 1.0 {
        t = t.min((1.0 - y) / (hi - y));
    }
    rgb.map(|v| (y + t * (v - y)).clamp(0.0, 1.0))
}

/// A display and how to show an image on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayParams {
    pub space: RgbSpace,
    pub exposure: Exposure,
}

/// The encoded display values (0..1, before quantisation) of an XYZ image, row-major RGB.
pub fn encode(xyz: &[[f32; 3]], params: &DisplayParams) -> Vec<[f32; 3]> {
    let k = exposure_scale(xyz, params.exposure);
    let m = params.space.xyz_to_rgb();
    let luminance = params.space.rgb_to_xyz().row(1).to_array();
    let transfer = params.space.transfer();
    xyz.iter()
        .map(|p| {
            let v = m * (DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * k);
            gamut_map(v.to_array(), luminance).map(|c| transfer.encode(c) as f32)
        })
        .collect()
}

/// Quantise encoded values to 8-bit code values.
pub fn to_u8(encoded: &[[f32; 3]]) -> Vec<u8> {
    encoded.iter().flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)).collect()
}

/// Quantise encoded values to 16-bit code values.
pub fn to_u16(encoded: &[[f32; 3]]) -> Vec<u16> {
    encoded.iter().flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colorimetry::Xyz;

    fn hue(rgb: [f64; 3], y: f64) -> f64 {
        // The direction of the chroma vector rgb − (Y, Y, Y), as an angle in a plane.
        let d = [rgb[0] - y, rgb[1] - y, rgb[2] - y];
        let (a, b) = (d[0] - 0.5 * (d[1] + d[2]), 0.75f64.sqrt() * (d[1] - d[2]));
        b.atan2(a)
    }

    #[test]
    fn in_gamut_colours_are_unchanged() {
        let lum = RgbSpace::Srgb.rgb_to_xyz().row(1).to_array();
        for rgb in [[0.2, 0.5, 0.9], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.3, 0.3, 0.3]] {
            let m = gamut_map(rgb, lum);
            for c in 0..3 {
                assert!((m[c] - rgb[c]).abs() < 1e-12, "{rgb:?} → {m:?}");
            }
        }
    }

    #[test]
    fn out_of_gamut_colours_keep_luminance_and_hue() {
        let lum = RgbSpace::Srgb.rgb_to_xyz().row(1).to_array();
        for rgb in [[1.4, 0.2, -0.1], [-0.3, 0.8, 0.2], [0.1, 0.2, 1.8], [1.2, 0.9, -0.05]] {
            let y = lum[0] * rgb[0] + lum[1] * rgb[1] + lum[2] * rgb[2];
            let m = gamut_map(rgb, lum);
            assert!(m.iter().all(|v| (0.0..=1.0).contains(v)), "{m:?}");
            let ym = lum[0] * m[0] + lum[1] * m[1] + lum[2] * m[2];
            assert!((ym - y).abs() < 1e-12, "{rgb:?}: Y {y} → {ym}");
            assert!((hue(m, y) - hue(rgb, y)).abs() < 1e-9, "{rgb:?} → {m:?}");
            // On the gamut boundary: one component at 0 or 1.
            assert!(m.iter().any(|&v| !(1e-12..=1.0 - 1e-12).contains(&v)), "{m:?}");
        }
        // Brighter than white is white; black or negative luminance is black.
        assert_eq!(gamut_map([2.0, 2.0, 0.9], lum), [1.0; 3]);
        assert_eq!(gamut_map([-0.1, 0.0, 0.0], lum), [0.0; 3]);
    }

    #[test]
    fn absolute_exposure_maps_the_given_luminance_to_white() {
        // A D65 white surface of 250 cd/m² shown with 250 cd/m² as white is (1, 1, 1).
        let white = crate::appearance::d65_white().scale(250.0);
        let img = vec![[white.x as f32, white.y as f32, white.z as f32]];
        let params = DisplayParams {
            space: RgbSpace::Srgb,
            exposure: Exposure::Absolute { white_cd_m2: 250.0 },
        };
        let out = encode(&img, &params);
        assert!(out[0].iter().all(|v| (v - 1.0).abs() < 1e-5), "{out:?}");
        assert_eq!(to_u8(&out), vec![255, 255, 255]);
        assert_eq!(to_u16(&out), vec![65535, 65535, 65535]);
    }

    #[test]
    fn automatic_exposure_puts_the_log_average_at_the_key() {
        // Two greys whose log-average is √(10 · 1000) = 100 cd/m².
        let d = crate::appearance::d65_white();
        let grey = |l: f64| {
            let x: Xyz = d.scale(l);
            [x.x as f32, x.y as f32, x.z as f32]
        };
        let img = vec![grey(10.0), grey(1000.0), [0.0; 3]];
        // The black pixel is left out.
        assert!((log_average_luminance(&img) / 100.0 - 1.0).abs() < 1e-4);
        let k = exposure_scale(&img, Exposure::Automatic { key: 0.18 });
        assert!((k * 100.0 - 0.18).abs() < 1e-5);
        assert_eq!(exposure_scale(&img, Exposure::Relative), 1.0);
    }
}
