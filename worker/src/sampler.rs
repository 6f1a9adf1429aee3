//! Sample values as pure functions of (job seed, pixel, sample index, dimension): the d-th value
//! of the stream keyed by (seed, x, y, sample). A tile therefore renders bit-identically
//! whichever worker renders it, whatever the tile size or the number of threads.

use restauro_spectral::keyed_random::{KeyedRng, mix64};

/// The random stream of one sample of one pixel.
pub struct PixelSampler {
    rng: KeyedRng,
}

impl PixelSampler {
    pub fn new(seed: u64, x: u32, y: u32, sample: u32) -> Self {
        // (x, y) fills one 64-bit word exactly, so three mixes key every (seed, pixel, sample)
        // apart; this runs once per camera sample.
        let pixel = (u64::from(x) << 32) | u64::from(y);
        let key = mix64(mix64(seed ^ 0x5851_f42d_4c95_7f2d) ^ pixel)
            ^ u64::from(sample).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        Self { rng: KeyedRng::new(mix64(key)) }
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

/// The position of sample `index` of `count` within a pixel: stratified on a √count × √count
/// grid (the last row partly filled when count is not a square), jittered by (u, v).
pub fn stratified(index: u32, count: u32, u: f32, v: f32) -> (f32, f32) {
    let n = (count as f32).sqrt().ceil().max(1.0) as u32;
    let (sx, sy) = (index % n, (index / n) % n);
    ((sx as f32 + u) / n as f32, (sy as f32 + v) / n as f32)
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
            let (x, y) = stratified(i, 16, 0.5, 0.5);
            cells[(y * 4.0) as usize * 4 + (x * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
    }
}
