//! Frameworks told apart only where their light jumps.
//!
//! The renderer's `lit_by` mask says which lights light a pixel (a light counts where it gives
//! a tenth of the direct light). At the edge of a sun's shadow the light jumps, and the eye sees
//! two frameworks of illumination. Where two floodlights overlap, or a beam fades out over a
//! metre, the mask changes too, but the light does not jump: it changes gradually, and the eye
//! takes a gradual change of light for light, not for an edge between two regions (Land &
//! McCann 1971: gradients below a threshold are discounted). Adapting each side to its own
//! light there drew a hard edge across a floodlit facade where none is.
//!
//! So adjacent frameworks are merged where the adapting white is continuous across their edge:
//! over all pairs of pixels three apart across it (each inside its framework's area), the median
//! ratio of their whites' luminances is below [`JUMP`]. A shadow's edge (a ratio of 3 to 10 in
//! sun and sky) keeps its frameworks apart; the edge where a second flood's share passes a tenth
//! (a ratio of 1.1) does not.

use crate::retinex::Frameworks;
use std::collections::HashMap;

/// The least ratio of light across an edge that makes it an edge between frameworks.
pub const JUMP: f64 = 1.5;
/// Pixels this far apart across an edge are compared (the one between may be in the penumbra).
const PAIR_DISTANCE_PX: usize = 3;
/// The fewest pairs of pixels that tell whether an edge is a jump.
const LEAST_PAIRS: usize = 16;

/// `frameworks`, with those whose light is continuous across their common edge merged (the
/// largest first again). `white_y` is each pixel's adapting white luminance.
pub(super) fn merge_continuous(
    frameworks: Frameworks,
    white_y: &[f32],
    width: usize,
) -> Frameworks {
    if frameworks.count < 2 {
        return frameworks;
    }
    let n = white_y.len();
    let mut across: HashMap<(u8, u8), Vec<f64>> = HashMap::new();
    let d = PAIR_DISTANCE_PX;
    for a in (0..n).filter(|&a| frameworks.solid[a] && white_y[a] > 0.0) {
        let right = (a % width + d < width).then(|| a + d);
        let below = (a + d * width < n).then(|| a + d * width);
        for b in [right, below].into_iter().flatten() {
            let (f, g) = (frameworks.labels[a], frameworks.labels[b]);
            if f != g && frameworks.solid[b] && white_y[b] > 0.0 {
                let ratio = (f64::from(white_y[a]) / f64::from(white_y[b])).ln().abs();
                across.entry((f.min(g), f.max(g))).or_default().push(ratio);
            }
        }
    }
    // Union–find over the frameworks, in a fixed order (by pair) so the result is the same
    // whatever the map's order.
    let mut parent: Vec<usize> = (0..frameworks.count).collect();
    fn root(parent: &mut [usize], mut f: usize) -> usize {
        while parent[f] != f {
            parent[f] = parent[parent[f]];
            f = parent[f];
        }
        f
    }
    let mut edges: Vec<((u8, u8), Vec<f64>)> = across.into_iter().collect();
    edges.sort_by_key(|e| e.0);
    for ((f, g), mut ratios) in edges {
        if ratios.len() < LEAST_PAIRS {
            continue;
        }
        let mid = ratios.len() / 2;
        let median = *ratios.select_nth_unstable_by(mid, f64::total_cmp).1;
        if median < JUMP.ln() {
            let (a, b) = (root(&mut parent, usize::from(f)), root(&mut parent, usize::from(g)));
            parent[a.max(b)] = a.min(b);
        }
    }
    let roots: Vec<usize> = (0..frameworks.count).map(|f| root(&mut parent, f)).collect();
    // Relabel the merged frameworks, the largest first.
    let mut size: HashMap<usize, usize> = HashMap::new();
    for p in (0..n).filter(|&p| frameworks.solid[p]) {
        *size.entry(roots[usize::from(frameworks.labels[p])]).or_default() += 1;
    }
    let mut order: Vec<usize> = roots.clone();
    order.sort_unstable();
    order.dedup();
    order.sort_by_key(|r| (std::cmp::Reverse(size.get(r).copied().unwrap_or(0)), *r));
    let label_of: HashMap<usize, u8> =
        order.iter().enumerate().map(|(i, &r)| (r, i as u8)).collect();
    let labels = frameworks
        .labels
        .iter()
        .zip(&frameworks.solid)
        .map(|(&l, &solid)| if solid { label_of[&roots[usize::from(l)]] } else { 0 })
        .collect();
    Frameworks { labels, solid: frameworks.solid, count: order.len() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::retinex::{counted, frameworks_of};

    /// Three bands lit by different lights: a sun-lit left, a middle where a second flood
    /// joins (the light 10 % more), a shadow on the right (a fifth of it). The first two merge,
    /// the shadow stays apart.
    #[test]
    fn a_jump_of_light_divides_and_a_gradual_change_does_not() {
        let (w, h) = (90, 40);
        let keys: Vec<u32> = (0..w * h).map(|p| [1, 3, 0][(p % w) / 30]).collect();
        let white: Vec<f32> = (0..w * h).map(|p| [100.0, 110.0, 20.0][(p % w) / 30]).collect();
        let f = frameworks_of(&keys, counted(&vec![false; w * h], &vec![[1.0; 3]; w * h]), (w, h));
        assert_eq!(f.count, 3);
        let merged = merge_continuous(f, &white, w);
        assert_eq!(merged.count, 2);
        let at = |x: usize| merged.labels[20 * w + x];
        assert_eq!(at(10), at(50));
        assert_ne!(at(10), at(80));
    }
}
