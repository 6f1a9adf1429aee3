//! Where a pixel is kept while the paths run: in 16×16 tiles, in Morton (Z) order inside each
//! tile.
//!
//! A path moves one pixel per step in any direction and reads the logs and adds to the sums
//! of every pixel it enters. In row-major order a vertical step jumps a whole row (30 KiB of
//! sums at 1920 px), so almost every step missed the caches and the TLB: at 1920×1080, 88 % of
//! the Retinex's time was spent waiting on those two accesses. In tiles, a tile of sums
//! (16 bytes a pixel) is one 4 KiB page, and a 64-byte line holds a 2×2 block of sums or a 4×2
//! block of logs, whichever way the path goes. The order is only storage: the samples are the
//! same integers, summed in any order, so the output is bit-identical.

#[cfg(test)]
use rayon::prelude::*;

const TILE_BITS: u32 = 4;
const TILE_MASK: usize = (1 << TILE_BITS) - 1;

/// A coordinate's low four bits spread to the even bit positions: 0b abcd → 0b0a0b0c0d.
const SPREAD: [u8; 16] = {
    let mut table = [0u8; 16];
    let mut v = 0;
    while v < 16 {
        table[v] = ((v & 1) | (v & 2) << 1 | (v & 4) << 2 | (v & 8) << 3) as u8;
        v += 1;
    }
    table
};

/// The tiled order of a `width` × `height` image (padded to whole tiles).
#[derive(Clone, Copy, Debug)]
pub(super) struct Tiling {
    width: usize,
    tiles_x: usize,
    len: usize,
}

impl Tiling {
    pub(super) fn new(width: usize, height: usize) -> Self {
        let tiles_x = width.div_ceil(1 << TILE_BITS);
        let tiles_y = height.div_ceil(1 << TILE_BITS);
        Self { width, tiles_x, len: (tiles_x * tiles_y) << (2 * TILE_BITS) }
    }

    /// The number of places, padding included.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// The place of pixel (x, y).
    #[inline]
    pub(super) fn index(&self, x: usize, y: usize) -> usize {
        let tile = (y >> TILE_BITS) * self.tiles_x + (x >> TILE_BITS);
        let within = SPREAD[x & TILE_MASK] | SPREAD[y & TILE_MASK] << 1;
        (tile << (2 * TILE_BITS)) | usize::from(within)
    }

    /// The place of the pixel at row-major index `p`.
    #[inline]
    pub(super) fn index_of(&self, p: usize) -> usize {
        self.index(p % self.width, p / self.width)
    }

    /// A row-major image in tiled order, the padding `fill`.
    pub(super) fn tiled<T: Copy + Send + Sync>(&self, row_major: &[T], fill: T) -> Vec<T> {
        let mut out = vec![fill; self.len];
        // Scattered once, in order: 2 M pixels take a few milliseconds.
        for (p, v) in row_major.iter().enumerate() {
            out[self.index_of(p)] = *v;
        }
        out
    }

    /// A tiled image back in row-major order (`pixels` of them).
    #[cfg(test)]
    pub(super) fn row_major<T: Copy + Send + Sync>(&self, tiled: &[T], pixels: usize) -> Vec<T> {
        (0..pixels).into_par_iter().map(|p| tiled[self.index_of(p)]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pixel_has_its_own_place_and_comes_back() {
        for (w, h) in [(1, 1), (17, 5), (40, 33), (64, 16)] {
            let tiling = Tiling::new(w, h);
            let mut seen = vec![false; tiling.len()];
            for p in 0..w * h {
                let i = tiling.index_of(p);
                assert!(!seen[i], "{w}×{h}: pixel {p} shares place {i}");
                seen[i] = true;
            }
            let image: Vec<usize> = (0..w * h).collect();
            assert_eq!(tiling.row_major(&tiling.tiled(&image, usize::MAX), w * h), image);
        }
    }

    #[test]
    fn a_cache_line_of_sums_holds_a_two_by_two_block() {
        let tiling = Tiling::new(64, 64);
        // 16-byte sums, 4 to a 64-byte line: places 4k..4k+3 are a 2×2 block.
        let block = [(6, 10), (7, 10), (6, 11), (7, 11)].map(|(x, y)| tiling.index(x, y));
        assert_eq!(block[0] % 4, 0);
        assert_eq!(block, [0, 1, 2, 3].map(|k| block[0] + k));
    }
}
