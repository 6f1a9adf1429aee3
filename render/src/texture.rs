//! Photo textures as relative detail maps over a measured reflectance, filtered by the ray's
//! footprint so that distant stone does not alias.
//!
//! A photo carries the light it was taken under and an unknown white balance, so restauro never
//! takes its colour for an albedo. With `detail = "luminance"` the reflectance at a point is
//! ρ(λ, x) = min(1, ρₘ(λ)·Y(x)/Ȳ): the measured spectrum ρₘ scaled by the photo's relative
//! luminance there, Ȳ being the mean luminance over the surfaces the material covers. A photo
//! equal to its mean everywhere gives back ρₘ exactly.
//!
//! Filtering: a pyramid of the photo's luminance, each level the 2×2 box mean of the one above
//! (Williams, "Pyramidal parametrics", SIGGRAPH 1983), sampled bilinearly on the two levels
//! around the footprint's level and blended (trilinear). The footprint is a ray cone's
//! (Akenine-Möller et al., "Texture level of detail strategies for real-time ray tracing", Ray
//! Tracing Gems, ch. 20, 2019): the width a pixel's cone has reached after the distance the path
//! has travelled, widened by 1/√|cos θ| on a slanted surface (the geometric mean of the cone's
//! two axes on the surface), over the size of one texel on that triangle.

use crate::vertex_colour::{ColourPoint, VertexPalette};
use glam::Vec2;
use restauro_scene::texture::Texture;
use restauro_spectral::Spectrum;
use restauro_spectral::rgb_space::Transfer;
use restauro_spectral::rgb_upsampling::{SigmoidPolynomial, fit};
use std::sync::Arc;

/// A material state's photo, or its part's vertex colours, as detail over its measured
/// reflectance ρₘ.
pub enum Detail {
    /// ρ(λ, x) = min(1, ρₘ(λ)·Y(x)/Ȳ).
    Luminance {
        pyramid: Arc<LuminancePyramid>,
        inverse_mean: f32,
    },
    /// ρ(λ, x) = min(1, ρₘ(λ)·S_x(λ)/S̄(λ)): `inverse_mean` is 1/S̄(λ), S̄ the smooth spectrum of
    /// the photo's mean colour.
    Chromatic {
        pyramid: Arc<ChromaticPyramid>,
        inverse_mean: Box<Spectrum>,
    },
    /// The same two from vertex colours ([`crate::vertex_colour`]).
    VertexLuminance {
        palette: Arc<VertexPalette>,
        inverse_mean: f32,
    },
    VertexChromatic {
        palette: Arc<VertexPalette>,
        inverse_mean: Box<Spectrum>,
    },
}

/// Where a hit falls on what gives its material detail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DetailPoint {
    Photo(TexturePoint),
    Vertices(ColourPoint),
}

impl Detail {
    /// ρ(λ) at `at` (ρₘ in, ρ out), a photo filtered over `footprint_m`.
    #[inline]
    pub fn apply(&self, at: DetailPoint, footprint_m: f32, rho: &mut Spectrum) {
        match (self, at) {
            (Detail::Luminance { pyramid, inverse_mean }, DetailPoint::Photo(at)) => {
                let lod = level_of_detail(footprint_m, at.texel_m);
                scale(rho, pyramid.sample(at.uv, lod) * inverse_mean);
            }
            (Detail::Chromatic { pyramid, inverse_mean }, DetailPoint::Photo(at)) => {
                let lod = level_of_detail(footprint_m, at.texel_m);
                let mut smooth = Spectrum::ZERO;
                pyramid.sample(at.uv, lod, &mut smooth);
                modulate(rho, &smooth, inverse_mean);
            }
            (Detail::VertexLuminance { palette, inverse_mean }, DetailPoint::Vertices(at)) => {
                scale(rho, palette.luminance(&at) * inverse_mean);
            }
            (Detail::VertexChromatic { palette, inverse_mean }, DetailPoint::Vertices(at)) => {
                let mut smooth = Spectrum::ZERO;
                palette.spectrum(&at, &mut smooth);
                modulate(rho, &smooth, inverse_mean);
            }
            // A triangle carries the kind of point its material's detail reads.
            _ => {}
        }
    }
}

/// ρ ← min(1, ρ·k).
#[inline]
fn scale(rho: &mut Spectrum, k: f32) {
    for r in &mut rho.0 {
        *r = (*r * k).min(1.0);
    }
}

/// ρ(λ) ← min(1, ρ(λ)·S(λ)/S̄(λ)), given 1/S̄.
#[inline]
fn modulate(rho: &mut Spectrum, smooth: &Spectrum, inverse_mean: &Spectrum) {
    for ((r, s), k) in rho.0.iter_mut().zip(&smooth.0).zip(&inverse_mean.0) {
        *r = (*r * s * k).min(1.0);
    }
}

/// 1/S̄(λ), S̄ the smooth spectrum of linear colour `mean`; `None` when no sigmoid reaches it.
pub fn inverse_smooth_spectrum(mean: [f32; 3]) -> Option<Box<Spectrum>> {
    let average = fit(mean.map(f64::from)).ok()?.spectrum();
    Some(Box::new(Spectrum(average.0.map(|s| 1.0 / s))))
}

/// A photo's pyramid for one kind of detail, shared by the materials that use it.
#[derive(Clone)]
pub enum Pyramid {
    Luminance(Arc<LuminancePyramid>),
    Chromatic(Arc<ChromaticPyramid>),
}

impl Pyramid {
    /// The pyramid `kind` of detail needs; `None` for no detail.
    pub fn new(texture: &Texture, kind: restauro_scene::scene_file::Detail) -> Option<Self> {
        use restauro_scene::scene_file::Detail as Kind;
        match kind {
            Kind::Luminance => Some(Pyramid::Luminance(Arc::new(LuminancePyramid::new(texture)))),
            Kind::Chromatic => Some(Pyramid::Chromatic(Arc::new(ChromaticPyramid::new(texture)))),
            Kind::None => None,
        }
    }

    pub fn size(&self) -> (u32, u32) {
        match self {
            Pyramid::Luminance(p) => p.size(),
            Pyramid::Chromatic(p) => p.size(),
        }
    }

    /// What the mean is taken of: the luminance (in each of the three places) or the linear
    /// colour.
    pub fn colour(&self, uv: Vec2, lod: f32) -> [f32; 3] {
        match self {
            Pyramid::Luminance(p) => [p.sample(uv, lod); 3],
            Pyramid::Chromatic(p) => p.colour(uv, lod),
        }
    }

    /// The detail this photo gives a material whose surfaces it covers with mean `mean` (as
    /// [`Pyramid::colour`] gives it); `None` for a black mean, which has no detail to give.
    pub fn detail(self, mean: [f32; 3]) -> Option<Detail> {
        match self {
            Pyramid::Luminance(pyramid) => {
                (mean[0] > 0.0).then(|| Detail::Luminance { pyramid, inverse_mean: 1.0 / mean[0] })
            }
            Pyramid::Chromatic(pyramid) => {
                let inverse_mean = inverse_smooth_spectrum(mean)?;
                Some(Detail::Chromatic { pyramid, inverse_mean })
            }
        }
    }

    pub fn memory_bytes(&self) -> usize {
        match self {
            Pyramid::Luminance(p) => p.memory_bytes(),
            Pyramid::Chromatic(p) => p.memory_bytes(),
        }
    }
}

/// One level of a luminance pyramid: linear relative luminance Y (0..1) per texel, rows from
/// the top.
struct Level {
    width: u32,
    height: u32,
    y: Vec<f32>,
}

/// A photo's luminance, from full size down to one texel.
pub struct LuminancePyramid {
    levels: Vec<Level>,
}

pub(crate) use restauro_scene::texture::luminance;

impl LuminancePyramid {
    pub fn new(texture: &Texture) -> Self {
        let (w, h) = (texture.width, texture.height);
        let mut y = Vec::with_capacity(w as usize * h as usize);
        for row in 0..h {
            y.extend((0..w).map(|x| luminance(texture.linear_rgb(x, row))));
        }
        Self::from_values(w, h, y)
    }

    /// A pyramid of given values (0..1), rows from the top: a degradation class's coverage.
    pub fn from_values(width: u32, height: u32, values: Vec<f32>) -> Self {
        let first = Level { width, height, y: values };
        Self { levels: build_levels(first, |l| (l.width, l.height), half) }
    }

    /// The full-size texels across and down.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// As [`LuminancePyramid::sample`], but with the edge texels held beyond the edges instead
    /// of repeating (a map laid over one rectangle: its east edge is not its west one).
    pub fn sample_clamped(&self, uv: Vec2, lod: f32) -> f32 {
        self.sample_with(uv, lod, Edges::Clamp)
    }

    /// Y at texture coordinates `uv` (repeating outside 0..1, as glTF's default sampler), on
    /// level `lod` (0 the full photo; fractions blend two levels).
    pub fn sample(&self, uv: Vec2, lod: f32) -> f32 {
        self.sample_with(uv, lod, Edges::Repeat)
    }

    fn sample_with(&self, uv: Vec2, lod: f32, edges: Edges) -> f32 {
        let (fine, coarse, t) = levels_around(lod, self.levels.len());
        let a = bilinear(&self.levels[fine], uv, edges);
        if t <= 0.0 {
            return a;
        }
        a + (bilinear(&self.levels[coarse], uv, edges) - a) * t
    }

    /// Bytes held, for a worker's bound on the scenes it keeps.
    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.y.len() * std::mem::size_of::<f32>()).sum()
    }
}

/// A photo as smooth spectra: each texel's colour (quantised to 8-bit sRGB, finer than a
/// photo's own noise) fitted once with Jakob & Hanika's sigmoid polynomial, a texel holding the
/// index of its colour in a palette. Coarser levels average their children's linear colours
/// and fit the mean (a fit of the mean, not a mean of fits: the fit is not linear).
pub struct ChromaticPyramid {
    levels: Vec<IndexLevel>,
    /// Per colour: its linear sRGB and its spectrum's coefficients.
    palette: Vec<([f32; 3], SigmoidPolynomial)>,
}

struct IndexLevel {
    width: u32,
    height: u32,
    index: Vec<u32>,
}

/// The palette being gathered: colours by their 8-bit sRGB key.
#[derive(Default)]
struct Palette {
    keys: std::collections::HashMap<u32, u32>,
    rgb: Vec<[f32; 3]>,
}

impl Palette {
    /// The index of the colour whose 8-bit sRGB encoding is `srgb8`.
    fn index(&mut self, srgb8: [u8; 3]) -> u32 {
        let key = u32::from(srgb8[0]) << 16 | u32::from(srgb8[1]) << 8 | u32::from(srgb8[2]);
        let next = self.rgb.len() as u32;
        *self.keys.entry(key).or_insert_with(|| {
            self.rgb.push(srgb8.map(|c| Transfer::Srgb.decode(f64::from(c) / 255.0) as f32));
            next
        })
    }
}

/// A linear value's 8-bit sRGB code (IEC 61966-2-1's encoding function).
fn linear_to_srgb8(v: f32) -> u8 {
    (Transfer::Srgb.encode(f64::from(v)) * 255.0).round() as u8
}

impl ChromaticPyramid {
    pub fn new(texture: &Texture) -> Self {
        use rayon::prelude::*;
        let mut palette = Palette::default();
        let to8 = |c: u16| ((u32::from(c) + 128) / 257) as u8;
        let index = texture.texels.iter().map(|t| palette.index(t.map(to8))).collect();
        let first = IndexLevel { width: texture.width, height: texture.height, index };
        let levels = build_levels(
            first,
            |l| (l.width, l.height),
            |l, shape| half_indices(l, shape, &mut palette),
        );
        // A colour no sigmoid reaches (none of the sRGB cube, the fit's tests say) would keep
        // the flat 0.5: the detail then leaves that texel's reflectance as measured.
        let fits: Vec<SigmoidPolynomial> =
            palette.rgb.par_iter().map(|c| fit(c.map(f64::from)).unwrap_or_default()).collect();
        Self { levels, palette: palette.rgb.into_iter().zip(fits).collect() }
    }

    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// The smooth spectrum at `uv` on level `lod` into `out`: the texels' spectra evaluated,
    /// then blended (bilinearly on each of the two levels, then between them).
    pub fn sample(&self, uv: Vec2, lod: f32, out: &mut Spectrum) {
        *out = Spectrum::ZERO;
        let (fine, coarse, t) = levels_around(lod, self.levels.len());
        self.add_bilinear(fine, uv, 1.0 - t, out);
        if t > 0.0 {
            self.add_bilinear(coarse, uv, t, out);
        }
    }

    fn add_bilinear(&self, level: usize, uv: Vec2, weight: f32, out: &mut Spectrum) {
        let l = &self.levels[level];
        for (x, y, w) in bilinear_taps(l.width, l.height, uv, Edges::Repeat) {
            let (_, s) = &self.palette[l.index[(y * l.width + x) as usize] as usize];
            let w = w * weight;
            if w > 0.0 {
                for (band, o) in out.0.iter_mut().enumerate() {
                    *o += w * s.value(band);
                }
            }
        }
    }

    /// The linear colour at `uv` on level `lod` (bilinear on the nearer level), for the mean.
    pub fn colour(&self, uv: Vec2, lod: f32) -> [f32; 3] {
        let level = (lod.round().max(0.0) as usize).min(self.levels.len() - 1);
        let l = &self.levels[level];
        let mut c = [0.0f32; 3];
        for (x, y, w) in bilinear_taps(l.width, l.height, uv, Edges::Repeat) {
            let (rgb, _) = &self.palette[l.index[(y * l.width + x) as usize] as usize];
            for k in 0..3 {
                c[k] += w * rgb[k];
            }
        }
        c
    }

    pub fn memory_bytes(&self) -> usize {
        self.levels.iter().map(|l| l.index.len() * 4).sum::<usize>()
            + self.palette.len() * std::mem::size_of::<([f32; 3], SigmoidPolynomial)>()
    }
}

fn half_indices(l: &IndexLevel, shape: Shape, palette: &mut Palette) -> IndexLevel {
    let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
    let mut index = Vec::with_capacity(w as usize * h as usize);
    for row in 0..h {
        for col in 0..w {
            let mut sum = [0.0f32; 3];
            for (i, weight) in shape.children(col, row) {
                let rgb = palette.rgb[l.index[i] as usize];
                (0..3).for_each(|k| sum[k] += weight * rgb[k]);
            }
            index.push(palette.index(sum.map(linear_to_srgb8)));
        }
    }
    IndexLevel { width: w, height: h, index }
}

/// A level about to be halved: its size, the photo's, and how many of the photo's texels each
/// of its texels spans along each axis (a power of two; fewer at an odd edge).
#[derive(Clone, Copy)]
struct Shape {
    width: u32,
    height: u32,
    full: (u32, u32),
    span: u32,
}

impl Shape {
    /// The (up to) 2×2 texels under texel (col, row) of the next level, by index, each weighted
    /// by the share of the photo's texels it spans, so that every level's mean, and the last
    /// texel, is the photo's mean whatever its size.
    fn children(self, col: u32, row: u32) -> impl Iterator<Item = (usize, f32)> {
        // The two texels along one axis and the photo's texels each spans (0 past the edge).
        let span = self.span;
        let axis = move |i: u32, n: u32, full: u32| {
            [2 * i, 2 * i + 1].map(|k| {
                (k, if k < n { span.min(full.saturating_sub(k * span)) as f32 } else { 0.0 })
            })
        };
        let xs = axis(col, self.width, self.full.0);
        let ys = axis(row, self.height, self.full.1);
        let total = (xs[0].1 + xs[1].1) * (ys[0].1 + ys[1].1);
        xs.into_iter().filter(|&(_, a)| a > 0.0).flat_map(move |(x, a)| {
            ys.into_iter()
                .filter(|&(_, b)| b > 0.0)
                .map(move |(y, b)| ((y * self.width + x) as usize, a * b / total))
        })
    }
}

/// The levels either side of `lod` in a pyramid of `count` levels, and how far `lod` lies from
/// the finer towards the coarser (`lod` clamped to the pyramid).
fn levels_around(lod: f32, count: usize) -> (usize, usize, f32) {
    let lod = lod.clamp(0.0, (count - 1) as f32);
    let fine = lod.floor() as usize;
    (fine, (fine + 1).min(count - 1), lod - fine as f32)
}

/// A pyramid's levels: `first`, then each made by `halve` from the one before, down to one
/// texel; `size` gives a level's texels across and down.
fn build_levels<L>(
    first: L,
    size: impl Fn(&L) -> (u32, u32),
    mut halve: impl FnMut(&L, Shape) -> L,
) -> Vec<L> {
    let full = size(&first);
    let mut levels = vec![first];
    while let Some(last) = levels.last().filter(|l| size(l) != (1, 1)) {
        let (width, height) = size(last);
        let shape = Shape { width, height, full, span: 1 << (levels.len() - 1) };
        let next = halve(last, shape);
        levels.push(next);
    }
    levels
}

/// What lies beyond an image's edges.
#[derive(Clone, Copy)]
enum Edges {
    /// The image again (a photo tiling a surface; glTF's default sampler).
    Repeat,
    /// The edge texels (an image laid over one rectangle).
    Clamp,
}

/// The four texels around `uv` and their bilinear weights.
fn bilinear_taps(width: u32, height: u32, uv: Vec2, edges: Edges) -> [(u32, u32, f32); 4] {
    let x = uv.x * width as f32 - 0.5;
    let y = uv.y * height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wrap = move |i: f32, n: u32| match edges {
        Edges::Repeat => (i as i64).rem_euclid(i64::from(n)) as u32,
        Edges::Clamp => (i as i64).clamp(0, i64::from(n) - 1) as u32,
    };
    let (xa, xb) = (wrap(x0, width), wrap(x0 + 1.0, width));
    let (ya, yb) = (wrap(y0, height), wrap(y0 + 1.0, height));
    [
        (xa, ya, (1.0 - fx) * (1.0 - fy)),
        (xb, ya, fx * (1.0 - fy)),
        (xa, yb, (1.0 - fx) * fy),
        (xb, yb, fx * fy),
    ]
}

/// The next level: each texel the mean of the (up to) 2×2 texels it covers, weighted by what
/// they span ([`Shape::children`]).
fn half(l: &Level, shape: Shape) -> Level {
    let (w, h) = (l.width.div_ceil(2), l.height.div_ceil(2));
    let mut y = Vec::with_capacity(w as usize * h as usize);
    for row in 0..h {
        for col in 0..w {
            y.push(shape.children(col, row).map(|(i, weight)| weight * l.y[i]).sum());
        }
    }
    Level { width: w, height: h, y }
}

/// Bilinear interpolation between the four texel centres around `uv`.
fn bilinear(l: &Level, uv: Vec2, edges: Edges) -> f32 {
    bilinear_taps(l.width, l.height, uv, edges)
        .iter()
        .map(|&(x, y, w)| w * l.y[(y * l.width + x) as usize])
        .sum()
}

/// The level of detail whose texels are the footprint's size: log₂(footprint / texel), where
/// `texel_m` is the size of one full-size texel on the surface.
#[inline]
pub fn level_of_detail(footprint_m: f32, texel_m: f32) -> f32 {
    if texel_m > 0.0 && footprint_m > texel_m { (footprint_m / texel_m).log2() } else { 0.0 }
}

/// Where a ray met a textured triangle: its texture coordinates and the size of one texel
/// there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePoint {
    pub uv: Vec2,
    pub texel_m: f32,
}

/// A triangle's texture coordinates and the size on it of one texel of its material's photo:
/// √(area / (uv area · texels)).
#[derive(Clone, Copy, Debug)]
pub struct TexturedTriangle {
    pub uv: [Vec2; 3],
    pub texel_m: f32,
}

impl TexturedTriangle {
    pub fn new(uv: [Vec2; 3], area_m2: f32, texels: (u32, u32)) -> Self {
        let uv_area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
        let texel_area = uv_area * texels.0 as f32 * texels.1 as f32;
        let texel_m = if texel_area > 0.0 { (area_m2 / texel_area).sqrt() } else { 0.0 };
        Self { uv, texel_m }
    }

    /// The texture point at barycentric `weights`.
    #[inline]
    pub fn at(&self, weights: [f32; 3]) -> TexturePoint {
        let uv = self.uv[0] * weights[0] + self.uv[1] * weights[1] + self.uv[2] * weights[2];
        TexturePoint { uv, texel_m: self.texel_m }
    }

    /// 16 points spread evenly over a triangle, as barycentric weights: the centroids of the
    /// 16 equal triangles of its 4 × 4 subdivision.
    pub fn spread_points() -> [[f32; 3]; 16] {
        let mut out = [[0.0; 3]; 16];
        let mut k = 0;
        for i in 0..4 {
            for j in 0..4 - i {
                let (u, v) = ((i as f32 + 1.0 / 3.0) / 4.0, (j as f32 + 1.0 / 3.0) / 4.0);
                out[k] = [1.0 - u - v, u, v];
                k += 1;
                if i + j < 3 {
                    let (u, v) = ((i as f32 + 2.0 / 3.0) / 4.0, (j as f32 + 2.0 / 3.0) / 4.0);
                    out[k] = [1.0 - u - v, u, v];
                    k += 1;
                }
            }
        }
        out
    }

    /// The level one of whose texels covers the whole triangle in texture space: a sample
    /// there is near the triangle's mean.
    pub fn whole_level(&self, texels: (u32, u32)) -> f32 {
        let uv_area = 0.5 * (self.uv[1] - self.uv[0]).perp_dot(self.uv[2] - self.uv[0]).abs();
        let texel_area = uv_area * texels.0 as f32 * texels.1 as f32;
        if texel_area > 1.0 { 0.5 * texel_area.log2() } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32, f: impl Fn(u32, u32) -> u16) -> Texture {
        let texels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| [f(x, y); 3]);
        Texture { width: w, height: h, texels: texels.collect() }
    }

    /// The top of the pyramid is the photo's mean luminance, for odd sizes too.
    #[test]
    fn the_last_level_is_the_mean() {
        let t = texture(5, 3, |x, y| ((x * 7 + y * 13) % 17 * 3000) as u16);
        let p = LuminancePyramid::new(&t);
        let full = &p.levels[0].y;
        let mean = full.iter().sum::<f32>() / full.len() as f32;
        let top = p.levels.last().unwrap();
        assert_eq!((top.width, top.height), (1, 1));
        assert!((top.y[0] - mean).abs() < 1e-6, "{} against {mean}", top.y[0]);
        let even = LuminancePyramid::new(&texture(4, 4, |x, y| ((x + 3 * y) * 4000) as u16));
        let full = &even.levels[0].y;
        let mean = full.iter().sum::<f32>() / full.len() as f32;
        assert!((even.levels.last().unwrap().y[0] - mean).abs() < 1e-6);
    }

    /// At a texel's centre bilinear filtering gives that texel; between two, their mean; and
    /// coordinates repeat.
    #[test]
    fn bilinear_lookup_hits_texel_centres_and_repeats() {
        let t = texture(2, 1, |x, _| if x == 0 { 0 } else { 65535 });
        let p = LuminancePyramid::new(&t);
        assert!((p.sample(Vec2::new(0.25, 0.5), 0.0) - 0.0).abs() < 1e-6);
        assert!((p.sample(Vec2::new(0.75, 0.5), 0.0) - 1.0).abs() < 1e-6);
        assert!((p.sample(Vec2::new(0.5, 0.5), 0.0) - 0.5).abs() < 1e-6);
        assert!((p.sample(Vec2::new(1.75, -0.5), 0.0) - 1.0).abs() < 1e-6);
        // The coarsest level is the mean everywhere.
        assert!((p.sample(Vec2::new(0.25, 0.5), 5.0) - 0.5).abs() < 1e-6);
    }
}
