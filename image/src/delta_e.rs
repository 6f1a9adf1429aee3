//! How far apart two images are as a person judges colour: CIEDE2000 (CIE 142-2001) pixel by
//! pixel in CIELAB relative to one reference white, its statistics, and the viridis colour map
//! its pictures use. `restauro compare` writes files from it; the studio's compare layer serves
//! the same numbers.

use crate::image_files::XyzImage;
use restauro_spectral::ciede2000::ciede2000;
use restauro_spectral::display::{Exposure, exposure_scale};
use restauro_spectral::{Lab, Xyz};
use serde::Serialize;

/// The ΔE00 map of two images and its statistics.
pub struct DeltaEMap {
    /// Per pixel; NaN where either image shows a light source.
    pub values: Vec<f32>,
    pub stats: DeltaEStats,
}

#[derive(Clone, Debug, Serialize)]
pub struct DeltaEStats {
    /// The pixels compared (light sources left out).
    pub pixels: usize,
    pub mean: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
    /// ΔE00 above which a pixel counts as changed.
    pub threshold: f64,
    /// The share (0–1) of the compared pixels above the threshold.
    pub share_above_threshold: f64,
}

/// ΔE00 between `a` and `b` (the same size) pixel by pixel, in CIELAB relative to `white`.
pub fn delta_e_map(a: &XyzImage, b: &XyzImage, white: Xyz, threshold: f64) -> DeltaEMap {
    let light = |image: &XyzImage, i: usize| image.emitter.as_ref().is_some_and(|m| m[i]);
    let xyz = |p: [f32; 3]| Xyz::from_array(p.map(f64::from));
    let values: Vec<f32> = (0..a.pixels.len())
        .map(|i| {
            if light(a, i) || light(b, i) {
                f32::NAN
            } else {
                let (la, lb) = (
                    Lab::from_xyz(xyz(a.pixels[i]), white),
                    Lab::from_xyz(xyz(b.pixels[i]), white),
                );
                ciede2000(la, lb) as f32
            }
        })
        .collect();
    let mut finite: Vec<f64> =
        values.iter().filter(|v| v.is_finite()).map(|&v| f64::from(v)).collect();
    finite.sort_by(f64::total_cmp);
    let n = finite.len();
    // The value below which a share q of the pixels lie (the nearest rank, ⌊q·n⌋).
    let at = |q: f64| if n == 0 { 0.0 } else { finite[((n as f64 * q) as usize).min(n - 1)] };
    let stats = DeltaEStats {
        pixels: n,
        mean: finite.iter().sum::<f64>() / n.max(1) as f64,
        median: at(0.5),
        p95: at(0.95),
        max: finite.last().copied().unwrap_or(0.0),
        threshold,
        share_above_threshold: finite.iter().filter(|&&v| v > threshold).count() as f64
            / n.max(1) as f64,
    };
    DeltaEMap { values, stats }
}

/// A round top for a ΔE00 scale: the 99th percentile up to the next multiple of 5 (at least 5).
pub fn scale_max(values: &[f32]) -> f64 {
    let mut finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
    finite.sort_by(f32::total_cmp);
    let p99 = f64::from(finite.get(finite.len() * 99 / 100).copied().unwrap_or(1.0));
    ((p99 / 5.0).ceil() * 5.0).max(5.0)
}

/// The reference white's luminance for `image` under `--white`.
pub fn white_luminance(image: &XyzImage, white: Exposure) -> f64 {
    1.0 / exposure_scale(&image.pixels, white)
}

/// matplotlib's viridis sampled at t = 0, 1/8, …, 1, as 0xRRGGBB.
const VIRIDIS: [u32; 9] =
    [0x440154, 0x472d7b, 0x3b528b, 0x2c728e, 0x21918c, 0x28ae80, 0x5ec962, 0xaddc30, 0xfde725];

/// A perceptually ordered colour map (viridis): t in [0,1] (clamped; NaN → magenta
/// [255,0,255], which viridis never produces, so invalid values stand out) → sRGB.
pub fn viridis(t: f64) -> [u8; 3] {
    if t.is_nan() {
        return [255, 0, 255];
    }
    let s = t.clamp(0.0, 1.0) * 8.0;
    let i = (s.floor() as usize).min(7);
    let f = s - i as f64;
    let channel = |rgb: u32, c: usize| f64::from((rgb >> (16 - 8 * c)) & 0xff);
    std::array::from_fn(|c| {
        let (a, b) = (channel(VIRIDIS[i], c), channel(VIRIDIS[i + 1], c));
        (a + f * (b - a)).round() as u8
    })
}

/// The map as 8-bit sRGB pixels: viridis up to `scale_max`, light sources grey.
pub fn map_rgb(map: &DeltaEMap, scale_max: f64) -> Vec<u8> {
    map.values
        .iter()
        .flat_map(|&v| {
            if v.is_nan() {
                [70, 70, 70]
            } else {
                viridis(f64::from(v) / scale_max.max(f64::MIN_POSITIVE))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use restauro_spectral::appearance::d65_white;

    /// Two greys of known CIELAB: L* 50 against L* 55 is ΔE00 4.56 (Sharma, Wu & Dalal's
    /// formula for a pure lightness step at L̄* = 52.5: ΔL/S_L with S_L = 1 + 0.015(L̄−50)²/√(20 +
    /// (L̄−50)²)).
    #[test]
    fn a_lightness_step_has_the_published_difference() {
        let white = d65_white();
        let grey = |l: f64| {
            let xyz = Lab { l, a: 0.0, b: 0.0 }.to_xyz(white);
            [xyz.x as f32, xyz.y as f32, xyz.z as f32]
        };
        let a = XyzImage::new(2, 1, vec![grey(50.0); 2]);
        let mut b = XyzImage::new(2, 1, vec![grey(55.0), grey(50.0)]);
        let map = delta_e_map(&a, &b, white, 2.0);
        let (lbar, dl) = (52.5f64, 5.0f64);
        let sl = 1.0 + 0.015 * (lbar - 50.0).powi(2) / (20.0 + (lbar - 50.0).powi(2)).sqrt();
        assert!((f64::from(map.values[0]) - dl / sl).abs() < 1e-3, "{:?}", map.values);
        assert_eq!(map.values[1], 0.0);
        assert_eq!((map.stats.pixels, map.stats.share_above_threshold), (2, 0.5));
        // A light source in either image is left out.
        b.emitter = Some(vec![true, false]);
        let map = delta_e_map(&a, &b, white, 2.0);
        assert!(map.values[0].is_nan());
        assert_eq!(map.stats.pixels, 1);
    }
}
