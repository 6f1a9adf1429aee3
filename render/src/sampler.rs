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

/// The strata of a pixel's samples: a √count × √count grid (the last row partly filled when
/// count is not a square), each sample jittered within its cell.
#[derive(Clone, Copy, Debug)]
pub struct Strata {
    side: u32,
    cell: f32,
}

impl Strata {
    pub fn new(count: u32) -> Self {
        let side = (count.max(1) as f32).sqrt().ceil().max(1.0) as u32;
        Self { side, cell: 1.0 / side as f32 }
    }

    /// The position of sample `index` within the pixel, jittered by (u, v) in [0, 1)².
    #[inline]
    pub fn position(&self, index: u32, u: f32, v: f32) -> (f32, f32) {
        let (sx, sy) = (index % self.side, (index / self.side) % self.side);
        ((sx as f32 + u) * self.cell, (sy as f32 + v) * self.cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_depend_only_on_their_key() {
        let a: Vec<f32> = {
            let mut s = PixelSampler::new(1, 2, 3, 4);
            (0..6).map(|_| s.next_1d()).collect()
        };
        let _other = PixelSampler::new(1, 2, 3, 5).next_1d();
        let mut s = PixelSampler::new(1, 2, 3, 4);
        let b: Vec<f32> = (0..6).map(|_| s.next_1d()).collect();
        assert_eq!(a, b);
        assert_ne!(PixelSampler::new(1, 3, 2, 4).next_1d(), a[0]);
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
}
