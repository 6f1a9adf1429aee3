//! The path of the Retinex: an isotropic, persistent random walk over the image plane.
//!
//! Marini & Rizzi (2000) take Brownian paths: random in shape and with no preferred direction.
//! A walk on the pixel lattice (one step to one of the 8 neighbours, turning by 45°) is not
//! that: its straight stretches run along four lines only, and because one path serves every
//! pixel it crosses, its errors are laid down along those lines — the cross-hatch of straight
//! diagonal and axial lines the old filter drew over every flat area.
//!
//! This walk moves in the continuous plane instead: the position is held in fixed point
//! (1/4096 px), each step is one pixel long in a direction of 4096 possible angles, and the
//! direction diffuses — at each step it turns by an angle uniform in [−a, a]. The angular
//! variance per step a²/3 sets the persistence length ℓ_p = 2 / (a²/3) steps (the directions of
//! steps k apart correlate as e^(−k/ℓ_p)); on scales beyond ℓ_p the walk is Brownian motion,
//! and on every scale its law is the same for any direction. At the image border the walk is
//! reflected as in a mirror on the border's outer edge (position and direction), which is the
//! walk on the unfolded plane folded back, so every pixel is visited equally often.

use crate::keyed_random::KeyedRng;
use std::sync::OnceLock;

/// Fixed-point fraction bits of a position: 1/4096 px.
const FRACTION_BITS: u32 = 12;
const ONE: i32 = 1 << FRACTION_BITS;
/// Directions per turn.
const ANGLES: u32 = 4096;
const HALF_TURN: u32 = ANGLES / 2;

/// The unit step of each angle, in fixed point (|component| ≤ 4096: an `i16` holds it, and
/// the table is 16 KiB, half the L1 data cache, which the image's reads share).
type Directions = [[i16; 2]; ANGLES as usize];

fn directions() -> &'static Directions {
    static TABLE: OnceLock<Directions> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|a| {
            let theta = std::f64::consts::TAU * a as f64 / f64::from(ANGLES);
            let one = f64::from(ONE);
            [(theta.cos() * one).round() as i16, (theta.sin() * one).round() as i16]
        })
    })
}

/// How far a walk turns per step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Turning {
    /// The half-width a of the uniform turn, in angle units.
    half_width: u32,
}

impl Turning {
    /// The turning of a walk whose persistence length is `steps` (≥ 1).
    pub(super) fn with_persistence(steps: f64) -> Self {
        // ℓ_p = 2 / σ², σ² = a²/3 (a in radians) → a = √(6 / ℓ_p).
        let a = (6.0 / steps.max(1.0)).sqrt();
        let units = (a * f64::from(ANGLES) / std::f64::consts::TAU).round();
        Self { half_width: units.clamp(0.0, f64::from(HALF_TURN)) as u32 }
    }
}

/// The expected squared distance from the start after `k` steps of a walk of persistence `l`
/// (the worm-like chain in 2D): 2ℓk − 2ℓ²(1 − e^(−k/ℓ)).
pub(super) fn mean_square_distance(k: f64, l: f64) -> f64 {
    2.0 * l * k - 2.0 * l * l * (1.0 - (-k / l).exp())
}

/// A walker on an image of `width` × `height` pixels; it owns its generator, so that its
/// whole state can stay in registers.
pub(super) struct Walk {
    x: i32,
    y: i32,
    x_end: i32,
    y_end: i32,
    angle: u32,
    span: u32,
    half_width: i32,
    directions: &'static Directions,
    rng: KeyedRng,
    bits: u64,
    bits_left: u32,
}

impl Walk {
    /// A walk from a uniformly random point of pixel `start`, in a uniformly random direction.
    pub(super) fn new(
        mut rng: KeyedRng,
        width: usize,
        height: usize,
        start: usize,
        turning: Turning,
    ) -> Self {
        let draw = rng.next_u64();
        let (fx, fy) = ((draw & 0xfff) as i32, ((draw >> 12) & 0xfff) as i32);
        let angle = ((draw >> 24) & u64::from(ANGLES - 1)) as u32;
        Walk {
            x: ((start % width) as i32 * ONE) | fx,
            y: ((start / width) as i32 * ONE) | fy,
            x_end: width as i32 * ONE,
            y_end: height as i32 * ONE,
            angle,
            span: 2 * turning.half_width + 1,
            half_width: turning.half_width as i32,
            directions: directions(),
            rng,
            bits: 0,
            bits_left: 0,
        }
    }

    #[inline]
    fn draw16(&mut self) -> u32 {
        if self.bits_left == 0 {
            self.bits = self.rng.next_u64();
            self.bits_left = 4;
        }
        self.bits_left -= 1;
        let v = (self.bits & 0xffff) as u32;
        self.bits >>= 16;
        v
    }

    /// One step; returns the pixel (x, y) the walk is in afterwards (often the same one: a
    /// step is one pixel long in any direction).
    #[inline]
    pub(super) fn step(&mut self) -> (usize, usize) {
        let turn = ((self.draw16() * self.span) >> 16) as i32 - self.half_width;
        self.angle = (self.angle as i32 + turn) as u32 & (ANGLES - 1);
        let [dx, dy] = self.directions[self.angle as usize];
        self.x += i32::from(dx);
        self.y += i32::from(dy);
        // A mirror on the outer edge of the border: x → −x (−1 in fixed point keeps the
        // position inside) and the direction's x component flips (θ → π − θ).
        if self.x < 0 {
            self.x = -self.x - 1;
            self.angle = (HALF_TURN.wrapping_sub(self.angle)) & (ANGLES - 1);
        } else if self.x >= self.x_end {
            self.x = 2 * self.x_end - self.x - 1;
            self.angle = (HALF_TURN.wrapping_sub(self.angle)) & (ANGLES - 1);
        }
        if self.y < 0 {
            self.y = -self.y - 1;
            self.angle = (ANGLES - self.angle) & (ANGLES - 1);
        } else if self.y >= self.y_end {
            self.y = 2 * self.y_end - self.y - 1;
            self.angle = (ANGLES - self.angle) & (ANGLES - 1);
        }
        ((self.x >> FRACTION_BITS) as usize, (self.y >> FRACTION_BITS) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk's spread from its start is the same along the axes and along the diagonals,
    /// and its mean squared distance is the worm-like chain's: no preferred direction, the
    /// persistence it was given.
    #[test]
    fn the_walk_is_isotropic_with_the_persistence_it_was_given() {
        let (w, h) = (4001, 4001);
        let persistence = 20.0;
        let turning = Turning::with_persistence(persistence);
        let k = 200;
        let (mut axis, mut diagonal, mut msd) = (0.0, 0.0, 0.0);
        let paths = 20_000;
        for i in 0..paths {
            let rng = KeyedRng::from_parts(&[5, i]);
            let start = (h / 2) * w + w / 2;
            let mut walk = Walk::new(rng, w, h, start, turning);
            let mut p = (w / 2, h / 2);
            for _ in 0..k {
                p = walk.step();
            }
            let dx = p.0 as f64 - (w / 2) as f64;
            let dy = p.1 as f64 - (h / 2) as f64;
            axis += dx * dx - dy * dy;
            diagonal += 2.0 * dx * dy;
            msd += dx * dx + dy * dy;
        }
        let n = paths as f64;
        let (axis, diagonal, msd) = (axis / n, diagonal / n, msd / n);
        let expect = mean_square_distance(k as f64, persistence);
        // The anisotropy along the axes (⟨dx² − dy²⟩) and the diagonals (⟨2 dx dy⟩) is zero
        // within sampling error (a few % of ⟨r²⟩ for 20 000 paths).
        assert!(axis.abs() < 0.03 * msd, "axes: {axis} of {msd}");
        assert!(diagonal.abs() < 0.03 * msd, "diagonals: {diagonal} of {msd}");
        assert!((msd / expect - 1.0).abs() < 0.05, "⟨r²⟩ {msd}, worm-like chain {expect}");
    }

    #[test]
    fn the_walk_stays_in_the_image_and_reaches_its_corners() {
        let (w, h) = (7, 3);
        let mut walk = Walk::new(KeyedRng::new(1), w, h, 10, Turning::with_persistence(5.0));
        let mut seen = vec![0u32; w * h];
        for _ in 0..200_000 {
            let (x, y) = walk.step();
            seen[y * w + x] += 1;
        }
        // Every pixel, the corners included, is visited about equally often.
        let mean = 200_000.0 / (w * h) as f64;
        for (p, &c) in seen.iter().enumerate() {
            assert!((f64::from(c) / mean - 1.0).abs() < 0.1, "pixel {p}: {c} of {mean}");
        }
    }
}
