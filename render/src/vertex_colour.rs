//! A scan's vertex colours (PLY `red`, `green`, `blue`; glTF `COLOR_0`) as detail over a
//! measured reflectance, the two ways a photo gives it ([`crate::texture`]): with
//! `detail = "luminance"`,
//! ρ(λ, x) = min(1, ρₘ(λ)·Y(x)/Ȳ), Y interpolated between the triangle's vertices; with
//! `detail = "chromatic"`, ρ(λ, x) = min(1, ρₘ(λ)·S_x(λ)/S̄(λ)), S_x the vertices' smooth
//! spectra (Jakob & Hanika 2019, fitted once per colour) interpolated after evaluation, not
//! before. Ȳ and S̄ come from the material's mean colour over the surfaces it covers, weighted
//! by area: a colour varying linearly over a triangle has the mean of its three corners there,
//! so the mean is exact.
//!
//! No filtering is needed: colours given per vertex vary no faster than the geometry, which a
//! pixel's samples already filter.

use restauro_scene::texture::luminance;
use restauro_spectral::Spectrum;
use restauro_spectral::rgb_space::Transfer;
use restauro_spectral::rgb_upsampling::{SigmoidPolynomial, fit};
use std::collections::HashMap;

/// Where a ray met a coloured triangle: its corners' colours (indices in the
/// [`VertexPalette`]) and the hit's barycentric weights for them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourPoint {
    pub corners: [u32; 3],
    pub weights: [f32; 3],
}

/// The colours the vertices of a prepared scene take, each once: its luminance, and when a
/// material takes chromatic detail from them, its smooth spectrum.
pub struct VertexPalette {
    luminance: Vec<f32>,
    spectra: Vec<SigmoidPolynomial>,
}

/// The colours being gathered, each once by its 16-bit sRGB code: exact for the 8-bit colours
/// most scans carry, and far finer than a scanner's colour noise for the rest (floats, and
/// glTF's linear bytes).
#[derive(Default)]
pub struct PaletteBuilder {
    keys: HashMap<u64, u32>,
    rgb: Vec<[f32; 3]>,
}

impl PaletteBuilder {
    /// The index of linear colour `rgb` (0..1).
    pub fn index(&mut self, rgb: [f32; 3]) -> u32 {
        let code = rgb.map(|c| {
            (Transfer::Srgb.encode(f64::from(c).clamp(0.0, 1.0)) * 65535.0).round() as u64
        });
        let next = self.rgb.len() as u32;
        *self.keys.entry(code[0] << 32 | code[1] << 16 | code[2]).or_insert_with(|| {
            self.rgb.push(code.map(|c| Transfer::Srgb.decode(c as f64 / 65535.0) as f32));
            next
        })
    }

    /// The linear colour at `index`, as the palette holds it.
    pub fn colour(&self, index: u32) -> [f32; 3] {
        self.rgb[index as usize]
    }

    /// The palette, with each colour's spectrum fitted when `chromatic` (a fit per colour, in
    /// parallel; a colour no sigmoid reaches keeps the flat 0.5 and so leaves ρₘ as it is).
    pub fn finish(self, chromatic: bool) -> VertexPalette {
        use rayon::prelude::*;
        let rgb = self.rgb;
        let spectra = match chromatic {
            true => rgb.par_iter().map(|c| fit(c.map(f64::from)).unwrap_or_default()).collect(),
            false => Vec::new(),
        };
        VertexPalette { luminance: rgb.iter().map(|&c| luminance(c)).collect(), spectra }
    }
}

impl VertexPalette {
    /// Y at `at`: the corners' luminances interpolated.
    #[inline]
    pub fn luminance(&self, at: &ColourPoint) -> f32 {
        (0..3).map(|k| at.weights[k] * self.luminance[at.corners[k] as usize]).sum()
    }

    /// S(λ) at `at` into `out`: the corners' spectra evaluated, then interpolated.
    #[inline]
    pub fn spectrum(&self, at: &ColourPoint, out: &mut Spectrum) {
        let corners = at.corners.map(|c| &self.spectra[c as usize]);
        for (band, o) in out.0.iter_mut().enumerate() {
            *o = (0..3).map(|k| at.weights[k] * corners[k].value(band)).sum();
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.luminance.len() * 4 + self.spectra.len() * std::mem::size_of::<SigmoidPolynomial>()
    }
}
