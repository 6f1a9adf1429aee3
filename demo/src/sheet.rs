//! Labelled "contact sheets" for the demo's output and `restauro compare`.
//!
//! A sheet is a grid of images with text drawn straight into the pixels (title, row and column
//! labels, captions, footer), so one PNG explains itself without a viewer or HTML page. Text uses
//! the public-domain 8×8 bitmap font from `font8x8`, scaled by pixel replication: crisp at any
//! integer scale and free of font files. For difference maps (e.g. CIEDE2000) there is a viridis
//! colour map and a labelled colour bar. Nothing here writes files: every function returns an
//! [`Rgb8`] that the caller encodes however it likes.

use font8x8::{BASIC_FONTS, GREEK_FONTS, LATIN_FONTS, UnicodeFonts};
use restauro_spectral::rgb_space::Transfer;

/// Sheet background: dark neutral grey, so neither bright nor dark renders dominate.
pub const BACKGROUND: [u8; 3] = [24, 24, 24];
/// Text colour on [`BACKGROUND`].
pub const INK: [u8; 3] = [235, 235, 235];

const MARGIN: u32 = 12;
const GAP: u32 = 8;
/// Line pitch of scale-2 text: 16 px glyphs plus 4 px leading.
const LINE2: u32 = 20;
/// Line pitch of scale-1 text: 8 px glyphs plus 2 px leading.
const LINE1: u32 = 10;
/// Row labels wrap at this many characters so one long label doesn't widen the whole sheet.
const ROW_LABEL_CHARS: usize = 22;

/// An 8-bit sRGB image, row-major, 3 bytes per pixel (`data.len() == width * height * 3`).
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl Rgb8 {
    /// A `width` × `height` image filled with `background`.
    pub fn new(width: u32, height: u32, background: [u8; 3]) -> Self {
        let data = background.repeat(width as usize * height as usize);
        Rgb8 { width, height, data }
    }

    /// The pixel at (x, y). Panics if (x, y) is outside the image.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside image");
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Sets one pixel; coordinates outside the image are ignored.
    pub fn put(&mut self, x: u32, y: u32, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = (y as usize * self.width as usize + x as usize) * 3;
            self.data[i..i + 3].copy_from_slice(&c);
        }
    }

    /// The part of the span [start, start + len) that lies inside [0, limit), if any.
    fn clip(start: i64, len: u32, limit: u32) -> Option<(usize, usize)> {
        let lo = start.max(0);
        let hi = (start + i64::from(len)).min(i64::from(limit));
        (lo < hi).then_some((lo as usize, hi as usize))
    }

    /// Fills a rectangle, clipped to the image.
    pub fn fill_rect(&mut self, x: i64, y: i64, w: u32, h: u32, c: [u8; 3]) {
        let (Some((x0, x1)), Some((y0, y1))) =
            (Self::clip(x, w, self.width), Self::clip(y, h, self.height))
        else {
            return;
        };
        let stride = self.width as usize * 3;
        for row in y0..y1 {
            let span = &mut self.data[row * stride + x0 * 3..row * stride + x1 * 3];
            span.chunks_exact_mut(3).for_each(|p| p.copy_from_slice(&c));
        }
    }

    /// Draws a 1-px rectangle outline, clipped to the image.
    pub fn stroke_rect(&mut self, x: i64, y: i64, w: u32, h: u32, c: [u8; 3]) {
        if w == 0 || h == 0 {
            return;
        }
        self.fill_rect(x, y, w, 1, c);
        self.fill_rect(x, y + i64::from(h) - 1, w, 1, c);
        self.fill_rect(x, y, 1, h, c);
        self.fill_rect(x + i64::from(w) - 1, y, 1, h, c);
    }

    /// Copies `src` with its top-left corner at (x, y), clipped to this image.
    pub fn blit(&mut self, x: i64, y: i64, src: &Rgb8) {
        let (Some((x0, x1)), Some((y0, y1))) =
            (Self::clip(x, src.width, self.width), Self::clip(y, src.height, self.height))
        else {
            return;
        };
        let (dst_stride, src_stride) = (self.width as usize * 3, src.width as usize * 3);
        // Offsets of the visible part inside `src` (non-zero when x or y is negative).
        let (sx, sy) = ((x0 as i64 - x) as usize, (y0 as i64 - y) as usize);
        for row in y0..y1 {
            let s = (row - y0 + sy) * src_stride + sx * 3;
            let d = row * dst_stride + x0 * 3;
            let n = (x1 - x0) * 3;
            self.data[d..d + n].copy_from_slice(&src.data[s..s + n]);
        }
    }

    /// Area-averaged resize to the given width, keeping the aspect ratio (height rounded, ≥ 1).
    /// Averaging is done in linear light (decode sRGB, average, encode) so downscaled images keep
    /// their brightness. A width of 0 is treated as 1; an empty source gives a black 1-px-tall image.
    pub fn resized_to_width(&self, width: u32) -> Rgb8 {
        let width = width.max(1);
        if self.width == 0 || self.height == 0 {
            return Rgb8::new(width, 1, [0; 3]);
        }
        if width == self.width {
            return self.clone();
        }
        let ratio = f64::from(width) / f64::from(self.width);
        let height = ((f64::from(self.height) * ratio).round() as u32).max(1);
        let lut: Vec<f64> = (0..=255u8).map(srgb_to_linear).collect();
        let (xw, yw) = (box_weights(self.width, width), box_weights(self.height, height));
        // Horizontal pass into a linear-light buffer (width × source height), then vertical.
        let mut tmp = vec![0.0f64; width as usize * self.height as usize * 3];
        for y in 0..self.height as usize {
            let src_row = &self.data[y * self.width as usize * 3..];
            for (ox, taps) in xw.iter().enumerate() {
                let out = &mut tmp[(y * width as usize + ox) * 3..][..3];
                for &(ix, w) in taps {
                    for c in 0..3 {
                        out[c] += w * lut[src_row[ix * 3 + c] as usize];
                    }
                }
            }
        }
        let mut img = Rgb8::new(width, height, [0; 3]);
        for (oy, taps) in yw.iter().enumerate() {
            for ox in 0..width as usize {
                let mut acc = [0.0f64; 3];
                for &(iy, w) in taps {
                    let t = &tmp[(iy * width as usize + ox) * 3..][..3];
                    acc.iter_mut().zip(t).for_each(|(a, v)| *a += w * v);
                }
                img.put(ox as u32, oy as u32, acc.map(linear_to_srgb));
            }
        }
        img
    }

    /// Draws `text` with font8x8 glyphs at an integer `scale` (1 = 8 px per glyph cell), top-left
    /// at (x, y); returns the advance width in pixels. Supports printable ASCII, Latin-1, Greek
    /// (for Δ) and maps common typographic characters to ASCII; unknown characters draw '?'.
    /// Clipped at the image border.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: u32, colour: [u8; 3]) -> u32 {
        let s = i64::from(scale);
        for (i, ch) in text.chars().enumerate() {
            let gx = x + i as i64 * 8 * s;
            for (row, bits) in glyph(ch).into_iter().enumerate() {
                // font8x8 stores the leftmost pixel of each row in bit 0.
                for col in (0..8).filter(|b| bits >> b & 1 == 1) {
                    self.fill_rect(gx + col * s, y + row as i64 * s, scale, scale, colour);
                }
            }
        }
        text_width(text, scale)
    }
}

/// Width in pixels that `text` takes at `scale` (8·scale per char).
pub fn text_width(text: &str, scale: u32) -> u32 {
    (text.chars().count() as u32).saturating_mul(scale.saturating_mul(8))
}

/// The 8×8 bitmap for `ch`, falling back to '?' so missing glyphs stay visible.
fn glyph(ch: char) -> [u8; 8] {
    // The font has no glyphs for these, but their ASCII look-alikes read the same in labels.
    // × and · also exist in Latin-1; the ASCII forms keep "4×" and "4x" looking the same.
    let ch = match ch {
        '‐' | '‑' | '‒' | '–' | '—' | '−' => '-',
        '‘' | '’' | '‚' | '′' => '\'',
        '“' | '”' | '„' | '″' => '"',
        '×' => 'x',
        '·' | '•' => '.',
        c => c,
    };
    let found = if (' '..='~').contains(&ch) {
        BASIC_FONTS.get(ch)
    } else {
        LATIN_FONTS.get(ch).or_else(|| GREEK_FONTS.get(ch))
    };
    found.or_else(|| BASIC_FONTS.get('?')).unwrap_or_default()
}

/// An 8-bit sRGB code's linear value (IEC 61966-2-1).
fn srgb_to_linear(v: u8) -> f64 {
    Transfer::Srgb.decode(f64::from(v) / 255.0)
}

/// A linear value's 8-bit sRGB code (IEC 61966-2-1).
fn linear_to_srgb(l: f64) -> u8 {
    (Transfer::Srgb.encode(l) * 255.0).round() as u8
}

/// For each of `dst` output pixels, the source pixels it covers and their normalised overlap
/// (a box filter: exact area averaging for downscaling, nearest-like for upscaling).
fn box_weights(src: u32, dst: u32) -> Vec<Vec<(usize, f64)>> {
    let step = f64::from(src) / f64::from(dst);
    (0..dst)
        .map(|o| {
            let (a, b) = (f64::from(o) * step, f64::from(o + 1) * step);
            let mut taps: Vec<(usize, f64)> = (a.floor() as usize
                ..(b.ceil() as usize).min(src as usize))
                .map(|i| (i, b.min(i as f64 + 1.0) - a.max(i as f64)))
                .filter(|&(_, w)| w > 0.0)
                .collect();
            let sum: f64 = taps.iter().map(|t| t.1).sum();
            taps.iter_mut().for_each(|t| t.1 /= sum);
            taps
        })
        .collect()
}

/// Greedy word wrap to at most `max_chars` characters per line; honours '\n' and hard-breaks
/// words longer than a line. Empty text gives no lines.
fn wrap(text: &str, max_chars: usize) -> Vec<String> {
    let max_chars = max_chars.max(1);
    let mut lines = Vec::new();
    for para in text.lines() {
        let mut line = String::new();
        for word in para.split_whitespace() {
            let chars: Vec<char> = word.chars().collect();
            for piece in chars.chunks(max_chars) {
                let (n, p) = (line.chars().count(), piece.len());
                if n > 0 && n + 1 + p > max_chars {
                    lines.push(std::mem::take(&mut line));
                } else if n > 0 {
                    line.push(' ');
                }
                line.extend(piece);
            }
        }
        if !line.is_empty() {
            lines.push(line);
        }
    }
    lines
}

/// Height in pixels of `lines` lines of text drawn with line pitch `pitch` at `scale`.
fn block_height(lines: usize, pitch: u32, scale: u32) -> u32 {
    if lines == 0 { 0 } else { (lines as u32 - 1) * pitch + 8 * scale }
}

/// Entry `i` of a possibly short list of texts; missing entries are empty.
fn at(v: &[String], i: usize) -> &str {
    v.get(i).map_or("", String::as_str)
}

fn widest(lines: &[String], scale: u32) -> u32 {
    lines.iter().map(|l| text_width(l, scale)).max().unwrap_or(0)
}

/// A grid of images with labels: a title line at the top, column labels over each column,
/// row labels to the left of each row, each cell image resized to `cell_width`, an optional
/// caption under each cell, and free-form footer lines at the bottom. Cells may be None (left blank).
pub struct Grid<'a> {
    pub title: &'a str,
    pub column_labels: Vec<String>,
    pub row_labels: Vec<String>,
    /// `[row][column]`.
    pub cells: Vec<Vec<Option<Rgb8>>>,
    /// `[row][column]`; may be empty or ragged (missing entries mean no caption).
    pub captions: Vec<Vec<String>>,
    pub cell_width: u32,
    pub footer: Vec<String>,
}

impl Grid<'_> {
    /// Lays out and draws the sheet. Blocks (title, column labels, each row, footer) are stacked
    /// with `GAP` between them inside a `MARGIN`; a row is as tall as its tallest cell (or its
    /// wrapped label, if taller), plus its captions.
    pub fn render(&self) -> Rgb8 {
        let cw = self.cell_width.max(1);
        let n_rows = self.row_labels.len().max(self.cells.len());
        let n_cols =
            self.column_labels.len().max(self.cells.iter().map(Vec::len).max().unwrap_or(0));
        // With no rows or no columns there is no grid at all, just title and footer.
        let (n_rows, n_cols) = if n_rows == 0 || n_cols == 0 { (0, 0) } else { (n_rows, n_cols) };
        let row_labels: Vec<Vec<String>> =
            (0..n_rows).map(|r| wrap(at(&self.row_labels, r), ROW_LABEL_CHARS)).collect();
        let col_labels: Vec<Vec<String>> =
            (0..n_cols).map(|c| wrap(at(&self.column_labels, c), (cw / 16) as usize)).collect();
        let captions: Vec<Vec<Vec<String>>> = (0..n_rows)
            .map(|r| {
                let row = self.captions.get(r).map_or(&[][..], Vec::as_slice);
                (0..n_cols).map(|c| wrap(at(row, c), (cw / 8) as usize)).collect()
            })
            .collect();
        // Resize every cell once up front: row heights depend on the resized heights.
        let cells: Vec<Vec<Option<Rgb8>>> = (0..n_rows)
            .map(|r| {
                let row = self.cells.get(r).map_or(&[][..], Vec::as_slice);
                (0..n_cols).map(|c| row.get(c)?.as_ref().map(|i| i.resized_to_width(cw))).collect()
            })
            .collect();
        let label_w = row_labels.iter().map(|l| widest(l, 2)).max().unwrap_or(0);
        let col_h = block_height(col_labels.iter().map(Vec::len).max().unwrap_or(0), LINE2, 2);
        // Per row: (image band height, image band + captions height).
        let rows: Vec<(u32, u32)> = (0..n_rows)
            .map(|r| {
                let tallest = cells[r].iter().flatten().map(|i| i.height).max().unwrap_or(0);
                let img_h = tallest.max(block_height(row_labels[r].len(), LINE2, 2));
                let cap =
                    block_height(captions[r].iter().map(Vec::len).max().unwrap_or(0), LINE1, 1);
                (img_h, if cap > 0 { img_h + 4 + cap } else { img_h })
            })
            .collect();

        let foot_h = block_height(self.footer.len(), LINE1, 1);
        let title_h = if self.title.is_empty() { 0 } else { 16 };
        let mut blocks: Vec<u32> = [title_h, col_h].into_iter().filter(|&h| h > 0).collect();
        blocks.extend(rows.iter().map(|r| r.1));
        blocks.extend((foot_h > 0).then_some(foot_h));
        let content = blocks.iter().sum::<u32>() + GAP * (blocks.len() as u32).saturating_sub(1);
        let mut width = 2 * MARGIN + text_width(self.title, 2).max(widest(&self.footer, 1));
        if n_cols > 0 {
            width = width.max(2 * MARGIN + label_w + n_cols as u32 * (cw + GAP));
        }
        let mut img = Rgb8::new(width, 2 * MARGIN + content, BACKGROUND);

        let m = i64::from(MARGIN);
        let col_x = |c: usize| m + i64::from(label_w + GAP) + c as i64 * i64::from(cw + GAP);
        let line_y = |top: i64, k: usize, pitch: u32| top + k as i64 * i64::from(pitch);
        let mut y = m;
        if title_h > 0 {
            img.text(m, y, self.title, 2, INK);
            y += i64::from(title_h + GAP);
        }
        if col_h > 0 {
            for (c, lines) in col_labels.iter().enumerate() {
                for (k, line) in lines.iter().enumerate() {
                    let dx = i64::from(cw.saturating_sub(text_width(line, 2)) / 2);
                    img.text(col_x(c) + dx, line_y(y, k, LINE2), line, 2, INK);
                }
            }
            y += i64::from(col_h + GAP);
        }
        for (r, &(img_h, row_h)) in rows.iter().enumerate() {
            for (k, line) in row_labels[r].iter().enumerate() {
                img.text(m, line_y(y, k, LINE2), line, 2, INK);
            }
            for c in 0..n_cols {
                if let Some(cell) = &cells[r][c] {
                    img.blit(col_x(c), y, cell);
                }
                for (k, line) in captions[r][c].iter().enumerate() {
                    img.text(col_x(c), line_y(y + i64::from(img_h) + 4, k, LINE1), line, 1, INK);
                }
            }
            y += i64::from(row_h + GAP);
        }
        for (k, line) in self.footer.iter().enumerate() {
            img.text(m, line_y(y, k, LINE1), line, 1, INK);
        }
        img
    }
}

/// The viridis colour map, shared with the studio's ΔE00 layer.
pub use restauro_image::delta_e::viridis;

/// A map image: each value v (row-major, width×height) coloured viridis(v / max_value).
/// Missing values and NaN show magenta; with a non-positive `max_value` every positive value
/// saturates (the divisor is clamped to the smallest positive float instead of dividing by 0).
pub fn colour_map(values: &[f32], width: u32, height: u32, max_value: f64) -> Rgb8 {
    let mut img = Rgb8::new(width, height, [0; 3]);
    for (i, px) in img.data.chunks_exact_mut(3).enumerate() {
        let v = values.get(i).map_or(f64::NAN, |&v| f64::from(v));
        let t = v / max_value.max(f64::MIN_POSITIVE);
        px.copy_from_slice(&viridis(t));
    }
    img
}

const BAR_PAD: u32 = 8;
const BAR_WIDTH: u32 = 24;
/// Top of the bar: below the scale-2 label, with room for the top tick label to straddle it.
const BAR_TOP: u32 = BAR_PAD + 16 + 8;

/// A vertical colour bar `height` px tall with tick labels: `ticks` evenly spaced values from 0 to
/// `max_value` (inclusive), each label formatted with the given number of decimals, and a label
/// text (e.g. "ΔE00") above it. Returns an image (bar 24 px wide plus tick labels to its right).
pub fn colour_bar(max_value: f64, ticks: usize, decimals: usize, label: &str, height: u32) -> Rgb8 {
    let height = height.max(1);
    // Tick k sits at fraction k/(ticks-1) of the range; a single tick is 0.
    let frac = |k: usize| if ticks > 1 { k as f64 / (ticks - 1) as f64 } else { 0.0 };
    let labels: Vec<String> =
        (0..ticks).map(|k| format!("{:.*}", decimals, max_value * frac(k))).collect();
    let text_x = BAR_PAD + BAR_WIDTH + 7;
    let width = (text_x + widest(&labels, 1)).max(BAR_PAD + text_width(label, 2)) + BAR_PAD;
    let mut img = Rgb8::new(width, BAR_TOP + height + 4 + BAR_PAD, BACKGROUND);
    img.text(i64::from(BAR_PAD), i64::from(BAR_PAD), label, 2, INK);
    let (bx, top) = (i64::from(BAR_PAD), i64::from(BAR_TOP));
    for j in 0..height {
        let t = if height > 1 { 1.0 - f64::from(j) / f64::from(height - 1) } else { 1.0 };
        img.fill_rect(bx, top + i64::from(j), BAR_WIDTH, 1, viridis(t));
    }
    // Outline just outside the bar so the end colours stay exact.
    img.stroke_rect(bx - 1, top - 1, BAR_WIDTH + 2, height + 2, [128; 3]);
    for (k, text) in labels.iter().enumerate() {
        let ty = top + ((1.0 - frac(k)) * f64::from(height - 1)).round() as i64;
        img.fill_rect(bx + i64::from(BAR_WIDTH), ty, 4, 1, INK);
        img.text(i64::from(text_x), ty - 4, text, 1, INK);
    }
    img
}

/// `grid` with a colour bar to its right, the bar's top a little below the grid's title so that
/// its scale stands beside the first row of cells.
pub fn beside_colour_bar(grid: &Rgb8, bar: &Rgb8) -> Rgb8 {
    let mut sheet =
        Rgb8::new(grid.width + bar.width + 24, grid.height.max(bar.height + 60), BACKGROUND);
    sheet.blit(0, 0, grid);
    sheet.blit(i64::from(grid.width), 56, bar);
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    fn single(ch: &str) -> Rgb8 {
        let mut img = Rgb8::new(8, 8, [0; 3]);
        img.text(0, 0, ch, 1, [255; 3]);
        img
    }

    #[test]
    fn text_stays_in_its_box_and_falls_back() {
        let (red, s) = ([255, 0, 0], "Hi ΔE00 – x°");
        let mut img = Rgb8::new(300, 40, [0; 3]);
        let adv = img.text(5, 7, s, 2, red);
        assert_eq!((adv, text_width(s, 2)), (12 * 16, 12 * 16));
        let hits: Vec<(u32, u32)> = (0..img.height)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get(x, y) == red)
            .collect();
        assert!(hits.len() > 50);
        assert!(hits.iter().all(|&(x, y)| (5..5 + adv).contains(&x) && (7..23).contains(&y)));
        img.text(-20, -5, s, 3, red); // clipped at the borders, no panic
        img.text(290, 35, s, 3, red);
        // Exact placement and bit order (bit 0 = leftmost) on an asymmetric glyph at scale 2.
        let (mut f, bits) = (Rgb8::new(16, 16, [0; 3]), BASIC_FONTS.get('F').unwrap());
        f.text(0, 0, "F", 2, [255; 3]);
        for (x, y) in (0..16).flat_map(|y| (0..16).map(move |x| (x, y))) {
            assert_eq!(f.get(x, y) == [255; 3], bits[y as usize / 2] >> (x / 2) & 1 == 1);
        }
        let q = single("?");
        assert!(single("Δ") != q && single("Δ") != Rgb8::new(8, 8, [0; 3]));
        assert_eq!(single("☃"), q);
        assert_eq!(single("–"), single("-"));
    }

    #[test]
    fn resize_keeps_uniform_images_and_averages_in_linear_light() {
        for v in [0u8, 1, 37, 128, 254, 255] {
            let img = Rgb8::new(37, 23, [v, 255 - v, v / 2]);
            assert_eq!(img.resized_to_width(10), Rgb8::new(10, 6, [v, 255 - v, v / 2]));
            assert_eq!(img.resized_to_width(80), Rgb8::new(80, 50, [v, 255 - v, v / 2]));
        }
        let mut img = Rgb8::new(2, 1, [0; 3]);
        img.put(1, 0, [255; 3]);
        let r = img.resized_to_width(1);
        assert_eq!((r.width, r.height), (1, 1));
        assert!((187..=189).contains(&r.get(0, 0)[0]), "{:?}", r.get(0, 0));
    }

    #[test]
    fn viridis_anchors_and_order() {
        assert_eq!(viridis(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(viridis(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(viridis(0.5), [0x21, 0x91, 0x8c]);
        assert_eq!((viridis(-3.0), viridis(f64::NAN)), (viridis(0.0), [255, 0, 255]));
        let lum = |t: f64| {
            let l = viridis(t).map(srgb_to_linear);
            0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]
        };
        // Strictly increasing at steps coarser than 8-bit rounding; near-monotone in between.
        assert!((1..=128).all(|k| lum(f64::from(k) / 128.0) > lum(f64::from(k - 1) / 128.0)));
        assert!((1..=1000).all(|k| lum(f64::from(k) / 1e3) > lum(f64::from(k - 1) / 1e3) - 1e-3));
    }

    #[test]
    fn grid_layout() {
        let colour = |r: u32, c: u32| [40 + 50 * c as u8, 200 - 80 * r as u8, 99];
        let grid = Grid {
            title: "T",
            column_labels: vec!["x".into(), "y".into(), "z".into()],
            row_labels: vec!["a".into(), "b".into()],
            cells: (0..2)
                .map(|r| (0..3).map(|c| Some(Rgb8::new(16, 8, colour(r, c)))).collect())
                .collect(),
            captions: vec![],
            cell_width: 40,
            footer: vec![],
        };
        let img = grid.render();
        // margin + row label (1 char at scale 2) + 3 × (cell + gap) + margin.
        assert_eq!(img.width, 12 + 16 + 3 * (40 + 8) + 12);
        // margin + title + gap + column labels + gap + row + gap + row + margin.
        assert_eq!(img.height, 12 + 16 + 8 + 16 + 8 + 20 + 8 + 20 + 12);
        for (r, c) in (0..2).flat_map(|r| (0..3).map(move |c| (r, c))) {
            let (x0, y0, want) = (12 + 16 + 8 + c * 48, 12 + 24 + 24 + r * 28, colour(r, c));
            for (x, y) in [(x0, y0), (x0 + 39, y0 + 19), (x0 + 20, y0 + 10)] {
                assert_eq!(img.get(x, y), want, "cell ({r},{c}) at ({x},{y})");
            }
            assert!(img.get(x0 - 1, y0) != want && img.get(x0 + 40, y0 + 19) != want);
        }
    }

    #[test]
    fn grid_edge_cases() {
        let foot = "a footer line wider than the title";
        let mut grid = Grid {
            title: "Only a title",
            column_labels: vec!["c".into()],
            row_labels: vec![],
            cells: vec![],
            captions: vec![vec!["orphan".into()]],
            cell_width: 0,
            footer: vec![foot.into()],
        };
        let img = grid.render();
        assert_eq!((img.width, img.height), (24 + text_width(foot, 1), 24 + 16 + 8 + 8));
        grid.footer.clear();
        assert_eq!(grid.render().width, 24 + text_width("Only a title", 2));
        let ragged = Grid {
            title: "",
            column_labels: vec![],
            row_labels: vec!["a rather long row label that must wrap".into(), String::new()],
            cells: vec![vec![None, Some(Rgb8::new(4, 4, [9; 3]))], vec![]],
            captions: vec![vec![String::new(), "a caption that wraps".into()]],
            cell_width: 64,
            footer: vec![],
        };
        let img = ragged.render();
        // The label wraps to "label that must wrap" (20 chars); two columns of 64 px.
        assert_eq!(img.width, 24 + 20 * 16 + 2 * (64 + 8));
        assert!(img.data.chunks(3).any(|p| p == [9; 3]));
    }

    #[test]
    fn colour_bar_and_map() {
        let bar = colour_bar(5.0, 6, 1, "ΔE00", 200);
        let x = BAR_PAD + BAR_WIDTH / 2;
        assert_eq!(bar.get(x, BAR_TOP), viridis(1.0));
        assert_eq!(bar.get(x, BAR_TOP + 199), viridis(0.0));
        assert_ne!(bar.get(x, BAR_TOP + 200), viridis(0.0));
        assert!(bar.width >= BAR_PAD + BAR_WIDTH + text_width("5.0", 1));
        let map = colour_map(&[0.0, 2.5, 5.0, f32::NAN], 2, 2, 5.0);
        assert_eq!((map.get(0, 0), map.get(0, 1)), (viridis(0.0), viridis(1.0)));
        assert_eq!(map.get(1, 1), [255, 0, 255]);
        let flat = colour_map(&[0.0, 1.0], 2, 1, 0.0); // zero range: no division by zero
        assert_eq!((flat.get(0, 0), flat.get(1, 0)), (viridis(0.0), viridis(1.0)));
        colour_bar(0.0, 0, 0, "", 0); // degenerate inputs must not panic
    }
}
