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

/// One pass of the joint bilateral mean of the three channels' median logs: a neighbour is
/// taken only if it is in the pixel's own framework and within the cut in *every* channel, so
/// an edge that is strong in one channel keeps the others from mixing across it too (a
/// travertine on grey ground differs by 7 % in S but by 40 % in L). Light sources, pixels with
/// a log of −∞ and frameworks without noise keep their value.
pub(super) fn bilateral(
    image: &[[f32; 3]],
    regions: &[u8],
    (width, height): (usize, usize),
    noise: &[[f32; 3]],
) -> Vec<[f32; 3]> {
    let cuts: Vec<[f32; 3]> = noise.iter().map(|n| n.map(|n| RANGE_SIGMAS * n)).collect();
    let kernel = kernel();
    let mut out = vec![[0f32; 3]; image.len()];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, pixel) in row.iter_mut().enumerate() {
            let p = y * width + x;
            let (centre, own) = (image[p], regions[p]);
            *pixel = centre;
            if own == LIGHT {
                continue;
            }
            let cut = cuts[usize::from(own)];
            if centre.iter().any(|v| !v.is_finite()) || cut.contains(&0.0) {
                continue;
            }
            let (x0, x1) = (x.saturating_sub(RADIUS), (x + RADIUS).min(width - 1));
            let (y0, y1) = (y.saturating_sub(RADIUS), (y + RADIUS).min(height - 1));
            let (mut sum, mut total) = ([0.0f32; 3], 0.0f32);
            // Row by row and left to right, as the sum was always taken: the same floats in
            // the same order give the same image.
            for qy in y0..=y1 {
                let weights = &kernel[(qy + RADIUS - y) * SIDE..][..SIDE];
                let values = &image[qy * width..][x0..=x1];
                let neighbours = &regions[qy * width..][x0..=x1];
                for (i, (v, &r)) in values.iter().zip(neighbours).enumerate() {
                    let outside = (v[0] - centre[0]).abs() > cut[0]
                        || (v[1] - centre[1]).abs() > cut[1]
                        || (v[2] - centre[2]).abs() > cut[2];
                    if r != own || outside {
                        continue;
                    }
                    let k = weights[x0 + i + RADIUS - x];
                    for c in 0..3 {
                        sum[c] += k * v[c];
                    }
                    total += k;
                }
            }
            *pixel = sum.map(|s| s / total);
        }
    });
    out
}
