//! Frameworks of illumination: the regions of an image lit by the same light, and how their
//! lights differ.
//!
//! In a scene with two lights — a warm sun, and a blue sky in the shadows — the eye adapts to
//! each region's own light: a white card in the shadow looks white, not blue, though it is
//! bluer than the white card in the sun. Anchoring theory (Gilchrist et al., "An anchoring
//! theory of lightness perception", Psychological Review 106, 1999) calls these regions
//! *frameworks*: each has its own anchor, and a surface's lightness is a weighted mean of its
//! value relative to its own framework and to the whole image.
//!
//! **Which pixels.** A framework is a set of pixels with the same *key*: for a render, the bit
//! mask of the lights that light the camera's first hit (the renderer knows where the sun's
//! shadow falls; an image's own edges cannot say whether a step is a shadow or a darker stone).
//! A framework must be an area: a pixel is in its key's framework only if the key's region
//! survives a morphological opening there (a square of [`solid_radius`]), so the shadow in a
//! mortar joint, a crack or along a sill — a line, not an area — is seen within the framework
//! around it, as people see small shadows: darker and bluer. Keys of fewer than [`MIN_SHARE`]
//! of the surface pixels join the nearest large framework (the one whose mask differs in the
//! fewest lights; of those, the largest), and at most [`MAX_FRAMEWORKS`] are kept.
//!
//! **How their lights differ.** Where two frameworks meet, the same surfaces lie on both sides
//! of the edge (a shadow falls across the stones, it does not follow them), so the ratio of the
//! image across the edge is the ratio of the two lights — the cue by which the visual system
//! tells an illumination edge from a reflectance edge. Per channel, the median over all pairs of
//! pixels three apart across the edge (each inside its framework's area) is the log ratio of
//! the two lights; frameworks are chained to the largest through the edges with most pairs, and
//! the ratios are taken to the framework with the most light (where the image's white is). A
//! median of thousands of pairs is robust to Monte Carlo noise (the per-channel maxima of a
//! noisy shadow are not: they made an olive white) and to the few places where a material edge
//! runs along the shadow's.

use std::collections::HashMap;

/// The most frameworks an image is split into.
pub const MAX_FRAMEWORKS: usize = 8;
/// The least share of the surface pixels (light sources not counted) a framework covers.
pub const MIN_SHARE: f64 = 0.02;
/// Pixels this far apart across a framework edge are compared (the one between them is often
/// part lit, part shadowed).
const PAIR_DISTANCE_PX: usize = 3;

/// The frameworks of an image.
pub(crate) struct Frameworks {
    /// Each pixel's framework, 0..count (0 is the largest); light sources, black pixels and
    /// pixels outside every framework's area (a line of shadow) are given 0.
    pub labels: Vec<u8>,
    /// Whether each pixel lies in its framework's area (`labels` is its framework, not a
    /// default). With one framework, every surface pixel that is not black.
    pub solid: Vec<bool>,
    pub count: usize,
}

impl Frameworks {
    /// One framework: every pixel that `counted` marks lies in it.
    pub(crate) fn one(counted: Vec<bool>) -> Self {
        Frameworks { labels: vec![0; counted.len()], solid: counted, count: 1 }
    }
}

/// The pixels that can belong to a framework: surfaces (not light sources) that are not black
/// (a camera ray that met nothing, with no sky to see, is lit by nothing, but no framework).
pub(crate) fn counted(emitters: &[bool], pixels: &[[f32; 3]]) -> Vec<bool> {
    emitters.iter().zip(pixels).map(|(&e, p)| !e && *p != [0.0; 3]).collect()
}

/// The half-width of the square that a framework's area must hold: 2 px, and more for large
/// images (a 1920×1080 image's joints are wider).
pub(super) fn solid_radius(width: usize, height: usize) -> usize {
    let diagonal = ((width * width + height * height) as f64).sqrt();
    ((diagonal / 600.0).round() as usize).max(2)
}

/// Whether each pixel lies in the opening of its own key's region (light sources and black
/// pixels are in no region): in some full square of half-width `r` whose pixels all share its
/// key.
///
/// Both squares are taken as a row segment and then a column of them, 2 · (2r + 1) reads a
/// pixel instead of (2r + 1)²: a square lies in one region when each of its rows does and the
/// rows' keys agree; and a pixel within reach of an eroded pixel lies in that pixel's square,
/// so it has its key, and the dilation need not compare keys.
fn solid(keys: &[u32], counted: &[bool], width: usize, height: usize, r: usize) -> Vec<bool> {
    use rayon::prelude::*;
    let span = |c: usize, len: usize| c.saturating_sub(r)..=(c + r).min(len - 1);
    let each = |f: &(dyn Fn(usize, usize, usize) -> bool + Sync)| -> Vec<bool> {
        (0..keys.len()).into_par_iter().map(|p| f(p, p % width, p / width)).collect()
    };
    let at = |x: usize, y: usize| y * width + x;
    // Per pixel: the row segment around it lies inside the image and in its region.
    let row_inside = each(&|p, x, y| {
        x >= r
            && x + r < width
            && span(x, width).all(|i| counted[at(i, y)] && keys[at(i, y)] == keys[p])
    });
    // Erosion: the square around p lies wholly in p's region (and inside the image).
    let eroded = each(&|p, x, y| {
        y >= r
            && y + r < height
            && span(y, height).all(|j| row_inside[at(x, j)] && keys[at(x, j)] == keys[p])
    });
    // Dilation of the eroded region: a row segment, then a column of them.
    let row_any = each(&|_, x, y| span(x, width).any(|i| eroded[at(i, y)]));
    each(&|p, x, y| counted[p] && span(y, height).any(|j| row_any[at(x, j)]))
}

/// The frameworks of an image (`width` × `height`) with `keys` per pixel, among the pixels
/// `counted` marks (see [`counted`]).
pub(crate) fn frameworks(
    keys: &[u32],
    counted: Vec<bool>,
    (width, height): (usize, usize),
) -> Frameworks {
    let n = keys.len();
    let solid = solid(keys, &counted, width, height, solid_radius(width, height));
    let mut sizes: HashMap<u32, usize> = HashMap::new();
    for p in (0..n).filter(|&p| solid[p]) {
        *sizes.entry(keys[p]).or_default() += 1;
    }
    let surface = counted.iter().filter(|&&c| c).count();
    let mut by_size: Vec<(u32, usize)> = sizes.into_iter().collect();
    // Largest first, then by key, so that the labels do not depend on the hash order.
    by_size.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let least = (MIN_SHARE * surface as f64).ceil() as usize;
    let kept: Vec<u32> = by_size
        .iter()
        .enumerate()
        .take_while(|&(i, &(_, size))| i == 0 || size >= least)
        .take(MAX_FRAMEWORKS)
        .map(|(_, &(key, _))| key)
        .collect();
    if kept.len() <= 1 {
        return Frameworks::one(counted);
    }
    // The kept are in order of size, so the first of the nearest is the largest.
    let nearest = |key: u32| -> u8 {
        let (label, _) = kept
            .iter()
            .enumerate()
            .min_by_key(|&(i, &k)| ((k ^ key).count_ones(), i))
            .expect("at least one framework is kept");
        label as u8
    };
    let of_key: HashMap<u32, u8> = by_size.iter().map(|&(key, _)| (key, nearest(key))).collect();
    let labels: Vec<u8> = (0..n).map(|p| if solid[p] { of_key[&keys[p]] } else { 0 }).collect();
    Frameworks { labels, solid, count: kept.len() }
}

/// Per framework and channel, the natural log of (the light of the framework with the most
/// light / its own): 0 for that one, and for those that touch no other. From the pairs of
/// pixels across the edges between frameworks (see the module comment): for an image whose
/// lights are not known.
pub(crate) fn light_ratios(
    pixels: &[[f32; 3]],
    frameworks: &Frameworks,
    width: usize,
) -> Vec<[f64; 3]> {
    let Frameworks { labels, solid, count, .. } = frameworks;
    let count = *count;
    if count == 1 {
        return vec![[0.0; 3]];
    }
    let n = pixels.len();
    let ln = |p: usize| pixels[p].map(|v| f64::from(v).ln());
    // Per ordered pair of frameworks (f, g), the log ratios image(f-side) / image(g-side).
    let mut across: HashMap<(u8, u8), Vec<[f64; 3]>> = HashMap::new();
    let d = PAIR_DISTANCE_PX;
    for a in 0..n {
        let x = a % width;
        let right = (x + d < width).then(|| a + d);
        let below = (a + d * width < n).then(|| a + d * width);
        for b in [right, below].into_iter().flatten() {
            let (f, g) = (labels[a], labels[b]);
            let black = pixels[a].contains(&0.0) || pixels[b].contains(&0.0);
            if !solid[a] || !solid[b] || f == g || black {
                continue;
            }
            let (la, lb) = (ln(a), ln(b));
            let r: [f64; 3] = std::array::from_fn(|c| la[c] - lb[c]);
            across.entry((f, g)).or_default().push(r);
            across.entry((g, f)).or_default().push(r.map(|v| -v));
        }
    }
    let median = |v: &mut Vec<[f64; 3]>| -> [f64; 3] {
        std::array::from_fn(|c| {
            let mut xs: Vec<f64> = v.iter().map(|r| r[c]).collect();
            let mid = xs.len() / 2;
            *xs.select_nth_unstable_by(mid, f64::total_cmp).1
        })
    };
    // Chained from the largest: each step adds the framework reached through the edge with the
    // most pairs from those already reached. One touching no other keeps the image's light.
    let mut ratio: Vec<Option<[f64; 3]>> = vec![None; count];
    ratio[0] = Some([0.0; 3]);
    loop {
        let next = across
            .iter()
            .filter(|((f, g), _)| {
                ratio[usize::from(*f)].is_some() && ratio[usize::from(*g)].is_none()
            })
            .max_by_key(|((f, g), v)| (v.len(), std::cmp::Reverse((*f, *g))))
            .map(|(&k, _)| k);
        let Some((f, g)) = next else { break };
        let step = median(across.get_mut(&(f, g)).expect("the edge was found"));
        let base = ratio[usize::from(f)].expect("f is reached");
        // log(E₀/E_g) = log(E₀/E_f) + log(E_f/E_g), and across the edge I_f/I_g = E_f/E_g.
        ratio[usize::from(g)] = Some(std::array::from_fn(|c| base[c] + step[c]));
    }
    // Relative to the framework with the most light, where the image's white lies: its
    // surfaces are seen as the image's Retinex sees them, the others are adapted to their own
    // light.
    let ratio: Vec<[f64; 3]> = ratio.into_iter().map(|r| r.unwrap_or([0.0; 3])).collect();
    let level = |r: &[f64; 3]| r.iter().sum::<f64>();
    let brightest =
        ratio.iter().min_by(|a, b| level(a).total_cmp(&level(b))).copied().unwrap_or([0.0; 3]);
    ratio.iter().map(|r| std::array::from_fn(|c| r[c] - brightest[c])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image `w` × `h` of one grey, with keys from `key(x, y)`.
    fn grey(w: usize, h: usize, key: impl Fn(usize, usize) -> u32) -> (Vec<u32>, Vec<[f32; 3]>) {
        ((0..w * h).map(|p| key(p % w, p / w)).collect(), vec![[1.0; 3]; w * h])
    }

    /// The opening by its definition, square by square.
    fn solid_by_squares(keys: &[u32], counted: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
        let window = |p: usize| {
            let (x, y) = (p % w, p / w);
            let (x0, x1) = (x.saturating_sub(r), (x + r).min(w - 1));
            let (y0, y1) = (y.saturating_sub(r), (y + r).min(h - 1));
            (y0..=y1).flat_map(move |yy| (x0..=x1).map(move |xx| yy * w + xx))
        };
        let eroded: Vec<bool> = (0..keys.len())
            .map(|p| {
                let (x, y) = (p % w, p / w);
                counted[p]
                    && x >= r
                    && y >= r
                    && x + r < w
                    && y + r < h
                    && window(p).all(|q| counted[q] && keys[q] == keys[p])
            })
            .collect();
        (0..keys.len())
            .map(|p| counted[p] && window(p).any(|q| eroded[q] && keys[q] == keys[p]))
            .collect()
    }

    /// The separable opening is the opening by squares, on blotchy regions of four keys with
    /// holes, for several half-widths.
    #[test]
    fn the_opening_by_rows_and_columns_is_the_opening_by_squares() {
        let (w, h) = (97, 61);
        let mut rng = crate::keyed_random::KeyedRng::new(7);
        let mut keys = vec![0u32; w * h];
        // Random rectangles of random keys painted over one another.
        for _ in 0..60 {
            let (x0, y0) =
                ((rng.next_f32() * w as f32) as usize, (rng.next_f32() * h as f32) as usize);
            let (dx, dy) =
                (1 + (rng.next_f32() * 20.0) as usize, 1 + (rng.next_f32() * 15.0) as usize);
            let key = (rng.next_f32() * 4.0) as u32;
            for y in y0..(y0 + dy).min(h) {
                for x in x0..(x0 + dx).min(w) {
                    keys[y * w + x] = key;
                }
            }
        }
        let counted: Vec<bool> = (0..w * h).map(|_| rng.next_f32() > 0.003).collect();
        for r in [1, 2, 4, 7] {
            let expected = solid_by_squares(&keys, &counted, w, h, r);
            assert_eq!(solid(&keys, &counted, w, h, r), expected, "half-width {r}");
            assert!(r > 4 || (expected.iter().any(|&s| s) && expected.iter().any(|&s| !s)));
        }
    }

    #[test]
    fn one_key_is_one_framework() {
        let (keys, pixels) = grey(20, 10, |_, _| 5);
        let f = frameworks(&keys, counted(&[false; 200], &pixels), (20, 10));
        assert_eq!((f.count, f.labels.iter().all(|&l| l == 0)), (1, true));
    }

    #[test]
    fn a_line_of_shadow_is_no_framework() {
        // Sun everywhere but a shadowed stripe two pixels wide (a joint) and a block of 10×10.
        let (keys, pixels) = grey(40, 30, |x, y| {
            u32::from(!(x == 5 || x == 6 || ((20..30).contains(&x) && (10..20).contains(&y))))
        });
        let f = frameworks(&keys, counted(&[false; 1200], &pixels), (40, 30));
        assert_eq!(f.count, 2);
        let at = |x: usize, y: usize| f.labels[y * 40 + x];
        assert_eq!(at(5, 3), at(0, 0), "the joint is seen within the sunlit framework");
        assert_ne!(at(25, 15), at(0, 0), "the block is a framework");
        assert_eq!(at(20, 10), at(25, 15), "the block's corner is in it");
    }

    #[test]
    fn small_keys_join_the_nearest_large_framework() {
        // Left 60 % lit by lights 0 and 1, the rest by light 1, and two 6×6 patches (1 % each)
        // lit by light 0 only and by none.
        let (w, h) = (100, 60);
        let (keys, pixels) = grey(w, h, |x, y| match (x, y) {
            (10..16, 10..16) => 0b01,
            (70..76, 10..16) => 0b00,
            (x, _) if x < 60 => 0b11,
            _ => 0b10,
        });
        let f = frameworks(&keys, counted(&vec![false; w * h], &pixels), (w, h));
        assert_eq!(f.count, 2);
        let at = |x: usize, y: usize| f.labels[y * w + x];
        // 0b01 differs from 0b11 in one light and from 0b10 in two; 0b00 from 0b10 in one.
        assert_eq!(at(12, 12), at(0, 0));
        assert_eq!(at(72, 12), at(90, 50));
        assert_ne!(at(0, 0), at(90, 50));
    }

    #[test]
    fn light_sources_and_black_pixels_do_not_count() {
        // The sky above; a board (left half in the sun) below, beside a black void.
        let (w, h) = (40, 40);
        let (keys, mut pixels) = grey(w, h, |x, _| u32::from(x < 15));
        let emitters: Vec<bool> = (0..w * h).map(|p| p / w < 10).collect();
        for (p, pixel) in pixels.iter_mut().enumerate() {
            if p % w >= 30 {
                *pixel = [0.0; 3];
            }
        }
        let f = frameworks(&keys, counted(&emitters, &pixels), (w, h));
        assert_eq!(f.count, 2);
        assert_ne!(f.labels[20 * w + 5], f.labels[20 * w + 22]);
        assert_eq!(f.labels[20 * w + 35], 0, "the void belongs to none: 0");
    }

    #[test]
    fn at_most_eight_frameworks() {
        let (keys, pixels) = grey(120, 100, |x, _| (x / 10) as u32);
        let f = frameworks(&keys, counted(&vec![false; 12_000], &pixels), (120, 100));
        assert_eq!(f.count, MAX_FRAMEWORKS);
        assert!(f.labels.iter().all(|&l| usize::from(l) < MAX_FRAMEWORKS));
    }

    /// Stones of three colours in stripes across a shadow's edge: the ratio across the edge is
    /// the ratio of the lights, whatever the stones, and noise does not move the median.
    #[test]
    fn the_ratio_across_the_edge_is_the_ratio_of_the_lights() {
        let (w, h) = (60, 60);
        let shadow = [0.2f64, 0.25, 0.4];
        let stones = [[0.6f64, 0.5, 0.3], [0.3, 0.3, 0.3], [0.8, 0.7, 0.6]];
        let mut rng = crate::keyed_random::KeyedRng::from_parts(&[1]);
        let mut keys = Vec::new();
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                let lit = x < 30;
                keys.push(u32::from(lit));
                let stone = stones[(y / 7) % 3];
                std::array::from_fn(|c| {
                    let light = if lit { 1.0 } else { shadow[c] };
                    let noise = 1.0 + 0.2 * (f64::from(rng.below(1000)) / 1000.0 - 0.5);
                    (stone[c] * light * noise) as f32
                })
            })
            .collect();
        let f = frameworks(&keys, counted(&vec![false; w * h], &pixels), (w, h));
        assert_eq!(f.count, 2);
        let ratios = light_ratios(&pixels, &f, w);
        let shadowed = ratios[usize::from(f.labels[30 * w + 50])];
        let lit = ratios[usize::from(f.labels[30 * w + 5])];
        for c in 0..3 {
            // log(E₀/E_shadow) − log(E₀/E_sun) = log(E_sun/E_shadow).
            let expect = -shadow[c].ln();
            let got = shadowed[c] - lit[c];
            assert!((got - expect).abs() < 0.03, "channel {c}: {got} against {expect}");
        }
        assert_eq!(lit, [0.0; 3], "the sunlit framework is the reference");
    }
}
