//! Random numbers that are pure functions of a key.
//!
//! restauro's images must be bit-identical however the work is split (tiles, threads, workers),
//! so no random number may depend on what was drawn before it elsewhere. Every stream is seeded
//! by hashing its key — (seed, pixel, path, …) — and then runs SplitMix64 (Steele, Lea & Flood,
//! "Fast splittable pseudorandom number generators", OOPSLA 2014), whose finaliser is a
//! bijective 64-bit mixer with full avalanche.

/// The SplitMix64 increment, 2⁶⁴/φ rounded to odd.
const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// The SplitMix64 finaliser (Stafford's "Mix13"): a bijection of u64 in which every input bit
/// affects every output bit.
#[inline]
pub const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A 64-bit key from its parts, order-sensitive: `key(&[a, b]) != key(&[b, a])` in general.
#[inline]
pub fn key(parts: &[u64]) -> u64 {
    parts.iter().fold(GOLDEN_GAMMA, |h, &p| mix64(h ^ mix64(p.wrapping_add(GOLDEN_GAMMA))))
}

/// A SplitMix64 stream started from a key.
#[derive(Clone, Debug)]
pub struct KeyedRng {
    state: u64,
}

impl KeyedRng {
    pub fn new(key: u64) -> Self {
        Self { state: key }
    }

    /// The stream of the key made of `parts`.
    pub fn from_parts(parts: &[u64]) -> Self {
        Self::new(key(parts))
    }

    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        mix64(self.state)
    }

    /// Uniform in [0, 1), with 24 random bits (every f32 the interval holds at that spacing).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [0, 1), with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in 0..n (Lemire's multiply-shift; the bias is below 2⁻³² for n < 2³²).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * u64::from(n)) >> 32) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_depend_only_on_their_key() {
        let a: Vec<u64> = {
            let mut r = KeyedRng::from_parts(&[7, 3, 9]);
            (0..5).map(|_| r.next_u64()).collect()
        };
        // Drawing from other streams in between changes nothing.
        let mut other = KeyedRng::from_parts(&[7, 3, 8]);
        let _ = other.next_u64();
        let mut r = KeyedRng::from_parts(&[7, 3, 9]);
        let b: Vec<u64> = (0..5).map(|_| r.next_u64()).collect();
        assert_eq!(a, b);
        assert_ne!(key(&[1, 2]), key(&[2, 1]));
        assert_ne!(key(&[0]), key(&[0, 0]));
    }

    #[test]
    fn uniform_draws_are_uniform() {
        // χ² over 16 bins, 160 000 draws: 15 degrees of freedom, the 99.9 % quantile is 37.7.
        let mut r = KeyedRng::new(42);
        let mut bins = [0u32; 16];
        for _ in 0..160_000 {
            bins[(r.next_f64() * 16.0) as usize] += 1;
        }
        let chi2: f64 = bins.iter().map(|&b| (f64::from(b) - 10_000.0).powi(2) / 10_000.0).sum();
        assert!(chi2 < 37.7, "{chi2} {bins:?}");
        let mut below = [0u32; 5];
        for _ in 0..50_000 {
            below[r.below(5) as usize] += 1;
        }
        assert!(below.iter().all(|&b| (9_500..10_500).contains(&b)), "{below:?}");
        for _ in 0..1000 {
            let f = r.next_f32();
            assert!((0.0..1.0).contains(&f));
        }
    }
}
