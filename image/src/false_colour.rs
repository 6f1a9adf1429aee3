//! Luminance in false colour, the map a lighting designer reads: each pixel's luminance (the Y of
//! the absolute XYZ a render writes, cd/m²) placed on a stated scale, logarithmic or linear, and
//! coloured by viridis; isolines where it crosses each of the scale's levels; and a legend strip
//! below the image with the colour bar, each level's value and the unit. The studio's false
//! colour and `restauro display --false-colour luminance` both draw with this.

use crate::delta_e::viridis;
use crate::error::ImageError;
use std::fmt;
use std::str::FromStr;

/// How luminance is laid along the colour bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Equal steps are equal ratios (the eye's way; a render's luminances span decades).
    Log,
    /// Equal steps are equal differences.
    Linear,
}

impl FromStr for Scale {
    type Err = ImageError;
    fn from_str(s: &str) -> Result<Self, ImageError> {
        match s {
            "log" => Ok(Scale::Log),
            "linear" => Ok(Scale::Linear),
            other => Err(ImageError::UnknownScale { text: other.to_owned() }),
        }
    }
}

impl fmt::Display for Scale {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if *self == Scale::Log { "log" } else { "linear" })
    }
}

/// The values at the ends of the colour bar, in the picture's [`Unit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub min: f64,
    pub max: f64,
}

/// What a false-colour picture shows, named in its legend.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Unit {
    /// Luminance, cd/m² (a render's Y).
    #[default]
    CandelaPerSquareMetre,
    /// Illuminance, lx (a calculation grid's Y).
    Lux,
}

impl Unit {
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::CandelaPerSquareMetre => "cd/m²",
            Unit::Lux => "lx",
        }
    }
}

impl Range {
    /// A range for `scale`, refused unless min < max (and 0 < min on a log scale).
    pub fn new(min_cd_m2: f64, max_cd_m2: f64, scale: Scale) -> Result<Self, ImageError> {
        let finite = min_cd_m2.is_finite() && max_cd_m2.is_finite();
        if !finite || min_cd_m2 >= max_cd_m2 || min_cd_m2 < 0.0 {
            return Err(ImageError::EmptyRange { min_cd_m2, max_cd_m2 });
        }
        if scale == Scale::Log && min_cd_m2 <= 0.0 {
            return Err(ImageError::LogRangeFromZero { min_cd_m2, max_cd_m2 });
        }
        Ok(Range { min: min_cd_m2, max: max_cd_m2 })
    }

    /// The range chosen for an image: whole decades around the 1st and 99th percentiles of its
    /// luminances above zero (log), or 0 to the 99th percentile rounded up to 1, 2 or 5 times a
    /// power of ten (linear).
    pub fn auto(pixels: &[[f32; 3]], scale: Scale) -> Range {
        let [p1, _, p99] = percentiles(pixels);
        match scale {
            Scale::Log => {
                let min = 10f64.powf(p1.log10().floor());
                let max = 10f64.powf(p99.log10().ceil()).max(min * 10.0);
                Range { min, max }
            }
            Scale::Linear => Range { min: 0.0, max: nice_above(p99) },
        }
    }
}

/// The 1st, 50th and 99th percentiles of the luminances above zero, cd/m² (1 when none is).
pub fn percentiles(pixels: &[[f32; 3]]) -> [f64; 3] {
    let mut y: Vec<f64> = pixels.iter().map(|p| f64::from(p[1])).filter(|v| *v > 0.0).collect();
    y.sort_by(f64::total_cmp);
    [0.01, 0.5, 0.99].map(|q| {
        y.get(((y.len() as f64 * q) as usize).min(y.len().saturating_sub(1)))
            .copied()
            .unwrap_or(1.0)
    })
}

/// The least of 1, 2 or 5 times a power of ten that is at least `v`.
pub fn nice_above(v: f64) -> f64 {
    let decade = 10f64.powf(v.max(f64::MIN_POSITIVE).log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * decade).find(|n| *n >= v).unwrap_or(10.0 * decade)
}

/// Where luminance `y` falls on the scale from `range.min` to `range.max` (0–1, clamped).
pub fn position(y: f64, scale: Scale, range: Range) -> f64 {
    let Range { min, max } = range;
    match scale {
        Scale::Log if y <= 0.0 => 0.0,
        Scale::Log => ((y.log10() - min.log10()) / (max.log10() - min.log10())).clamp(0.0, 1.0),
        Scale::Linear => ((y - min) / (max - min)).clamp(0.0, 1.0),
    }
}

/// The luminance at `t` (0–1) along the scale.
pub fn value_at(t: f64, scale: Scale, range: Range) -> f64 {
    let Range { min, max } = range;
    match scale {
        Scale::Log => 10f64.powf(min.log10() + t * (max.log10() - min.log10())),
        Scale::Linear => min + t * (max - min),
    }
}

/// How a false-colour picture is drawn.
#[derive(Clone, Copy, Debug)]
pub struct FalseColour {
    pub scale: Scale,
    pub range: Range,
    /// The bands between isolines: an isoline at each of the `bands − 1` inner levels (0: none).
    pub bands: u32,
    pub unit: Unit,
}

/// The height of the legend strip below the image, in pixels.
pub const LEGEND_PX: usize = 36;

/// `pixels` (absolute XYZ, row-major, `width` wide) in false colour with its isolines, and the
/// legend below: 8-bit sRGB, `width` × (height + [`LEGEND_PX`]).
pub fn picture(pixels: &[[f32; 3]], width: usize, fc: &FalseColour) -> Vec<u8> {
    let height = pixels.len() / width.max(1);
    let t: Vec<f64> =
        pixels.iter().map(|p| position(f64::from(p[1]), fc.scale, fc.range)).collect();
    let band = |i: usize| (t[i] * f64::from(fc.bands)).floor().min(f64::from(fc.bands) - 1.0);
    let mut rgb = Vec::with_capacity(width * (height + LEGEND_PX) * 3);
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let edge = fc.bands > 1
                && ((x + 1 < width && band(i) != band(i + 1))
                    || (y + 1 < height && band(i) != band(i + width)));
            rgb.extend_from_slice(&if edge { [0, 0, 0] } else { viridis(t[i]) });
        }
    }
    rgb.extend(legend(width, fc));
    rgb
}

/// The legend strip: the colour bar with a tick at each level, the levels' values under their
/// ticks where they fit, and the unit at the right.
fn legend(width: usize, fc: &FalseColour) -> Vec<u8> {
    let mut strip = Canvas { width, rgb: vec![255; width * LEGEND_PX * 3] };
    let (left, right) = (4usize, width.saturating_sub(4).max(5));
    let span = (right - left) as f64;
    for x in left..right {
        let colour = viridis((x - left) as f64 / span);
        for y in 4..16 {
            strip.set(x, y, colour);
        }
    }
    let unit = fc.unit.symbol();
    let unit_x = right.saturating_sub(text_width(unit));
    strip.text(unit_x, 22, unit);
    let levels = fc.bands.max(1);
    let mut free_from = 0usize;
    for k in 0..=levels {
        let t = f64::from(k) / f64::from(levels);
        let x = left + (t * span).round() as usize;
        for y in 16..20 {
            strip.set(x.min(width - 1), y, [0, 0, 0]);
        }
        let label = number(value_at(t, fc.scale, fc.range));
        let w = text_width(&label);
        let start = x.saturating_sub(w / 2).min(width.saturating_sub(w));
        if start >= free_from && start + w + 4 <= unit_x {
            strip.text(start, 22, &label);
            free_from = start + w + 6;
        }
    }
    strip.rgb
}

/// A value as a legend prints it: three significant digits, in exponent form when very large
/// or small.
fn number(v: f64) -> String {
    if v == 0.0 {
        "0".to_owned()
    } else if !(0.01..100_000.0).contains(&v.abs()) {
        format!("{v:.1e}")
    } else {
        let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
        let text = format!("{v:.digits$}");
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            text
        }
    }
}

/// An RGB strip to draw the legend on.
struct Canvas {
    width: usize,
    rgb: Vec<u8>,
}

/// Glyphs are drawn at twice their 5-row size.
const GLYPH_SCALE: usize = 2;

impl Canvas {
    fn set(&mut self, x: usize, y: usize, colour: [u8; 3]) {
        let i = (y * self.width + x) * 3;
        if x < self.width && i + 3 <= self.rgb.len() {
            self.rgb[i..i + 3].copy_from_slice(&colour);
        }
    }

    fn text(&mut self, x: usize, y: usize, text: &str) {
        let mut at = x;
        for c in text.chars() {
            let (w, rows) = glyph(c);
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..w {
                    if bits >> (w - 1 - col) & 1 == 1 {
                        for dy in 0..GLYPH_SCALE {
                            for dx in 0..GLYPH_SCALE {
                                let px = at + col * GLYPH_SCALE + dx;
                                self.set(px, y + r * GLYPH_SCALE + dy, [0, 0, 0]);
                            }
                        }
                    }
                }
            }
            at += (w + 1) * GLYPH_SCALE;
        }
    }
}

/// The width of `text` as drawn, in pixels.
fn text_width(text: &str) -> usize {
    text.chars().map(|c| (glyph(c).0 + 1) * GLYPH_SCALE).sum()
}

/// A glyph of the legend's font: its width and its five rows, high bit on the left. Only what
/// a value and the units need (digits, `.`, `-`, `+`, `e`, `c`, `d`, `/`, `m`, `²`, `l`, `x`).
fn glyph(c: char) -> (usize, [u8; 5]) {
    match c {
        '0' => (3, [0b111, 0b101, 0b101, 0b101, 0b111]),
        '1' => (3, [0b010, 0b110, 0b010, 0b010, 0b111]),
        '2' => (3, [0b111, 0b001, 0b111, 0b100, 0b111]),
        '3' => (3, [0b111, 0b001, 0b111, 0b001, 0b111]),
        '4' => (3, [0b101, 0b101, 0b111, 0b001, 0b001]),
        '5' => (3, [0b111, 0b100, 0b111, 0b001, 0b111]),
        '6' => (3, [0b111, 0b100, 0b111, 0b101, 0b111]),
        '7' => (3, [0b111, 0b001, 0b001, 0b001, 0b001]),
        '8' => (3, [0b111, 0b101, 0b111, 0b101, 0b111]),
        '9' => (3, [0b111, 0b101, 0b111, 0b001, 0b111]),
        '.' => (1, [0, 0, 0, 0, 1]),
        '-' => (3, [0, 0, 0b111, 0, 0]),
        '+' => (3, [0, 0b010, 0b111, 0b010, 0]),
        'e' => (3, [0, 0b111, 0b111, 0b100, 0b111]),
        'c' => (3, [0, 0b111, 0b100, 0b100, 0b111]),
        'd' => (3, [0b001, 0b001, 0b111, 0b101, 0b111]),
        '/' => (3, [0b001, 0b001, 0b010, 0b100, 0b100]),
        'm' => (5, [0, 0b11110, 0b10101, 0b10101, 0b10101]),
        '²' => (3, [0b110, 0b001, 0b010, 0b111, 0]),
        'l' => (1, [1, 1, 1, 1, 1]),
        'x' => (3, [0, 0b101, 0b010, 0b010, 0b101]),
        _ => (3, [0; 5]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_on_both_scales() {
        let range = Range::new(1.0, 1000.0, Scale::Log).unwrap();
        assert!((position(10.0, Scale::Log, range) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(position(0.0, Scale::Log, range), 0.0);
        assert_eq!(position(5000.0, Scale::Log, range), 1.0);
        let range = Range::new(0.0, 200.0, Scale::Linear).unwrap();
        assert_eq!(position(50.0, Scale::Linear, range), 0.25);
        assert!((value_at(0.25, Scale::Linear, range) - 50.0).abs() < 1e-12);
        assert!(Range::new(0.0, 10.0, Scale::Log).is_err());
        assert!(Range::new(5.0, 5.0, Scale::Linear).is_err());
        assert!(Range::new(f64::NAN, 5.0, Scale::Linear).is_err());
    }

    #[test]
    fn numbers_and_nice_ends() {
        assert_eq!(number(1000.0), "1000");
        assert_eq!(number(31.6227), "31.6");
        assert_eq!(number(0.5), "0.5");
        assert_eq!(number(2.5e6), "2.5e6");
        assert_eq!(nice_above(130.0), 200.0);
        assert_eq!(nice_above(4.2), 5.0);
        assert_eq!(nice_above(100.0), 100.0);
    }

    /// Luminance rising linearly across the image from 0 to 100 cd/m², on a linear scale of
    /// 0–100 in four bands: isolines at x = 25, 50 and 75 % of the width and nowhere else.
    #[test]
    fn isolines_stand_where_the_levels_are_crossed() {
        let (w, h) = (101usize, 3usize);
        let pixels: Vec<[f32; 3]> = (0..w * h).map(|i| [0.0, (i % w) as f32, 0.0]).collect();
        let fc = FalseColour {
            scale: Scale::Linear,
            range: Range::new(0.0, 100.0, Scale::Linear).unwrap(),
            bands: 4,
            unit: Unit::CandelaPerSquareMetre,
        };
        let rgb = picture(&pixels, w, &fc);
        assert_eq!(rgb.len(), w * (h + LEGEND_PX) * 3);
        let black: Vec<usize> = (0..w).filter(|&x| rgb[x * 3..x * 3 + 3] == [0, 0, 0]).collect();
        assert_eq!(black, [24, 49, 74]);
        // Elsewhere viridis, at the pixel's place on the scale: 60 cd/m² is at 0.6.
        assert_eq!(rgb[60 * 3..60 * 3 + 3], viridis(0.6));
        // The legend holds dark text (the levels' values and the unit) under its colour bar.
        let legend = &rgb[w * h * 3..];
        let dark = legend.chunks(3).skip(w * 20).filter(|p| p.iter().all(|&c| c < 50)).count();
        assert!(dark > 20, "{dark} dark pixels of text");
    }
}
