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

/// Everything a path needs to know about the image.
pub(super) struct Walker<'a> {
    /// The cleaned logs, in the tiled order of `tiling`.
    pub logs: &'a [[i16; 4]],
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
struct State {
    s: [i32; 4],
    last: [i16; 4],
    on_surface: bool,
}

impl State {
    fn new() -> Self {
        State { s: [0; 4], last: [0; 4], on_surface: false }
    }

    /// One step onto a pixel with logs `to`; `prior` is the walker's (a known white's).
    #[inline]
    fn step(&mut self, to: [i16; 4], threshold: i32, prior: Option<[i32; 3]>) {
        if to[3] == EMITTER {
            return;
        }
        if self.on_surface {
            // Four lanes so that the compiler does the three channels in one vector operation;
            // the fourth (a surface's framework) is never read.
            #[allow(clippy::needless_range_loop)] // the lanes of three arrays at once
            for c in 0..4 {
                let r = i32::from(to[c]) - i32::from(self.last[c]);
                // A select, not a branch: whether a step crosses an edge is unpredictable.
                let delta = if r.abs() > threshold { r } else { 0 };
                self.s[c] = (self.s[c] + delta).min(0);
            }
        } else if let Some(prior) = prior {
            for c in 0..3 {
                self.s[c] = (i32::from(to[c]) + prior[c]).min(0);
            }
        }
        self.last = to;
        self.on_surface = true;
    }

    /// The white found: log w = log W_last − s, per channel.
    #[inline]
    fn white(&self) -> [i32; 4] {
        std::array::from_fn(|c| i32::from(self.last[c]) - self.s[c])
    }
}

#[inline]
fn add(sums: &mut Sums, white: [i32; 4]) {
    for c in 0..4 {
        let v = if c == 3 { 1 } else { white[c].clamp(-32768, 32767) };
        sums[c] = sums[c].wrapping_add(v);
    }
}

/// `b`'s samples added to `a`'s (wrapping, so in any order).
fn merge(a: &mut Sums, b: &Sums) {
    for c in 0..4 {
        a[c] = a[c].wrapping_add(b[c]);
    }
}

pub(super) fn count(sums: &Sums) -> u32 {
    sums[3] as u32
}

impl Walker<'_> {
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
        rngs: &mut [KeyedRng; K],
        starts: [usize; K],
        steps: u32,
        from: u32,
        sums: &mut [Sums],
    ) {
        const BATCH: u32 = 32;
        let mut walks: [Walk; K] = {
            let mut rngs = rngs.iter_mut();
            std::array::from_fn(|i| {
                let rng = rngs.next().expect("one generator per path");
                Walk::new(rng, self.width, self.height, starts[i], self.turning)
            })
        };
        let mut states = [State::new(); K];
        for (state, &start) in states.iter_mut().zip(&starts) {
            state.step(self.logs[self.tiling.index_of(start)], self.threshold, self.prior);
        }
        let mut places = [[0usize; K]; BATCH as usize];
        let mut logs = [[[0i16; 4]; K]; BATCH as usize];
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
                    touched = touched.wrapping_add(sums[place][3]);
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
        let by_memory = (ACCUMULATOR_BYTES / (n * std::mem::size_of::<Sums>())).max(1);
        let tasks = rayon::current_num_threads().clamp(1, MAX_ACCUMULATOR_IMAGES).min(by_memory);
        let tasks = tasks as u64;
        let done = AtomicU64::new(0);
        const CHUNK: u64 = 256;
        let partials: Vec<Vec<Sums>> = (0..tasks)
            .into_par_iter()
            .map(|task| {
                let mut sums = vec![[0i32; 4]; n];
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
                        let mut rngs = group.map(|(rng, _)| rng);
                        self.run(&mut rngs, starts, steps, burn_in, &mut sums);
                        path += SIDE_BY_SIDE as u64;
                    } else {
                        let (rng, start) = path_rng(path);
                        self.run(&mut [rng], [start], steps, burn_in, &mut sums);
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
        let mut sums = partials.next().unwrap_or_else(|| vec![[0i32; 4]; n]);
        for partial in partials {
            sums.par_iter_mut().zip(partial.par_iter()).for_each(|(a, b)| merge(a, b));
        }
        self.tiling.row_major(&sums, pixels)
    }

    /// Phase 2: every pixel with fewer than `least` samples gets its own paths ending there,
    /// `least − count` of them. A path ending at p is walked from p outwards and read
    /// backwards (the walk is reversible), so its value at p is that of a path from the far end
    /// to p. Returns the paths and steps added.
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
        let top_ups: Vec<(usize, Sums, u64)> = short
            .par_iter()
            .map_init(
                || Vec::with_capacity(steps as usize + 1),
                |trail, &(pixel, deficit)| {
                    let mut total = [0i32; 4];
                    let mut walked = 0;
                    for j in 0..deficit {
                        let mut rng = KeyedRng::from_parts(&[seed, 2, pixel as u64, u64::from(j)]);
                        let k = burn_in + rng.below(steps - burn_in + 1);
                        // The logs along the walk, read as it goes (the reads do not wait on
                        // one another), then taken backwards.
                        trail.clear();
                        trail.push(self.logs[self.tiling.index_of(pixel)]);
                        let mut walk =
                            Walk::new(&mut rng, self.width, self.height, pixel, self.turning);
                        for _ in 0..k {
                            let (x, y) = walk.step();
                            trail.push(self.logs[self.tiling.index(x, y)]);
                        }
                        let mut state = State::new();
                        for &logs in trail.iter().rev() {
                            state.step(logs, self.threshold, self.prior);
                        }
                        if state.on_surface {
                            add(&mut total, state.white());
                        }
                        walked += u64::from(k);
                    }
                    (pixel, total, walked)
                },
            )
            .collect();
        let mut walked = 0;
        for (pixel, extra, k) in top_ups {
            merge(&mut sums[pixel], &extra);
            walked += k;
        }
        (paths, walked)
    }
}
