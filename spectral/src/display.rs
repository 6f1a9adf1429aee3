//! The display pipeline: absolute (or relative) XYZ → display RGB through M⁻¹ computed from the
//! display's primaries → exposure → tone curve → gamut mapping → the display's transfer function
//! → 8- or 16-bit code values.
//!
//! Every exposure names a **reference white**, a luminance that the tone curve
//! ([`crate::tone`]) shows at 0.7 of the display's white, linearly below it and with a smooth
//! shoulder above it, so that a white lit by a chromatic light keeps its hue and what is brighter
//! than the white is compressed, not clipped:
//! * **absolute**: a given luminance (cd/m²) is the reference white, as a camera with a fixed
//!   exposure;
//! * **automatic**: the log-average luminance is shown at a key value of the reference white
//!   (Reinhard et al., "Photographic tone reproduction", SIGGRAPH 2002, Eq. 1–2), as a camera on
//!   auto-exposure — but never brighter than to put the 99th percentile of the lit pixels'
//!   luminance above the reference white (see [`automatic_scale`]), so that neither a hot spot nor
//!   a bright area of a few per cent of the image is pushed into the shoulder;
//! * **relative**: the image is already relative to its white (Y = 1 is the reference white), as
//!   the Retinex output is; it goes through the same curve, so rendered and seen images are shown
//!   alike.
//!
//! The tone curve acts on luminance: the linear RGB of a colour is scaled by Y′/Y, which keeps
//! its chromaticity. Colours still outside the display's gamut are then mapped, not wrapped or
//! clipped per channel: the colour moves towards the grey of the same luminance along a straight
//! line in linear RGB, so that luminance and hue are kept and only chroma is given up.

use crate::error::{Error, ExposureProblem};
use crate::rgb_space::RgbSpace;
use crate::tone;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// How absolute luminance becomes display luminance: which luminance is the reference white
/// (shown at [`tone::REFERENCE_WHITE`] of the display's white).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case")]
pub enum Exposure {
    /// This luminance (cd/m²) is the reference white.
    Absolute { white_cd_m2: f64 },
    /// The log-average luminance is shown at `key` of the reference white (0.18 is middle grey),
    /// unless that puts the 99th percentile above the reference white.
    Automatic { key: f64 },
    /// The image is relative already: Y = 1 is the reference white.
    Relative,
}

impl Default for Exposure {
    /// Automatic, with middle grey at 0.18 of the reference white.
    fn default() -> Self {
        Exposure::Automatic { key: 0.18 }
    }
}

impl Exposure {
    /// The exposure if its number is usable: finite and above 0 (and a key at most 1).
    pub fn checked(self) -> Result<Self, Error> {
        self.problem().map_or(Ok(self), |p| Err(Error::Exposure(p)))
    }

    /// What is wrong with the exposure's number, if anything.
    fn problem(self) -> Option<ExposureProblem> {
        match self {
            Exposure::Automatic { key } if !(key.is_finite() && key > 0.0 && key <= 1.0) => {
                Some(ExposureProblem::Key { key })
            }
            Exposure::Absolute { white_cd_m2 }
                if !(white_cd_m2.is_finite() && white_cd_m2 > 0.0 && white_cd_m2 < 1e12) =>
            {
                Some(ExposureProblem::White { white_cd_m2 })
            }
            _ => None,
        }
    }
}

/// `auto`, `auto:<key>`, `absolute:<cd/m²>` or `relative` (the command line's form).
impl std::str::FromStr for Exposure {
    type Err = Error;

    fn from_str(text: &str) -> Result<Self, Error> {
        let lower = text.trim().to_ascii_lowercase();
        let number =
            |s: &str| s.parse::<f64>().map_err(|_| Error::NotANumber { text: s.to_owned() });
        let exposure = match lower.as_str() {
            "auto" => Exposure::default(),
            "relative" => Exposure::Relative,
            _ => {
                if let Some(k) = lower.strip_prefix("auto:") {
                    Exposure::Automatic { key: number(k)? }
                } else if let Some(l) = lower.strip_prefix("absolute:") {
                    Exposure::Absolute { white_cd_m2: number(l)? }
                } else {
                    return Err(Error::UnknownExposure { text: text.to_owned() });
                }
            }
        };
        match exposure.problem() {
            Some(problem) => Err(Error::ExposureText { text: text.to_owned(), problem }),
            None => Ok(exposure),
        }
    }
}

/// The percentile of the lit pixels' luminance that an automatic exposure may put at most at
/// the reference white.
pub const AUTOMATIC_PERCENTILE: f64 = 99.0;

/// The luminances above 0 of an image: the pixels that receive any light. Pixels of luminance 0
/// (or not a number) — an empty sky in a scene without sky light, the background of a test card
/// — carry no exposure information and would otherwise pull the average to black.
fn lit_luminances(xyz: &[[f32; 3]]) -> Vec<f64> {
    xyz.iter().map(|p| f64::from(p[1])).filter(|&y| y > 0.0).collect()
}

/// The `percent`-th percentile of `values` by nearest rank (the smallest value with at least
/// `percent` % of the values at or below it), reordering them; `None` if there are none.
fn percentile(values: &mut [f64], percent: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let rank = ((percent / 100.0 * values.len() as f64).ceil() as usize).clamp(1, values.len());
    let (_, nth, _) = values.select_nth_unstable_by(rank - 1, f64::total_cmp);
    Some(*nth)
}

/// The `percent`-th percentile (nearest rank) of the luminance of the lit pixels (Y > 0); 0 if
/// none is lit.
pub fn luminance_percentile(xyz: &[[f32; 3]], percent: f64) -> f64 {
    percentile(&mut lit_luminances(xyz), percent).unwrap_or(0.0)
}

/// exp(mean ln(δ + Y)) over `lit`, with δ a millionth of `high` (Reinhard et al. 2002, Eq. 1).
fn log_average(lit: &[f64], high: f64) -> f64 {
    let delta = high * 1e-6;
    (lit.iter().map(|&y| (delta + y).ln()).sum::<f64>() / lit.len() as f64).exp()
}

/// The log-average luminance exp(mean ln(δ + Y)) (Reinhard et al. 2002, Eq. 1) over the pixels
/// that receive any light (Y > 0), with δ a millionth of their 99th-percentile luminance (not of
/// the maximum, which one firefly decides); 0 if none is lit.
pub fn log_average_luminance(xyz: &[[f32; 3]]) -> f64 {
    let mut lit = lit_luminances(xyz);
    match percentile(&mut lit, AUTOMATIC_PERCENTILE) {
        Some(high) => log_average(&lit, high),
        None => 0.0,
    }
}

/// The automatic exposure's factor from image luminance to luminance relative to the reference
/// white:
///
/// k = min(key / L̄, 1 / L₉₉),
///
/// with L̄ the log-average luminance of the lit pixels (Reinhard et al. 2002, Eq. 1–2: the
/// log-average is shown at `key` of the reference white) and L₉₉ their 99th-percentile luminance
/// (nearest rank). The bound keeps at most 1 % of the lit pixels above the reference white, in
/// the tone curve's shoulder, where their colours are compressed: a scene whose log-average is
/// pulled down by large dark areas is not exposed so brightly that its lit surfaces are washed
/// out. A percentile, not the maximum, bounds it (as Reinhard, "Parameter estimation for
/// photographic tone reproduction", JGT 7(1), 2002, takes the 1st and 99th percentiles for the
/// dynamic range), so a hot spot or firefly of fewer than 1 % of the pixels decides nothing: it
/// only moves the log-average by its share of the pixels times the log of its brightness.
/// An image with no lit pixel gets 1.
pub fn automatic_scale(xyz: &[[f32; 3]], key: f64) -> f64 {
    let mut lit = lit_luminances(xyz);
    let Some(high) = percentile(&mut lit, AUTOMATIC_PERCENTILE) else {
        return 1.0;
    };
    let average = log_average(&lit, high);
    (key / average).min(1.0 / high)
}

/// The factor that takes image luminance to luminance relative to the reference white (the
/// reference white = 1; [`tone::display_luminance`] then makes it display luminance).
pub fn exposure_scale(xyz: &[[f32; 3]], exposure: Exposure) -> f64 {
    match exposure {
        Exposure::Absolute { white_cd_m2 } => 1.0 / white_cd_m2,
        Exposure::Automatic { key } => automatic_scale(xyz, key),
        Exposure::Relative => 1.0,
    }
}

/// A linear RGB colour relative to the reference white (the reference white = 1, on the display's
/// primaries) as display linear RGB in the unit cube: its luminance Y = `luminance` · rgb goes
/// through the tone curve, the colour is scaled by Y′/Y (its chromaticity kept), and what is
/// still outside the cube is gamut-mapped towards the grey of Y′ ([`gamut_map`]).
pub fn tone_map(rgb: [f64; 3], luminance: [f64; 3]) -> [f64; 3] {
    let y = luminance[0] * rgb[0] + luminance[1] * rgb[1] + luminance[2] * rgb[2];
    if !y.is_finite() || y <= 0.0 {
        return gamut_map(rgb, luminance);
    }
    let scale = tone::display_luminance(y) / y;
    gamut_map(rgb.map(|c| c * scale), luminance)
}

/// Map a linear RGB colour into the unit cube, keeping its luminance Y = `luminance` · rgb and
/// its hue: move it along the line towards the grey (Y, Y, Y) just far enough. A colour of
/// Y ≥ 1 can only be the display's white (which the tone curve reaches only in the limit).
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
            tone_map(v.to_array(), luminance).map(|c| transfer.encode(c) as f32)
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
    use crate::colorimetry::{Chromaticity, Xyz};

    fn hue(rgb: [f64; 3], y: f64) -> f64 {
        // The direction of the chroma vector rgb − (Y, Y, Y), as an angle in a plane.
        let d = [rgb[0] - y, rgb[1] - y, rgb[2] - y];
        let (a, b) = (d[0] - 0.5 * (d[1] + d[2]), 0.75f64.sqrt() * (d[1] - d[2]));
        b.atan2(a)
    }

    fn pixel(xyz: Xyz) -> [f32; 3] {
        [xyz.x as f32, xyz.y as f32, xyz.z as f32]
    }

    /// A D65 grey of luminance `l` (cd/m²).
    fn grey(l: f64) -> [f32; 3] {
        pixel(RgbSpace::Srgb.white().scale(l))
    }

    /// The sRGB encoding of IEC 61966-2-1 §5.2, written out here rather than taken from
    /// `Transfer`: 12.92 v up to 0.0031308, 1.055 v^(1/2.4) − 0.055 above.
    fn srgb_code(linear: f64) -> u8 {
        let v = if linear <= 0.003_130_8 {
            12.92 * linear
        } else {
            1.055 * linear.powf(1.0 / 2.4) - 0.055
        };
        (v * 255.0).round() as u8
    }

    fn srgb_u8(img: &[[f32; 3]], exposure: Exposure) -> Vec<u8> {
        to_u8(&encode(img, &DisplayParams { space: RgbSpace::Srgb, exposure }))
    }

    #[test]
    fn in_gamut_colours_are_unchanged() {
        // The gamut mapping leaves a colour inside the cube as it is. The tone curve is linear
        // up to the reference white, so a colour (relative to the reference white) of at most
        // its luminance that fits the cube at 0.7 of itself is shown as exactly 0.7 · rgb, the
        // reference white's level, each channel alike.
        let lum = RgbSpace::Srgb.rgb_to_xyz().row(1).to_array();
        for rgb in
            [[0.2, 0.5, 0.9], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [0.3, 0.3, 0.3], [0.9, 0.4, 0.1]]
        {
            let (mapped, toned) = (gamut_map(rgb, lum), tone_map(rgb, lum));
            for c in 0..3 {
                assert!((mapped[c] - rgb[c]).abs() < 1e-12, "{rgb:?} → {mapped:?}");
                assert!((toned[c] - 0.7 * rgb[c]).abs() < 1e-12, "{rgb:?} → {toned:?}");
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
        // Black or negative luminance is black.
        assert_eq!(gamut_map([-0.1, 0.0, 0.0], lum), [0.0; 3]);
        // Brighter than the reference white is not white: a yellow of Y ≈ 1.9 times the
        // reference white goes through the shoulder to L_d = 0.7 + 0.3 u/(1 + u) < 1, and keeps
        // its hue (R = G > B) at that luminance.
        let rgb = [2.0, 2.0, 0.9];
        let y = lum[0] * rgb[0] + lum[1] * rgb[1] + lum[2] * rgb[2];
        let u = (0.7 * y - 0.7) / 0.3;
        let expected_y = 0.7 + 0.3 * u / (1.0 + u);
        let m = tone_map(rgb, lum);
        let ym = lum[0] * m[0] + lum[1] * m[1] + lum[2] * m[2];
        assert!((ym - expected_y).abs() < 1e-12, "{m:?}: Y {ym}, expected {expected_y}");
        assert!(m.iter().all(|v| (0.0..=1.0).contains(v)), "{m:?}");
        assert!((m[0] - m[1]).abs() < 1e-12 && m[1] > m[2] + 0.05, "{m:?}");
        assert!((hue(m, ym) - hue(rgb, y)).abs() < 1e-9, "{rgb:?} → {m:?}");
        // Only a colour of luminance at or above the display's white, which the tone curve
        // reaches only in the limit, is the white.
        assert_eq!(gamut_map([2.0, 2.0, 0.9], lum), [1.0; 3]);
    }

    #[test]
    fn absolute_exposure_shows_the_given_luminance_at_the_reference_white() {
        // A D65 white surface of 250 cd/m² shown with 250 cd/m² as the reference white is the
        // grey (0.7, 0.7, 0.7): sRGB 1.055 · 0.7^(1/2.4) − 0.055 = 0.8543, code 218.
        let img = vec![grey(250.0), grey(500.0), grey(250.0 * 40.0)];
        let params = DisplayParams {
            space: RgbSpace::Srgb,
            exposure: Exposure::Absolute { white_cd_m2: 250.0 },
        };
        let out = encode(&img, &params);
        let expected = 1.055 * 0.7f64.powf(1.0 / 2.4) - 0.055;
        assert!(out[0].iter().all(|&v| (f64::from(v) - expected).abs() < 1e-5), "{out:?}");
        let codes = to_u8(&out);
        assert_eq!(codes[..3], [218, 218, 218]);
        assert_eq!(to_u16(&out)[..3], [(expected * 65535.0).round() as u16; 3]);
        // Twice the reference white is compressed into the shoulder, not clipped: L_d = 0.91,
        // code 243 (tone.rs states the curve).
        assert_eq!(codes[3..6], [srgb_code(0.91); 3]);
        assert!(codes[3] < 255);
        // Forty times the reference white is far above it: the 8-bit white.
        assert_eq!(codes[6..9], [255, 255, 255]);
    }

    #[test]
    fn a_chromatic_white_keeps_its_hue() {
        // The white of CIE A (x 0.44757, y 0.40745; CIE 15:2004 Table T.3) at Y = 1, shown as
        // relative (Y = 1 is the reference white). Its linear sRGB from the IEC 61966-2-1
        // matrix is R = 3.2406 X − 1.5372 Y − 0.4986 Z = 1.845, G = 0.826, B = 0.233: red above
        // the cube. At the reference white's 0.7 the grey-ward mapping keeps t = 0.3 / (0.7 ·
        // 1.845 − 0.7) = 0.507 of the chroma: linear (1, 0.638, 0.428), codes (255, 209, 175).
        let (x, y) = (0.44757, 0.40745);
        let a = Chromaticity::new(x, y).to_xyz(1.0);
        let (xx, zz) = (x / y, (1.0 - x - y) / y);
        let lin = [
            3.2406 * xx - 1.5372 - 0.4986 * zz,
            -0.9689 * xx + 1.8758 + 0.0415 * zz,
            0.0557 * xx - 0.2040 + 1.0570 * zz,
        ];
        assert!(lin[0] > 1.0 && lin[0] > lin[1] && lin[1] > lin[2], "{lin:?}");
        let t = 0.3 / (0.7 * lin[0] - 0.7);
        let expected = lin.map(|c| srgb_code(0.7 + t * (0.7 * c - 0.7)));
        for exposure in [Exposure::Relative, Exposure::Absolute { white_cd_m2: 1.0 }] {
            let got = srgb_u8(&[pixel(a)], exposure);
            assert_ne!(got, [255, 255, 255], "{exposure:?}");
            for c in 0..3 {
                assert!(got[c].abs_diff(expected[c]) <= 2, "{exposure:?}: {got:?} vs {expected:?}");
            }
            // R > G > B clearly: an orange, not a grey.
            assert!(got[0] >= got[1] + 30 && got[1] >= got[2] + 20, "{got:?}");
        }
        // CIE B's white (x 0.34842, y 0.35161) is inside the gamut at 0.7 and shown whole, so
        // it differs from A's: linear 0.7 · (1.249, 0.951, 0.753), codes (240, 213, 192).
        let b = Chromaticity::new(0.34842, 0.35161).to_xyz(1.0);
        let got = srgb_u8(&[pixel(b)], Exposure::Relative);
        let expected_b = [1.2486, 0.9511, 0.7530].map(|c| srgb_code(0.7 * c));
        for c in 0..3 {
            assert!(got[c].abs_diff(expected_b[c]) <= 2, "{got:?} vs {expected_b:?}");
        }
        // And C's (x 0.31006, y 0.31616) is slightly blue: B > R > G.
        let c = Chromaticity::new(0.31006, 0.31616).to_xyz(1.0);
        let got = srgb_u8(&[pixel(c)], Exposure::Relative);
        assert!(got[2] > got[0] && got[0] > got[1], "{got:?}");
    }

    #[test]
    fn automatic_exposure_puts_the_log_average_at_the_key() {
        // Half the pixels at 50 cd/m², half at 200: the log-average is √(50 · 200) = 100 cd/m²,
        // and 0.18 / 100 puts the brighter half at 0.36 of the reference white, below the
        // 99th-percentile bound 1 / 200.
        let mut img = vec![grey(50.0); 50];
        img.extend(vec![grey(200.0); 50]);
        img.push([0.0; 3]);
        // The black pixel is left out.
        assert!((log_average_luminance(&img) / 100.0 - 1.0).abs() < 1e-4);
        let k = exposure_scale(&img, Exposure::Automatic { key: 0.18 });
        assert!((k * 100.0 - 0.18).abs() < 1e-5, "{k}");
        assert_eq!(exposure_scale(&img, Exposure::Relative), 1.0);
        assert_eq!(exposure_scale(&img, Exposure::Absolute { white_cd_m2: 250.0 }), 1.0 / 250.0);
        assert_eq!(exposure_scale(&[[0.0; 3]], Exposure::default()), 1.0);
    }

    #[test]
    fn automatic_exposure_keeps_the_99th_percentile_at_most_at_the_reference_white() {
        // A dark room with a lit wall: 80 % of the pixels at 1 cd/m², 20 % at 1000. The
        // log-average is 1000^0.2 ≈ 3.98 cd/m², and the key alone would put the wall at
        // 0.18 · 1000 / 3.98 ≈ 45 times the reference white, washed out in the shoulder. The
        // 99th percentile is the wall: it is put at the reference white.
        let mut img = vec![grey(1.0); 800];
        img.extend(vec![grey(1000.0); 200]);
        let k = exposure_scale(&img, Exposure::Automatic { key: 0.18 });
        assert!((k * 1000.0 - 1.0).abs() < 1e-5, "{k}");
        assert!((luminance_percentile(&img, 99.0) - 1000.0).abs() < 1e-3);
        assert!((luminance_percentile(&img, 50.0) - 1.0).abs() < 1e-6);
        // Shown: the wall at the reference white's grey, 0.7, code 218.
        let codes = srgb_u8(&img, Exposure::Automatic { key: 0.18 });
        assert_eq!(codes[3 * 999..], [218, 218, 218]);
    }

    /// A test card of 64 × 64 pixels, D65 greys whose luminance falls smoothly across it from
    /// 200 cd/m² to 200 / `range`.
    fn card(range: f64) -> Vec<[f32; 3]> {
        (0..64 * 64).map(|i| grey(200.0 * range.powf(-f64::from(i) / 4095.0))).collect()
    }

    #[test]
    fn a_firefly_does_not_change_the_automatic_exposure() {
        // One pixel 10⁴ times brighter than the brightest of the card. On a card of range 4 the
        // key decides (log-average 100 cd/m², 0.18/100 < 1/L₉₉ ≈ 1/198): the firefly's share of
        // the log-average is ln(2·10⁶ / Y)/4096 ≈ 0.25 %. On a card of range 100 the bound
        // decides (log-average 20, 0.18/20 > 1/L₉₉ ≈ 1/191): the 99th percentile moves by one
        // rank of 4096, 0.1 %.
        let exposure = Exposure::Automatic { key: 0.18 };
        for range in [4.0, 100.0] {
            let before = exposure_scale(&card(range), exposure);
            let mut img = card(range);
            img[1234] = grey(200.0 * 1e4);
            let after = exposure_scale(&img, exposure);
            assert!((after / before - 1.0).abs() < 0.01, "range {range}: {before} → {after}");
            // Had the maximum decided, the image would have been 10⁴ times darker.
            assert!(after > 1e3 / (200.0 * 1e4), "range {range}: {after}");
        }
    }

    #[test]
    fn a_hot_spot_does_not_decide_the_automatic_exposure() {
        // A specular highlight or a lamp: 0.5 % of the pixels (20 of 4096) at 10⁵ cd/m², 500
        // times the card's brightest. Fewer than 1 % of the pixels, so the 99th percentile stays
        // on the card; the log-average moves by 20/4096 · ln(10⁵ / Y) ≈ 3.5 %, the share of the
        // pixels the hot spot has, not by the factor of its brightness.
        let exposure = Exposure::Automatic { key: 0.18 };
        let before = exposure_scale(&card(4.0), exposure);
        let mut img = card(4.0);
        for p in img.iter_mut().skip(1).step_by(200).take(20) {
            *p = grey(1e5);
        }
        let after = exposure_scale(&img, exposure);
        assert!(after / before > 0.95 && after < before, "{before} → {after}");
        // The card is shown as it was: its brightest pixel is within a few codes.
        let (b, a) = (srgb_u8(&card(4.0), exposure), srgb_u8(&img, exposure));
        assert!(a[0].abs_diff(b[0]) <= 4, "{} vs {}", a[0], b[0]);
        // The hot spot itself is compressed into the shoulder: brighter than the card, and (at
        // 10⁵ · k ≈ 1.7·10² times the reference white) the 8-bit white.
        assert_eq!(a[3..6], [255, 255, 255]);
    }
}
