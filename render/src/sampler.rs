//! Sample values as pure functions of (job seed, pixel, sample index, dimension): the d-th value
//! of the stream keyed by (seed, x, y, sample). A tile therefore renders bit-identically
//! whichever worker renders it, whatever the tile size or the number of threads.

use restauro_spectral::keyed_random::{KeyedRng, mix64};

/// The random stream of one sample of one pixel.
pub struct PixelSampler {
    rng: KeyedRng,
}

/// The part of a sampler's key shared by all samples of one pixel, hashed once per pixel.
#[derive(Clone, Copy, Debug)]
pub struct PixelKey(u64);

impl PixelKey {
    pub fn new(seed: u64, x: u32, y: u32) -> Self {
        // (x, y) fills one 64-bit word exactly, so two mixes key every (seed, pixel) apart.
        let pixel = (u64::from(x) << 32) | u64::from(y);
        Self(mix64(mix64(seed ^ 0x5851_f42d_4c95_7f2d) ^ pixel))
    }

    /// The position within the pixel of sample `index` of a pixel that may stop after any
    /// batch of its samples (adaptive sampling, `crate::adaptive`): the 2-D Sobol sequence
    /// (Sobol 1967; its first two dimensions form a (0, 2)-sequence in base 2), digitally shifted
    /// by a value of the pixel's own (a random XOR, which keeps the nets). Every aligned block of
    /// 2^k samples is then a (0, k, 2)-net: each of the pixel's 2^k elementary rectangles of area
    /// 2^−k, of any shape, holds exactly one sample. A pixel that stops after 8, 16 or 24 samples
    /// has sampled its area as evenly as 8, 16 or 24 strata would.
    #[inline]
    pub fn subpixel_net(self, index: u32) -> (f32, f32) {
        let shift = mix64(self.0 ^ 0x2545_f491_4f6c_dd1d);
        let (shift_x, shift_y) = (shift as u32, (shift >> 32) as u32);
        let x = index.reverse_bits() ^ shift_x;
        let y = sobol_second_dimension(index) ^ shift_y;
        // The top 24 bits: exactly representable in f32, and below 1.
        let unit = |bits: u32| (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
        (unit(x), unit(y))
    }

    /// The stream of sample `sample` of the pixel.
    #[inline]
    pub fn sampler(self, sample: u32) -> PixelSampler {
        let key = self.0 ^ u64::from(sample).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        PixelSampler { rng: KeyedRng::new(mix64(key)) }
    }
}

impl PixelSampler {
    pub fn new(seed: u64, x: u32, y: u32, sample: u32) -> Self {
        PixelKey::new(seed, x, y).sampler(sample)
    }

    /// The next dimension, uniform in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }

    /// Two dimensions at once.
    #[inline]
    pub fn next2(&mut self) -> (f32, f32) {
        (self.next_1d(), self.next_1d())
    }
}

/// The second dimension of the Sobol sequence, as 32 bits: its direction numbers are
/// v₁ = 2³¹ and v_k = v_{k−1} ⊕ (v_{k−1} ≫ 1) (primitive polynomial x + 1), and the point of
/// index i is the XOR of the v_k of i's set bits (Bratley & Fox, ACM TOMS 14, 1988).
#[inline]
fn sobol_second_dimension(mut index: u32) -> u32 {
    let (mut v, mut bits) = (1u32 << 31, 0u32);
    while index != 0 {
        if index & 1 != 0 {
            bits ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    bits
}

/// The strata of a pixel's samples: `count` cells of equal area 1/count that tile the pixel,
/// each sample jittered within its own cell, so that the samples' expected mean is the pixel's
/// centre for every count. The cells lie in r = ⌊√count⌋ rows; the first `count mod r` rows hold
/// ⌈count/r⌉ cells and the rest ⌊count/r⌋, and a row of k cells is k/count high. For a square
/// count this is the √count × √count grid.
#[derive(Clone, Copy, Debug)]
pub struct Strata {
    count: u32,
    rows: u32,
    /// Cells in each of the first `wide_rows` rows; the others have one fewer.
    wide: u32,
    wide_rows: u32,
}

impl Strata {
    pub fn new(count: u32) -> Self {
        let count = count.max(1);
        let rows = count.isqrt().max(1);
        let wide_rows = count % rows;
        let wide = count / rows + u32::from(wide_rows > 0);
        Self { count, rows, wide, wide_rows }
    }

    /// The position of sample `index` (taken modulo the count) within the pixel, jittered by
    /// (u, v) in [0, 1)².
    #[inline]
    pub fn position(&self, index: u32, u: f32, v: f32) -> (f32, f32) {
        let index = index % self.count;
        if self.wide_rows == 0 && self.wide == self.rows {
            // A square count: the grid, in the arithmetic of a plain grid.
            let cell = 1.0 / self.rows as f32;
            let (sx, sy) = (index % self.rows, index / self.rows);
            return ((sx as f32 + u) * cell, (sy as f32 + v) * cell);
        }
        let in_wide = self.wide * self.wide_rows;
        let (column, cells, before) = if index < in_wide {
            (index % self.wide, self.wide, index / self.wide * self.wide)
        } else {
            let narrow = self.wide - u32::from(self.wide_rows > 0);
            let j = index - in_wide;
            (j % narrow, narrow, in_wide + j / narrow * narrow)
        };
        let x = (column as f32 + u) / cells as f32;
        let y = (before as f32 + cells as f32 * v) / self.count as f32;
        (x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_depend_only_on_their_key() {
        // The stream of one key, drawn first on its own.
        let draw = |seed, x, y, sample| -> Vec<f32> {
            let mut s = PixelSampler::new(seed, x, y, sample);
            (0..8).map(|_| s.next_1d()).collect()
        };
        let alone = draw(1, 2, 3, 4);
        // Then drawn again after other keys, on other threads, interleaved with them and through
        // a shared per-pixel key: any state outside the key (a counter, a thread-local) shows.
        let interleaved = std::thread::scope(|scope| {
            let noise = scope.spawn(|| (0..1000).map(|i| draw(i, i as u32, 7, 0)[0]).sum::<f32>());
            let mut mine = PixelKey::new(1, 2, 3).sampler(4);
            let mut other = PixelKey::new(1, 2, 3).sampler(5);
            let values: Vec<f32> = (0..8)
                .map(|_| {
                    other.next_1d();
                    mine.next_1d()
                })
                .collect();
            std::hint::black_box(noise.join().expect("the other thread finishes"));
            values
        });
        let elsewhere = std::thread::spawn(move || draw(1, 2, 3, 4)).join().expect("joins");
        assert_eq!(alone, interleaved);
        assert_eq!(alone, elsewhere);
        // And every part of the key matters, the pixel's x and y apart.
        for (seed, x, y, sample) in [(2, 2, 3, 4), (1, 3, 2, 4), (1, 2, 4, 4), (1, 2, 3, 5)] {
            assert_ne!(draw(seed, x, y, sample), alone, "key ({seed}, {x}, {y}, {sample})");
        }
        // The dimensions of one stream are not one repeated value.
        assert!(alone.windows(2).all(|w| w[0] != w[1]), "{alone:?}");
    }

    #[test]
    fn strata_cover_the_pixel() {
        let mut cells = [0u32; 16];
        for i in 0..16 {
            let (x, y) = Strata::new(16).position(i, 0.5, 0.5);
            cells[(y * 4.0) as usize * 4 + (x * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
    }

    /// Defect 12: with the last row of a √n grid partly filled, 2 samples both lay in the upper
    /// half. For every count 1–64 the cells tile the pixel with equal areas, so the mean of the
    /// cells' centres is the pixel's centre and a fine grid of points falls in each cell equally.
    #[test]
    fn every_count_is_stratified_without_bias() {
        for n in 1..=64u32 {
            let strata = Strata::new(n);
            let (mut mx, mut my) = (0.0f64, 0.0f64);
            for i in 0..n {
                let (x, y) = strata.position(i, 0.5, 0.5);
                mx += f64::from(x);
                my += f64::from(y);
            }
            let (mx, my) = (mx / f64::from(n), my / f64::from(n));
            assert!((mx - 0.5).abs() < 1e-6 && (my - 0.5).abs() < 1e-6, "{n}: mean ({mx}, {my})");
            // Each cell's corners: (u, v) = (0, 0) and (1, 1) give its extent.
            let mut area = 0.0f64;
            let cells: Vec<_> = (0..n)
                .map(|i| {
                    let (x0, y0) = strata.position(i, 0.0, 0.0);
                    let (x1, y1) = strata.position(i, 1.0, 1.0);
                    area += f64::from(x1 - x0) * f64::from(y1 - y0);
                    assert!(
                        ((x1 - x0) * (y1 - y0) * n as f32 - 1.0).abs() < 1e-4,
                        "{n}: cell {i} is not 1/{n} of the pixel"
                    );
                    (x0, y0, x1, y1)
                })
                .collect();
            assert!((area - 1.0).abs() < 1e-5, "{n}: cells cover {area}");
            // No two cells overlap: every point of a fine grid lies in exactly one.
            for gy in 0..50 {
                for gx in 0..50 {
                    let (px, py) = ((gx as f32 + 0.5) / 50.0, (gy as f32 + 0.5) / 50.0);
                    let inside = cells
                        .iter()
                        .filter(|c| px >= c.0 && px < c.2 && py >= c.1 && py < c.3)
                        .count();
                    assert_eq!(inside, 1, "{n}: point ({px}, {py})");
                }
            }
        }
    }

    /// Every aligned block of 2^k samples of the net puts one sample in each of the 2^k
    /// elementary rectangles of every shape 2^−a × 2^−(k−a), whatever the pixel's shift.
    #[test]
    fn subpixel_net_blocks_are_nets() {
        for pixel in [PixelKey::new(1, 0, 0), PixelKey::new(7, 31, 9)] {
            for (k, start) in [(3u32, 0u32), (3, 8), (4, 16), (5, 0), (6, 64)] {
                let n = 1u32 << k;
                let points: Vec<(f32, f32)> =
                    (start..start + n).map(|i| pixel.subpixel_net(i)).collect();
                assert!(
                    points.iter().all(|&(x, y)| (0.0..1.0).contains(&x) && (0.0..1.0).contains(&y))
                );
                for a in 0..=k {
                    let (columns, rows) = (1u32 << a, 1u32 << (k - a));
                    let mut seen = vec![0u32; n as usize];
                    for &(x, y) in &points {
                        let cell = (y * rows as f32) as u32 * columns + (x * columns as f32) as u32;
                        seen[cell as usize] += 1;
                    }
                    assert!(seen.iter().all(|&c| c == 1), "k {k}, start {start}, {columns}×{rows}");
                }
            }
        }
        // Two pixels are shifted apart.
        assert_ne!(PixelKey::new(1, 0, 0).subpixel_net(0), PixelKey::new(1, 1, 0).subpixel_net(0));
    }
}
