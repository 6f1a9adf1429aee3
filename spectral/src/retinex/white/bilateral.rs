//! The noise-adaptive joint bilateral mean that averages a render's own noise out of the image
//! the paths read (see the parent module for why), and the robust noise σ it is cut by.

use rayon::prelude::*;

/// The region of a light source in a region map; a surface's region is its framework (0–7).
pub(super) const LIGHT: u8 = u8::MAX;

/// The bilateral mean's spatial σ, in pixels, and its window's half-width.
const SPATIAL_SIGMA_PX: f32 = 1.25;
const RADIUS: usize = 2;
const SIDE: usize = 2 * RADIUS + 1;
/// Neighbours within this many noise σ of the pixel (in every channel) are averaged. At 3σ the
/// rendered travertine of `render/tests/retinex_rendered.rs` lost 13° of hue to its grey
/// ground, whose S differs by 7 % (about the render's noise); at 2σ, 4°, and a flat noisy field
/// is averaged as well.
const RANGE_SIGMAS: f32 = 2.0;

/// Per pixel, what the filters need to know besides its logs: [`LIGHT`] for a light source,
/// else its framework.
pub(super) fn regions(emitter: &[bool], frameworks: &[u8]) -> Vec<u8> {
    emitter.par_iter().zip(frameworks).map(|(&e, &f)| if e { LIGHT } else { f }).collect()
}

/// The robust noise σ of one channel's logs in framework `f`: 1.4826 · median
/// |ℓ(x+1) − ℓ(x)| / √2 over horizontal pairs of its surface pixels with finite logs (Donoho &
/// Johnstone's MAD estimator).
pub(super) fn noise_sigma(logs: &[f32], regions: &[u8], width: usize, f: u8) -> f32 {
    let mut differences: Vec<f32> = (0..logs.len() / width)
        .into_par_iter()
        .flat_map_iter(|y| {
            (y * width..(y + 1) * width - 1).filter_map(move |p| {
                let d = (logs[p + 1] - logs[p]).abs();
                let same = regions[p] == f && regions[p + 1] == f;
                (same && d.is_finite()).then_some(d)
            })
        })
        .collect();
    if differences.is_empty() {
        return 0.0;
    }
    let middle = differences.len() / 2;
    let (_, m, _) = differences.select_nth_unstable_by(middle, f32::total_cmp);
    1.4826 * *m / std::f32::consts::SQRT_2
}

/// The spatial weights of the window, row by row.
fn kernel() -> [f32; SIDE * SIDE] {
    std::array::from_fn(|i| {
        let (dx, dy) = ((i % SIDE) as f32 - RADIUS as f32, (i / SIDE) as f32 - RADIUS as f32);
        (-(dx * dx + dy * dy) / (2.0 * SPATIAL_SIGMA_PX * SPATIAL_SIGMA_PX)).exp()
    })
}

/// The bilateral sums of one pixel as its window is read.
#[derive(Clone, Copy)]
struct Window<const C: usize> {
    centre: [f32; C],
    own: u8,
    cut: [f32; C],
    sum: [f32; C],
    total: f32,
}

impl<const C: usize> Window<C> {
    /// The window of a pixel that is filtered, or `None` for one that keeps its value (a light
    /// source, a log of −∞, a framework without noise).
    fn of(centre: [f32; C], own: u8, cuts: &[[f32; C]]) -> Option<Self> {
        if own == LIGHT {
            return None;
        }
        let cut = cuts[usize::from(own)];
        if centre.iter().any(|v| !v.is_finite()) || cut.contains(&0.0) {
            return None;
        }
        Some(Self { centre, own, cut, sum: [0.0; C], total: 0.0 })
    }

    /// A neighbour of logs `v` in region `r` at spatial weight `k`.
    #[inline(always)]
    fn take(&mut self, v: [f32; C], r: u8, k: f32) {
        // Every channel compared, without a branch per channel.
        let mut outside = false;
        for ((v, centre), cut) in v.iter().zip(&self.centre).zip(&self.cut) {
            outside |= (v - centre).abs() > *cut;
        }
        if r != self.own || outside {
            return;
        }
        for (sum, v) in self.sum.iter_mut().zip(v) {
            *sum += k * v;
        }
        self.total += k;
    }

    fn mean(&self) -> [f32; C] {
        self.sum.map(|s| s / self.total)
    }
}

/// One pass of the joint bilateral mean of the three channels' median logs: a neighbour is
/// taken only if it is in the pixel's own framework and within the cut in *every* channel, so
/// an edge that is strong in one channel keeps the others from mixing across it too (a
/// travertine on grey ground differs by 7 % in S but by 40 % in L). Light sources, pixels with
/// a log of −∞ and frameworks without noise keep their value.
///
/// Each pixel's window is read row by row and left to right, as it always was: the same floats
/// added in the same order give the same image. Inside the image two neighbouring pixels are
/// filtered together, so that their chains of additions, each of which waits on itself, run
/// side by side.
///
/// `C` is 3, or 1 for a grey image: each channel's sums read that channel alone, and the cut
/// compares equal channels equally, so one channel gives the grey image's three bit for bit.
pub(super) fn bilateral<const C: usize>(
    image: &[[f32; C]],
    regions: &[u8],
    (width, height): (usize, usize),
    noise: &[[f32; C]],
) -> Vec<[f32; C]> {
    let cuts: Vec<[f32; C]> = noise.iter().map(|n| n.map(|n| RANGE_SIGMAS * n)).collect();
    let kernel = kernel();
    let mut out = image.to_vec();
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let window = |x: usize| Window::of(image[y * width + x], regions[y * width + x], &cuts);
        let rows_inside = y >= RADIUS && y + RADIUS < height;
        let mut x = 0;
        while x < width {
            let pair_inside = rows_inside && x >= RADIUS && x + 1 + RADIUS < width;
            match (window(x), pair_inside.then(|| window(x + 1)).flatten()) {
                (Some(mut a), Some(mut b)) => {
                    for dy in 0..SIDE {
                        let q = (y + dy - RADIUS) * width + x - RADIUS;
                        let (values, neighbours) =
                            (&image[q..q + SIDE + 1], &regions[q..q + SIDE + 1]);
                        for dx in 0..SIDE {
                            let k = kernel[dy * SIDE + dx];
                            a.take(values[dx], neighbours[dx], k);
                            b.take(values[dx + 1], neighbours[dx + 1], k);
                        }
                    }
                    row[x] = a.mean();
                    row[x + 1] = b.mean();
                    x += 2;
                }
                (a, _) => {
                    if let Some(mut a) = a {
                        let (x0, x1) = (x.saturating_sub(RADIUS), (x + RADIUS).min(width - 1));
                        let (y0, y1) = (y.saturating_sub(RADIUS), (y + RADIUS).min(height - 1));
                        for qy in y0..=y1 {
                            for qx in x0..=x1 {
                                let k = kernel[(qy + RADIUS - y) * SIDE + qx + RADIUS - x];
                                a.take(image[qy * width + qx], regions[qy * width + qx], k);
                            }
                        }
                        row[x] = a.mean();
                    }
                    x += 1;
                }
            }
        }
    });
    out
}
