//! The path function and the two phases that give every pixel its samples.
//!
//! Along a path, per channel, the paper's ratio–product–reset with threshold (Marini & Rizzi
//! 2000, Eq. 1–3):
//!
//! ```text
//!   s ← min(0, s + δ·log(W_{k+1} / W_k)),   δ = 0 where |log ratio| ≤ threshold, else 1,
//! ```
//!
//! on the cleaned log image W (see `white`). At each pixel the path is in, its sample is the
//! *white* it has found there, log w = log W_here − s: the brightest area crossed, reached
//! through the chain of ratios (with smooth gradients, below the threshold, discounted). Light
//! sources are passed over: a step onto one changes nothing, and the next surface is compared
//! with the last surface before it; a path samples nothing before it has met its first surface.
//! The lightness of a pixel is then its own value relative to the geometric mean of its
//! samples' whites (in `mod.rs`).
//!
//! **Shared paths.** A path's running white at every pixel it crosses is itself a sample for a
//! path ending there, so one path serves every pixel it visits once it is past a burn-in of L/4
//! steps. Phase 1 starts enough paths at uniformly random pixels to give each pixel about 2N
//! samples; phase 2 gives every pixel still short of N its own paths ending exactly there, with
//! lengths drawn from the same L/4..L.
//!
//! **A grey image** (the seen image's Retinex runs on one relative luminance copied to three
//! channels) is walked with one channel: the three would be the same integers, so the sums are
//! too, and a pixel's logs and sums take half the memory (4 and 8 bytes instead of 8 and 16),
//! which is what the walk waits on at 1920×1080.
//!
//! **Exactness and determinism.** The whole path function runs in integers; every random
//! number is a function of (seed, phase, path); samples are summed as integers, whose addition
//! is associative. The output is bit-identical for any number of threads and any order of work.

use super::tiling::Tiling;
use super::walk::{Turning, Walk};
use super::white::EMITTER;
use crate::keyed_random::KeyedRng;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The samples of one pixel: the sums of the three channels' log whites (fixed point, each
/// clamped to ±2¹⁵) and the count. Sums wrap rather than overflow, and wrapping addition is
/// associative, so the result is the same in any order; a pixel would need 65 536 samples to
/// wrap (N ≤ 4096 gives about 2N).
pub(super) type Sums = [i32; 4];

/// The samples' accumulators of phase 1 may hold at most this many bytes together; beyond it
/// fewer tasks run in parallel (each has its own image of sums).
const ACCUMULATOR_BYTES: usize = 2 << 30;
const MAX_ACCUMULATOR_IMAGES: usize = 8;
/// Phase-1 paths walked side by side in one thread (see [`Walker::run`]): at 1920×1080 on the
/// development machine, the phase took 1.43 s with 1 path, 1.12 s with 2, 0.91 s with 4 and
/// 0.98 s with 8.
const SIDE_BY_SIDE: usize = 4;

/// Everything a path needs to know about the image. `C` is the number of lanes of a pixel's
/// logs and sums: the channels and, last, a surface's framework (or [`EMITTER`]) in the logs
/// and the count in the sums — 4 for three channels, 2 for a grey image's one.
pub(super) struct Walker<'a, const C: usize> {
    /// The cleaned logs, in the tiled order of `tiling`.
    pub logs: &'a [[i16; C]],
    pub tiling: Tiling,
    pub width: usize,
    pub height: usize,
    pub turning: Turning,
    /// The threshold in fixed point.
    pub threshold: i32,
    /// With a known white (`Anchor::Known`): the fixed-point log that makes the logs absolute
    /// (the logs are relative to the brightest cleaned value), per channel. A path then starts
    /// with s = min(0, its first surface's absolute log): its start's own lightness.
    pub prior: Option<[i32; 3]>,
}

/// The state of a path: per channel the running s, and the logs of the last surface crossed.
#[derive(Clone, Copy)]
struct State<const C: usize> {
    s: [i32; C],
    last: [i16; C],
    on_surface: bool,
}

impl<const C: usize> State<C> {
    fn new() -> Self {
        State { s: [0; C], last: [0; C], on_surface: false }
    }

    /// One step onto a pixel with logs `to`; `prior` is the walker's (a known white's).
    #[inline]
    fn step(&mut self, to: [i16; C], threshold: i32, prior: Option<[i32; 3]>) {
        if to[C - 1] == EMITTER {
            return;
        }
        if self.on_surface {
            // All lanes, so that the compiler does the channels in one vector operation; the
            // last (a surface's framework) is never read.
            #[allow(clippy::needless_range_loop)] // the lanes of three arrays at once
            for c in 0..C {
                let r = i32::from(to[c]) - i32::from(self.last[c]);
                // A select, not a branch: whether a step crosses an edge is unpredictable.
                let delta = if r.abs() > threshold { r } else { 0 };
                self.s[c] = (self.s[c] + delta).min(0);
            }
        } else if let Some(prior) = prior {
            for c in 0..C - 1 {
                self.s[c] = (i32::from(to[c]) + prior[c]).min(0);
            }
        }
        self.last = to;
        self.on_surface = true;
    }

    /// The white found: log w = log W_last − s, per channel.
    #[inline]
    fn white(&self) -> [i32; C] {
        std::array::from_fn(|c| i32::from(self.last[c]) - self.s[c])
    }
}

/// A sample added to a pixel's sums: each channel's white, clamped, and one to the count.
#[inline]
fn add<const C: usize>(sums: &mut [i32; C], white: [i32; C]) {
    for c in 0..C {
        let v = if c == C - 1 { 1 } else { white[c].clamp(-32768, 32767) };
        sums[c] = sums[c].wrapping_add(v);
    }
}

/// `b`'s samples added to `a`'s (wrapping, so in any order).
fn merge<const C: usize>(a: &mut [i32; C], b: &[i32; C]) {
    for c in 0..C {
        a[c] = a[c].wrapping_add(b[c]);
    }
}

pub(super) fn count(sums: &Sums) -> u32 {
    sums[3] as u32
}

/// A pixel's sums with all of its channels: a grey image's one channel copied to the three.
fn full<const C: usize>(sums: &[i32; C]) -> Sums {
    std::array::from_fn(|c| if c == 3 { sums[C - 1] } else { sums[c.min(C - 2)] })
}

/// The value at its start of a path read backwards, from the far end to the start: what the
/// path function gives after walking the surfaces `y_m, …, y_1, y_0` (the order in which they
/// are met walking *out* from the start is y_0, y_1, …), folded in the order they are met.
///
/// The path function s ← min(0, s + d) from s₀ at y_m ends at
/// s = min(0, D_1, …, D_{m−1}, D_m + s₀), with D_j the sum of the first j steps' d taken
/// outwards (d for the step from y_{i+1} to y_i is the thresholded y_i − y_{i+1}): Lindley's
/// recursion unrolled. So one pass outwards keeps D and the least of the earlier D, and no
/// trail of the walk is stored. D is held in 64 bits; s₀ needs the last surface, known at the
/// end.
struct Backwards<const C: usize> {
    nearest: [i16; C],
    farthest: [i16; C],
    sum: [i64; C],
    least: [i64; C],
    surfaces: bool,
}

impl<const C: usize> Backwards<C> {
    fn new() -> Self {
        Backwards { nearest: [0; C], farthest: [0; C], sum: [0; C], least: [0; C], surfaces: false }
    }

    #[inline]
    fn step(&mut self, to: [i16; C], threshold: i32) {
        if to[C - 1] == EMITTER {
            return;
        }
        if self.surfaces {
            #[allow(clippy::needless_range_loop)] // the lanes of four arrays at once
            for c in 0..C {
                self.least[c] = self.least[c].min(self.sum[c]);
                let r = i32::from(self.farthest[c]) - i32::from(to[c]);
                let delta = if r.abs() > threshold { r } else { 0 };
                self.sum[c] += i64::from(delta);
            }
        } else {
            self.nearest = to;
            self.surfaces = true;
        }
        self.farthest = to;
    }

    /// The white found at the start, if the path met a surface.
    fn white(&self, prior: Option<[i32; 3]>) -> Option<[i32; C]> {
        self.surfaces.then(|| {
            std::array::from_fn(|c| {
                let start = match prior {
                    Some(prior) if c < C - 1 => {
                        (i32::from(self.farthest[c]) + prior[c]).min(0).into()
                    }
                    _ => 0,
                };
                let s = self.least[c].min(self.sum[c] + start);
                (i64::from(self.nearest[c]) - s) as i32
            })
        })
    }
}

impl<const C: usize> Walker<'_, C> {
    /// Walks K paths of `steps` steps each from pixels `starts` (row-major), side by side, and
    /// adds the white each has found to `sums` (tiled) after each step k = `from`..=steps at
    /// which it has met a surface.
    ///
    /// In batches: where a walk goes does not depend on what it reads, so the places of a batch
    /// of steps are found first and their logs and sums read together, and the cache misses of
    /// a batch overlap instead of waiting one after another. Several paths at once, because the
    /// steps of one path wait on one another and those of two do not.
    #[inline]
    fn run<const K: usize>(
        &self,
        rngs: [KeyedRng; K],
        starts: [usize; K],
        steps: u32,
        from: u32,
        sums: &mut [[i32; C]],
    ) {
        const BATCH: u32 = 32;
        let mut rngs = rngs.into_iter();
        let mut walks: [Walk; K] = std::array::from_fn(|i| {
            let rng = rngs.next().expect("one generator per path");
            Walk::new(rng, self.width, self.height, starts[i], self.turning)
        });
        let mut states = [State::<C>::new(); K];
        for (state, &start) in states.iter_mut().zip(&starts) {
            state.step(self.logs[self.tiling.index_of(start)], self.threshold, self.prior);
        }
        let mut places = [[0usize; K]; BATCH as usize];
        let mut logs = [[[0i16; C]; K]; BATCH as usize];
        let mut k = 1;
        while k <= steps {
            let batch = BATCH.min(steps - k + 1) as usize;
            for step in &mut places[..batch] {
                for (place, walk) in step.iter_mut().zip(&mut walks) {
                    let (x, y) = walk.step();
                    *place = self.tiling.index(x, y);
                }
            }
            let mut touched = 0i32;
            for (l, step) in logs.iter_mut().zip(&places[..batch]) {
                for (l, &place) in l.iter_mut().zip(step) {
                    *l = self.logs[place];
                    touched = touched.wrapping_add(sums[place][C - 1]);
                }
            }
            // The sums were read only to bring them into the cache.
            std::hint::black_box(touched);
            for (step, l) in places[..batch].iter().zip(&logs) {
                for ((state, &place), &l) in states.iter_mut().zip(step).zip(l) {
                    state.step(l, self.threshold, self.prior);
                    if k >= from && state.on_surface {
                        add(&mut sums[place], state.white());
                    }
                }
                k += 1;
            }
        }
    }

    /// Phase 1: `paths` shared paths of `steps` steps from uniformly random starts, split into
    /// contiguous ranges, one accumulator image each (tiled), summed at the end. Returns the
    /// sums in row-major order.
    pub(super) fn shared(
        &self,
        seed: u64,
        paths: u64,
        steps: u32,
        burn_in: u32,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Vec<Sums> {
        let n = self.tiling.len();
        let pixels = self.width * self.height;
        let by_memory = (ACCUMULATOR_BYTES / (n * std::mem::size_of::<[i32; C]>())).max(1);
        let tasks = rayon::current_num_threads().clamp(1, MAX_ACCUMULATOR_IMAGES).min(by_memory);
        let tasks = tasks as u64;
        let done = AtomicU64::new(0);
        const CHUNK: u64 = 256;
        let partials: Vec<Vec<[i32; C]>> = (0..tasks)
            .into_par_iter()
            .map(|task| {
                let mut sums = vec![[0i32; C]; n];
                let (first, end) = (paths * task / tasks, paths * (task + 1) / tasks);
                // Each path's generator is its own: its start, then its walk.
                let path_rng = |path: u64| {
                    let mut rng = KeyedRng::from_parts(&[seed, 1, path]);
                    let start = rng.below(pixels as u32) as usize;
                    (rng, start)
                };
                let (mut path, mut reported) = (first, first);
                while path < end {
                    if end - path >= SIDE_BY_SIDE as u64 {
                        let group: [(KeyedRng, usize); SIDE_BY_SIDE] =
                            std::array::from_fn(|i| path_rng(path + i as u64));
                        let starts = group.each_ref().map(|(_, start)| *start);
                        let rngs = group.map(|(rng, _)| rng);
                        self.run(rngs, starts, steps, burn_in, &mut sums);
                        path += SIDE_BY_SIDE as u64;
                    } else {
                        let (rng, start) = path_rng(path);
                        self.run([rng], [start], steps, burn_in, &mut sums);
                        path += 1;
                    }
                    if path - reported >= CHUNK || path == end {
                        let step = path - reported;
                        reported = path;
                        progress(done.fetch_add(step, Ordering::Relaxed) + step, paths);
                    }
                }
                sums
            })
            .collect();
        let mut partials = partials.into_iter();
        let mut sums = partials.next().unwrap_or_else(|| vec![[0i32; C]; n]);
        for partial in partials {
            sums.par_iter_mut().zip(partial.par_iter()).for_each(|(a, b)| merge(a, b));
        }
        (0..pixels).into_par_iter().map(|p| full(&sums[self.tiling.index_of(p)])).collect()
    }

    /// Phase 2: every pixel with fewer than `least` samples gets its own paths ending there,
    /// `least − count` of them. A path ending at p is walked from p outwards and read
    /// backwards (the walk is reversible), so its value at p is that of a path from the far end
    /// to p (see [`Backwards`]). Returns the paths and steps added.
    pub(super) fn top_up(
        &self,
        sums: &mut [Sums],
        seed: u64,
        least: u32,
        steps: u32,
        burn_in: u32,
    ) -> (u64, u64) {
        let short: Vec<(usize, u32)> = sums
            .par_iter()
            .enumerate()
            .filter_map(|(p, s)| (count(s) < least).then(|| (p, least - count(s))))
            .collect();
        let paths: u64 = short.iter().map(|&(_, d)| u64::from(d)).sum();
        let top_ups: Vec<(usize, [i32; C], u64)> = short
            .par_iter()
            .map(|&(pixel, deficit)| {
                let mut total = [0i32; C];
                let mut walked = 0;
                for j in 0..deficit {
                    let mut rng = KeyedRng::from_parts(&[seed, 2, pixel as u64, u64::from(j)]);
                    let k = burn_in + rng.below(steps - burn_in + 1);
                    let mut backwards = Backwards::new();
                    backwards.step(self.logs[self.tiling.index_of(pixel)], self.threshold);
                    let mut walk = Walk::new(rng, self.width, self.height, pixel, self.turning);
                    for _ in 0..k {
                        let (x, y) = walk.step();
                        backwards.step(self.logs[self.tiling.index(x, y)], self.threshold);
                    }
                    if let Some(white) = backwards.white(self.prior) {
                        add(&mut total, white);
                    }
                    walked += u64::from(k);
                }
                (pixel, total, walked)
            })
            .collect();
        let mut walked = 0;
        for (pixel, extra, k) in top_ups {
            merge(&mut sums[pixel], &full(&extra));
            walked += k;
        }
        (paths, walked)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Logs of random surfaces and light sources, with steps above and below the threshold.
    fn trail(rng: &mut KeyedRng, len: usize) -> Vec<[i16; 4]> {
        (0..len)
            .map(|_| {
                if rng.below(6) == 0 {
                    [0, 0, 0, EMITTER]
                } else {
                    std::array::from_fn(|c| if c == 3 { 0 } else { -(rng.below(300) as i16) })
                }
            })
            .collect()
    }

    /// Folding a walk outwards gives, to the last bit, what the path function gives walking
    /// it backwards, from its far end to its start: with and without a known white, with
    /// light sources anywhere (the start among them) and with none of the trail a surface.
    #[test]
    fn the_outward_fold_is_the_path_function_walked_backwards() {
        let mut rng = KeyedRng::new(11);
        for case in 0..3000 {
            let trail = trail(&mut rng, 1 + case % 40);
            let prior = (case % 2 == 0).then_some([-20, 35, 0]);
            let threshold = (case % 3) as i32 * 40;
            let mut state = State::<4>::new();
            for &to in trail.iter().rev() {
                state.step(to, threshold, prior);
            }
            let mut fold = Backwards::<4>::new();
            for &to in &trail {
                fold.step(to, threshold);
            }
            let expect = state.on_surface.then(|| state.white());
            let got = fold.white(prior);
            assert_eq!(got.map(|w| [w[0], w[1], w[2]]), expect.map(|w| [w[0], w[1], w[2]]));
        }
    }

    /// A grey image walked with its one channel gives the sums that its three equal channels
    /// give walked as such.
    #[test]
    fn a_grey_image_walked_in_one_channel_gives_the_same_sums() {
        let (width, height) = (37, 23);
        let mut rng = KeyedRng::new(5);
        let logs: Vec<[i16; 4]> = (0..width * height)
            .map(|_| {
                let v = -(rng.below(2000) as i16);
                if rng.below(10) == 0 { [0, 0, 0, EMITTER] } else { [v, v, v, 0] }
            })
            .collect();
        let tiling = Tiling::new(width, height);
        let grey: Vec<[i16; 2]> = logs.iter().map(|l| [l[0], l[3]]).collect();
        let (four, two) = (tiling.tiled(&logs, [0; 4]), tiling.tiled(&grey, [0; 2]));
        for prior in [None, Some([-300; 3])] {
            let turning = Turning::with_persistence(6.0);
            let a =
                Walker { logs: &four[..], tiling, width, height, turning, threshold: 10, prior };
            let b = Walker { logs: &two[..], tiling, width, height, turning, threshold: 10, prior };
            let mut sums_a = a.shared(3, 9, 400, 100, &|_, _| {});
            let mut sums_b = b.shared(3, 9, 400, 100, &|_, _| {});
            assert_eq!(sums_a, sums_b);
            assert_eq!(
                a.top_up(&mut sums_a, 3, 30, 400, 100),
                b.top_up(&mut sums_b, 3, 30, 400, 100)
            );
            assert_eq!(sums_a, sums_b);
        }
    }
}
