//! The rank filters that keep a lone bright pixel from being the white: the 3×3 median and the
//! 2×2 opening, of one channel's logs, with light sources left out.
//!
//! Where a pixel's whole 3×3 window is surface (inside the image, no light source), its median
//! is taken by a sorting network of 19 compare–exchanges (Paeth, "Median finding on a 3×3
//! grid", Graphics Gems, 1990), without branches; elsewhere (at the border or beside a light
//! source, where the window holds fewer values) by sorting what it holds. Both give the same
//! value: the network's middle element is the sorted window's.

use rayon::prelude::*;

/// Orders a pair, low first. With no NaN among the values, a compare and two selects (the
/// processor's min and max).
#[inline(always)]
fn order(p: &mut [f32; 9], a: usize, b: usize) {
    let (x, y) = (p[a], p[b]);
    p[a] = if y < x { y } else { x };
    p[b] = if y < x { x } else { y };
}

/// The median of nine values by Paeth's network, written out so that it stays in registers.
#[inline]
fn median_of_9(mut p: [f32; 9]) -> f32 {
    order(&mut p, 1, 2);
    order(&mut p, 4, 5);
    order(&mut p, 7, 8);
    order(&mut p, 0, 1);
    order(&mut p, 3, 4);
    order(&mut p, 6, 7);
    order(&mut p, 1, 2);
    order(&mut p, 4, 5);
    order(&mut p, 7, 8);
    order(&mut p, 0, 3);
    order(&mut p, 5, 8);
    order(&mut p, 4, 7);
    order(&mut p, 3, 6);
    order(&mut p, 1, 4);
    order(&mut p, 2, 5);
    order(&mut p, 4, 7);
    order(&mut p, 4, 2);
    order(&mut p, 6, 4);
    order(&mut p, 4, 2);
    p[4]
}

/// The median of a window of any size, by sorting: for an even count (at a border or beside a
/// light source) the lower middle, so that the median is always one of the values.
fn median_of(window: &mut [f32]) -> f32 {
    window.sort_unstable_by(f32::total_cmp);
    window[(window.len() - 1) / 2]
}

/// `filter(x, y)` for every pixel, row by row in parallel (no division per pixel).
fn per_pixel(width: usize, height: usize, filter: impl Fn(usize, usize) -> f32 + Sync) -> Vec<f32> {
    let mut out = vec![0f32; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            *v = filter(x, y);
        }
    });
    out
}

/// The 3×3 median of one channel's logs over surface pixels (light sources left out; a light
/// source keeps its own value). `logs` holds no NaN (they are logs of finite values ≥ 0).
pub(super) fn median(logs: &[f32], emitter: &[bool], width: usize, height: usize) -> Vec<f32> {
    per_pixel(width, height, |x, y| {
        let p = y * width + x;
        if emitter[p] {
            return logs[p];
        }
        if x >= 1 && y >= 1 && x + 1 < width && y + 1 < height {
            let window: [usize; 9] =
                std::array::from_fn(|i| p + i % 3 + (i / 3) * width - width - 1);
            if window.iter().all(|&q| !emitter[q]) {
                return median_of_9(window.map(|q| logs[q]));
            }
        }
        let mut window = [0f32; 9];
        let mut n = 0;
        for qy in y.saturating_sub(1)..=(y + 1).min(height - 1) {
            for qx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                let q = qy * width + qx;
                if !emitter[q] {
                    window[n] = logs[q];
                    n += 1;
                }
            }
        }
        median_of(&mut window[..n])
    })
}

/// The 2×2 opening of one channel's logs (each pixel: the largest, over the 2×2 blocks inside
/// the image that hold it, of the block's smallest surface value). An area that is a union of
/// 2×2 blocks keeps every pixel, its corners included, which the 3×3 median would cut off.
pub(super) fn opening(logs: &[f32], emitter: &[bool], width: usize, height: usize) -> Vec<f32> {
    if width < 2 || height < 2 {
        return vec![f32::NEG_INFINITY; width * height];
    }
    // The smallest surface value of each 2×2 block, the block at (bx, by) covering
    // bx..=bx+1 × by..=by+1 (+∞ for a block of light sources only).
    let (bw, bh) = (width - 1, height - 1);
    let mut blocks = vec![f32::INFINITY; bw * bh];
    blocks.par_chunks_mut(bw).enumerate().for_each(|(by, row)| {
        for (bx, m) in row.iter_mut().enumerate() {
            for q in [by * width + bx, by * width + bx + 1, (by + 1) * width + bx] {
                if !emitter[q] {
                    *m = m.min(logs[q]);
                }
            }
            let q = (by + 1) * width + bx + 1;
            if !emitter[q] {
                *m = m.min(logs[q]);
            }
        }
    });
    per_pixel(width, height, |x, y| {
        let mut best = f32::NEG_INFINITY;
        for by in y.saturating_sub(1)..=y.min(bh - 1) {
            for bx in x.saturating_sub(1)..=x.min(bw - 1) {
                let m = blocks[by * bw + bx];
                if m < f32::INFINITY {
                    best = best.max(m);
                }
            }
        }
        best
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keyed_random::KeyedRng;

    /// The network's median is the sorted window's middle, for random windows with ties and
    /// −∞ (a black pixel's log) among the values.
    #[test]
    fn the_network_finds_the_middle_of_nine() {
        let mut rng = KeyedRng::new(9);
        for _ in 0..100_000 {
            let window: [f32; 9] = std::array::from_fn(|_| match rng.below(12) {
                0 => f32::NEG_INFINITY,
                v => (v as f32 - 6.0) * 0.5 + if rng.below(2) == 0 { rng.next_f32() } else { 0.0 },
            });
            let mut sorted = window;
            assert_eq!(median_of_9(window), median_of(&mut sorted), "{window:?}");
        }
    }

    /// Both filters against their definitions, written plainly, on random images with light
    /// sources, black pixels and ties, of sizes down to one pixel wide.
    #[test]
    fn the_filters_match_their_definitions() {
        let mut rng = KeyedRng::new(4);
        for (w, h) in [(1, 1), (1, 7), (6, 1), (2, 2), (9, 5), (23, 17)] {
            let logs: Vec<f32> = (0..w * h)
                .map(|_| match rng.below(8) {
                    0 => f32::NEG_INFINITY,
                    v => v as f32 * 0.25,
                })
                .collect();
            let emitter: Vec<bool> = (0..w * h).map(|_| rng.below(5) == 0).collect();
            let (median, opening) = (median(&logs, &emitter, w, h), opening(&logs, &emitter, w, h));
            for p in 0..w * h {
                let (x, y) = ((p % w) as i64, (p / w) as i64);
                let inside =
                    |qx: i64, qy: i64| qx >= 0 && qy >= 0 && qx < w as i64 && qy < h as i64;
                let at = |qx: i64, qy: i64| (qy * w as i64 + qx) as usize;
                let mut window: Vec<f32> = (-1..=1)
                    .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                    .filter(|&(qx, qy)| inside(qx, qy) && !emitter[at(qx, qy)])
                    .map(|(qx, qy)| logs[at(qx, qy)])
                    .collect();
                let expect = if emitter[p] { logs[p] } else { median_of(&mut window) };
                assert_eq!(median[p], expect, "median {w}×{h} at {p}");
                let mut best = f32::NEG_INFINITY;
                for (bx, by) in [(x - 1, y - 1), (x, y - 1), (x - 1, y), (x, y)] {
                    let block = [(bx, by), (bx + 1, by), (bx, by + 1), (bx + 1, by + 1)];
                    if !block.iter().all(|&(qx, qy)| inside(qx, qy)) {
                        continue;
                    }
                    let surface = block.iter().map(|&(qx, qy)| at(qx, qy)).filter(|&q| !emitter[q]);
                    if let Some(m) = surface.map(|q| logs[q]).reduce(f32::min) {
                        best = best.max(m);
                    }
                }
                assert_eq!(opening[p], best, "opening {w}×{h} at {p}");
            }
        }
    }

    #[test]
    fn a_window_beside_a_light_source_leaves_it_out() {
        // 3×3, the centre's neighbours 1..8 and a light source of 100 at the top left.
        let logs = [100.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let mut emitter = [false; 9];
        emitter[0] = true;
        // Eight values 1..8: the lower middle, 4.
        assert_eq!(median(&logs, &emitter, 3, 3)[4], 4.0);
        // Without the light source, nine values: 5.
        assert_eq!(median(&logs, &[false; 9], 3, 3)[4], 5.0);
    }
}
