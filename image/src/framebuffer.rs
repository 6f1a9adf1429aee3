//! The image a job assembles from its tiles, and the wire form of one tile's pixels.
//!
//! A tile travels and is stored as little-endian words: first X, Y, Z of every pixel (f32,
//! row-major within the tile), then, when the scene has a sky, each pixel's sky coverage (f32,
//! the fraction of its camera samples that saw the sky), then, when it has point or distant
//! lights, each pixel's mask of the lights that light it (u32, [`LIT_BITS`] bits), then, for an
//! image (not a calculation grid), each pixel's adapting white — X, Y, Z and the scotopic
//! luminance of a perfect white diffuser at its surface (4 × f32) —, then, with adaptive
//! sampling, the samples each pixel took (u32), then, when the job keeps spectra, the 81 bands
//! of every pixel (f32). All but the last make the tile's image part, the last its spectral part.
//!
//! Every value must be one a tracer can produce: radiometric quantities (X, Y, Z, the adapting
//! white and spectral radiance) finite, not negative and within
//! [`MAX_RADIOMETRIC`](crate::radiometric_bound::MAX_RADIOMETRIC) (why that bound: its module), a
//! coverage between 0 and 1, a mask within its bits, a sample count from 1 to the plan's cap.
//! [`check_tile`] refuses anything else, so a broken or hostile worker cannot put NaN or ∞ into
//! an image.

use crate::radiometric_bound::{MAX_RADIOMETRIC, is_radiometric};
use restauro_scene::plan::{LIT_BITS, Plan, Rect};
use restauro_spectral::grid::BANDS;

#[derive(Debug, thiserror::Error)]
#[error("tile {tile} of {width}×{height} pixels: {problem}")]
pub struct TileDataError {
    pub tile: u32,
    pub width: u32,
    pub height: u32,
    pub problem: String,
}

/// What a job's tiles carry besides XYZ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileLayout {
    /// The 81 bands of every pixel.
    pub spectral: bool,
    /// Each pixel's sky coverage.
    pub sky: bool,
    /// Each pixel's mask of the lights that light it.
    pub lit: bool,
    /// Each pixel's adapting white ([`WHITE_WORDS`] values).
    pub white: bool,
    /// With adaptive sampling, the plan's samples per pixel: each pixel's count of samples
    /// taken, at most this, follows the whites. 0: no counts.
    pub samples_cap: u32,
}

/// The values of a pixel's adapting white: X, Y, Z (Y in cd/m²) and the scotopic luminance.
pub const WHITE_WORDS: usize = 4;

impl From<&Plan> for TileLayout {
    fn from(plan: &Plan) -> Self {
        TileLayout {
            spectral: plan.spectral,
            sky: plan.sky,
            lit: plan.lit,
            white: plan.white,
            samples_cap: if plan.adaptive() { plan.samples_per_pixel } else { 0 },
        }
    }
}

impl TileLayout {
    /// The 4-byte words per pixel of the image part.
    fn image_words(self) -> usize {
        3 + usize::from(self.sky)
            + usize::from(self.lit)
            + WHITE_WORDS * usize::from(self.white)
            + usize::from(self.counts())
    }

    /// Whether tiles carry each pixel's count of samples.
    pub fn counts(self) -> bool {
        self.samples_cap > 0
    }
}

/// The byte sizes of a tile's two parts: the image (XYZ, sky coverage, light masks) and the
/// spectra.
pub fn tile_sizes(rect: &Rect, layout: TileLayout) -> (usize, usize) {
    let pixels = rect.width as usize * rect.height as usize;
    (pixels * layout.image_words() * 4, if layout.spectral { pixels * BANDS * 4 } else { 0 })
}

/// The parts of a tile's bytes, by where they start.
struct Parts {
    sky: usize,
    lit: usize,
    white: usize,
    samples: usize,
    spectral: usize,
    cap: u32,
}

impl Parts {
    fn of(rect: &Rect, layout: TileLayout) -> Self {
        let pixels = rect.width as usize * rect.height as usize;
        let sky = pixels * 12;
        let lit = sky + if layout.sky { pixels * 4 } else { 0 };
        let white = lit + if layout.lit { pixels * 4 } else { 0 };
        let samples = white + if layout.white { pixels * 4 * WHITE_WORDS } else { 0 };
        let spectral = samples + if layout.counts() { pixels * 4 } else { 0 };
        Parts { sky, lit, white, samples, spectral, cap: layout.samples_cap }
    }

    /// The part a byte offset lies in, the pixel, and whether its value is in range.
    fn check(&self, at: usize, word: [u8; 4]) -> (&'static str, usize, bool) {
        let v = f32::from_le_bytes(word);
        let radiometric = is_radiometric(v);
        match at {
            a if a < self.sky => ("XYZ", a / 12, radiometric),
            a if a < self.lit => ("sky coverage", (a - self.sky) / 4, (0.0..=1.0).contains(&v)),
            a if a < self.white => {
                ("light mask", (a - self.lit) / 4, u32::from_le_bytes(word) >> LIT_BITS == 0)
            }
            a if a < self.samples => ("adapting white", (a - self.white) / 16, radiometric),
            a if a < self.spectral => {
                let n = u32::from_le_bytes(word);
                ("sample count", (a - self.samples) / 4, (1..=self.cap).contains(&n))
            }
            a => ("spectral radiance", (a - self.spectral) / (BANDS * 4), radiometric),
        }
    }
}

/// Checks a tile's wire bytes: the size its rectangle and layout give, and every value in range.
pub fn check_tile(
    index: u32,
    rect: &Rect,
    layout: TileLayout,
    data: &[u8],
) -> Result<(), TileDataError> {
    let refuse = |problem: String| TileDataError {
        tile: index,
        width: rect.width,
        height: rect.height,
        problem,
    };
    let (image_bytes, spectral_bytes) = tile_sizes(rect, layout);
    if data.len() != image_bytes + spectral_bytes {
        return Err(refuse(format!(
            "{} bytes of pixel data, expected {}",
            data.len(),
            image_bytes + spectral_bytes
        )));
    }
    let parts = Parts::of(rect, layout);
    for (i, word) in data.chunks_exact(4).enumerate() {
        let word = [word[0], word[1], word[2], word[3]];
        let (what, pixel, in_range) = parts.check(4 * i, word);
        if !in_range {
            let (value, expected) = match what {
                "sky coverage" => (f32::from_le_bytes(word).to_string(), "0 to 1".to_owned()),
                "light mask" => (
                    format!("{:#x}", u32::from_le_bytes(word)),
                    "a mask of at most 24 lights".to_owned(),
                ),
                "sample count" => (
                    u32::from_le_bytes(word).to_string(),
                    format!("1 to {} (the plan's samples per pixel)", layout.samples_cap),
                ),
                _ => (
                    f32::from_le_bytes(word).to_string(),
                    format!("finite, ≥ 0 and at most {MAX_RADIOMETRIC:e}"),
                ),
            };
            return Err(refuse(format!(
                "pixel {pixel} has {what} {value}, which must be {expected}"
            )));
        }
    }
    Ok(())
}

/// Absolute XYZ (Y in cd/m²) of every pixel, and the spectral radiance band by band when kept.
pub struct Framebuffer {
    pub width: u32,
    pub height: u32,
    pub xyz: Vec<[f32; 3]>,
    /// One plane per band, each `width × height`.
    pub spectral: Option<Vec<Vec<f32>>>,
    /// The fraction of each pixel's camera samples that saw the sky, when the scene has one.
    pub sky: Option<Vec<f32>>,
    /// Which lights light each pixel, when the scene has point or distant lights.
    pub lit_by: Option<Vec<u32>>,
    /// Each pixel's adapting white (X, Y, Z, scotopic luminance), for an image.
    pub white: Option<Vec<[f32; 4]>>,
    /// With adaptive sampling, the samples each pixel took, and the cap.
    pub samples: Option<Vec<u32>>,
    samples_cap: u32,
}

impl Framebuffer {
    pub fn new(width: u32, height: u32, layout: TileLayout) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            xyz: vec![[0.0; 3]; n],
            spectral: layout.spectral.then(|| vec![vec![0.0; n]; BANDS]),
            sky: layout.sky.then(|| vec![0.0; n]),
            lit_by: layout.lit.then(|| vec![0; n]),
            white: layout.white.then(|| vec![[0.0; 4]; n]),
            samples: layout.counts().then(|| vec![0; n]),
            samples_cap: layout.samples_cap,
        }
    }

    pub fn layout(&self) -> TileLayout {
        TileLayout {
            spectral: self.spectral.is_some(),
            sky: self.sky.is_some(),
            lit: self.lit_by.is_some(),
            white: self.white.is_some(),
            samples_cap: self.samples_cap,
        }
    }

    /// Places tile `index` at `rect` from its wire bytes, refusing data of the wrong size.
    pub fn place(&mut self, index: u32, rect: &Rect, data: &[u8]) -> Result<(), TileDataError> {
        let layout = self.layout();
        check_tile(index, rect, layout, data)?;
        if rect.x + rect.width > self.width || rect.y + rect.height > self.height {
            return Err(TileDataError {
                tile: index,
                width: rect.width,
                height: rect.height,
                problem: format!("lies outside the {}×{} image", self.width, self.height),
            });
        }
        let words = |bytes: &[u8]| -> Vec<[u8; 4]> {
            bytes.chunks_exact(4).map(|b| [b[0], b[1], b[2], b[3]]).collect()
        };
        let floats = |bytes: &[u8]| -> Vec<f32> {
            words(bytes).into_iter().map(f32::from_le_bytes).collect()
        };
        let parts = Parts::of(rect, layout);
        let xyz = floats(&data[..parts.sky]);
        let w = rect.width as usize;
        for (i, p) in xyz.chunks_exact(3).enumerate() {
            self.xyz[at(self.width, rect, i, w)] = [p[0], p[1], p[2]];
        }
        if let Some(sky) = &mut self.sky {
            for (i, c) in floats(&data[parts.sky..parts.lit]).into_iter().enumerate() {
                sky[at(self.width, rect, i, w)] = c;
            }
        }
        if let Some(lit) = &mut self.lit_by {
            for (i, word) in words(&data[parts.lit..parts.white]).into_iter().enumerate() {
                lit[at(self.width, rect, i, w)] = u32::from_le_bytes(word);
            }
        }
        if let Some(white) = &mut self.white {
            let values = floats(&data[parts.white..parts.samples]);
            for (i, v) in values.chunks_exact(WHITE_WORDS).enumerate() {
                white[at(self.width, rect, i, w)] = [v[0], v[1], v[2], v[3]];
            }
        }
        if let Some(samples) = &mut self.samples {
            for (i, word) in words(&data[parts.samples..parts.spectral]).into_iter().enumerate() {
                samples[at(self.width, rect, i, w)] = u32::from_le_bytes(word);
            }
        }
        if let Some(planes) = &mut self.spectral {
            for (i, bands) in floats(&data[parts.spectral..]).chunks_exact(BANDS).enumerate() {
                let a = at(self.width, rect, i, w);
                for (plane, &v) in planes.iter_mut().zip(bands) {
                    plane[a] = v;
                }
            }
        }
        Ok(())
    }
}

/// The image index of pixel `i` (row-major) of a tile `w` pixels wide at `rect`.
fn at(image_width: u32, rect: &Rect, i: usize, w: usize) -> usize {
    (rect.y as usize + i / w) * image_width as usize + rect.x as usize + i % w
}

/// A tile's per-pixel data besides XYZ and spectra, as rendered.
#[derive(Clone, Copy, Default)]
pub struct TileExtras<'a> {
    pub sky: Option<&'a [f32]>,
    pub lit_by: Option<&'a [u32]>,
    pub white: Option<&'a [[f32; 4]]>,
    /// With adaptive sampling, the samples each pixel took.
    pub samples: Option<&'a [u32]>,
}

/// The wire bytes of a tile: XYZ, the sky coverage, light masks and adapting whites when given,
/// then the spectra when given (each pixel's 81 bands).
pub fn encode_tile<'a>(
    xyz: &[[f32; 3]],
    extras: TileExtras<'_>,
    spectral: Option<impl Iterator<Item = &'a [f32]>>,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(xyz.len() * 20);
    for v in xyz.iter().flatten().chain(extras.sky.into_iter().flatten()) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in extras.lit_by.into_iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in extras.white.into_iter().flatten().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in extras.samples.into_iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    if let Some(pixels) = spectral {
        for bands in pixels {
            for v in bands {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: TileLayout =
        TileLayout { spectral: true, sky: true, lit: true, white: true, samples_cap: 0 };

    #[test]
    fn tiles_land_where_their_rectangle_says() {
        let mut fb = Framebuffer::new(5, 4, ALL);
        let rect = Rect { x: 3, y: 1, width: 2, height: 3 };
        let xyz: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 10.0 + i as f32, 20.0]).collect();
        let sky: Vec<f32> = (0..6).map(|i| i as f32 / 8.0).collect();
        let lit: Vec<u32> = (0..6).map(|i| i % 3).collect();
        let white: Vec<[f32; 4]> = (0..6).map(|i| [i as f32, 1.0, 2.0, 3.0]).collect();
        let spectra: Vec<Vec<f32>> = (0..6).map(|i| vec![i as f32 * 0.5; BANDS]).collect();
        let extras =
            TileExtras { sky: Some(&sky), lit_by: Some(&lit), white: Some(&white), samples: None };
        let data = encode_tile(&xyz, extras, Some(spectra.iter().map(Vec::as_slice)));
        fb.place(7, &rect, &data).unwrap();
        // Pixel 3 of the 2-wide tile is its second row, second column: image (4, 2).
        assert_eq!(fb.xyz[2 * 5 + 4], [3.0, 13.0, 20.0]);
        assert_eq!(fb.sky.as_ref().unwrap()[2 * 5 + 4], 3.0 / 8.0);
        assert_eq!(fb.lit_by.as_ref().unwrap()[2 * 5 + 4], 0);
        assert_eq!(fb.lit_by.as_ref().unwrap()[2 * 5 + 3], 2);
        assert_eq!(fb.white.as_ref().unwrap()[2 * 5 + 4], [3.0, 1.0, 2.0, 3.0]);
        assert_eq!(fb.spectral.as_ref().unwrap()[40][2 * 5 + 4], 1.5);
        assert_eq!(fb.xyz[0], [0.0; 3]);
        let err = fb.place(7, &rect, &data[..data.len() - 4]).unwrap_err();
        assert!(err.to_string().contains("expected"), "{err}");
        let outside = Rect { x: 4, y: 1, width: 2, height: 3 };
        assert!(fb.place(8, &outside, &data).is_err());
    }

    /// NaN, ∞, negative radiance and radiance above the bound, a coverage outside 0–1 and a
    /// mask of lights the renderer cannot name are refused wherever they sit.
    #[test]
    fn values_a_tracer_cannot_produce_are_refused() {
        let rect = Rect { x: 0, y: 0, width: 2, height: 2 };
        let xyz = vec![[1.0f32, 2.0, 3.0]; 4];
        let sky = vec![0.5f32; 4];
        let lit = vec![1u32 << 23; 4];
        let white = vec![[2.0f32, 2.1, 2.2, 4.0]; 4];
        let spectra = vec![vec![0.25f32; BANDS]; 4];
        let extras =
            TileExtras { sky: Some(&sky), lit_by: Some(&lit), white: Some(&white), samples: None };
        let good = encode_tile(&xyz, extras, Some(spectra.iter().map(Vec::as_slice)));
        check_tile(0, &rect, ALL, &good).unwrap();
        let image_bytes = 4 * 36;
        for (at, bad, what) in [
            (4, f32::NAN.to_le_bytes(), "XYZ"),
            (40, f32::INFINITY.to_le_bytes(), "XYZ"),
            (0, (-1.0f32).to_le_bytes(), "XYZ"),
            (
                8,
                3.4e38f32.to_le_bytes(),
                "pixel 0 has XYZ 340000000000000000000000000000000000000, which must be finite, ≥ 0 and at most 1e30",
            ),
            (80 + 4, 2e30f32.to_le_bytes(), "pixel 0 has adapting white"),
            (image_bytes + 4, 1.1e30f32.to_le_bytes(), "spectral radiance"),
            (48 + 4, 1.5f32.to_le_bytes(), "sky coverage"),
            (64 + 8, (1u32 << 24).to_le_bytes(), "light mask"),
            (80 + 16 + 12, f32::NAN.to_le_bytes(), "pixel 1 has adapting white"),
            (80 + 4, (-1.0f32).to_le_bytes(), "pixel 0 has adapting white"),
            (image_bytes + 81 * 4 * 3 + 8, f32::NAN.to_le_bytes(), "spectral radiance"),
            (image_bytes, (-0.5f32).to_le_bytes(), "spectral radiance"),
        ] {
            let mut data = good.clone();
            data[at..at + 4].copy_from_slice(&bad);
            let e = check_tile(3, &rect, ALL, &data).unwrap_err().to_string();
            assert!(e.contains(what) && e.starts_with("tile 3"), "{e}");
        }
        // At the bound itself, everywhere: accepted.
        let mut at_bound = good.clone();
        for word in (0..12).chain(20..36).chain(36..36 + 4 * BANDS) {
            at_bound[4 * word..4 * word + 4].copy_from_slice(&MAX_RADIOMETRIC.to_le_bytes());
        }
        check_tile(0, &rect, ALL, &at_bound).unwrap();
        let e = check_tile(3, &rect, ALL, &good[..good.len() - 4]).unwrap_err();
        assert!(e.to_string().contains("expected"), "{e}");
        // Without a sky the masks follow XYZ directly.
        let no_sky = TileLayout { sky: false, ..ALL };
        let data = encode_tile(
            &xyz,
            TileExtras { sky: None, lit_by: Some(&lit), white: Some(&white), samples: None },
            Some(spectra.iter().map(Vec::as_slice)),
        );
        check_tile(0, &rect, no_sky, &data).unwrap();
    }

    /// With adaptive sampling each pixel's count of samples follows the whites, lands where its
    /// rectangle says, and must lie between 1 and the plan's cap.
    #[test]
    fn sample_counts_travel_and_are_checked() {
        let layout = TileLayout { samples_cap: 16, ..ALL };
        let rect = Rect { x: 1, y: 0, width: 2, height: 2 };
        let xyz = vec![[1.0f32, 2.0, 3.0]; 4];
        let sky = vec![0.5f32; 4];
        let lit = vec![1u32; 4];
        let white = vec![[2.0f32, 2.1, 2.2, 4.0]; 4];
        let samples = vec![8u32, 16, 1, 9];
        let spectra: Vec<Vec<f32>> = (0..4).map(|i| vec![i as f32; BANDS]).collect();
        let extras = TileExtras {
            sky: Some(&sky),
            lit_by: Some(&lit),
            white: Some(&white),
            samples: Some(&samples),
        };
        let good = encode_tile(&xyz, extras, Some(spectra.iter().map(Vec::as_slice)));
        assert_eq!(good.len(), 4 * 4 * (3 + 1 + 1 + 4 + 1) + 4 * 4 * BANDS);
        let mut fb = Framebuffer::new(3, 2, layout);
        fb.place(0, &rect, &good).unwrap();
        assert_eq!(fb.samples.as_deref(), Some(&[0, 8, 16, 0, 1, 9][..]));
        assert_eq!(fb.spectral.as_ref().unwrap()[0][5], 3.0, "the spectra follow the counts");
        let counts_at = 4 * 4 * 9;
        for bad in [0u32, 17] {
            let mut data = good.clone();
            data[counts_at + 4..counts_at + 8].copy_from_slice(&bad.to_le_bytes());
            let e = check_tile(2, &rect, layout, &data).unwrap_err().to_string();
            assert!(e.contains(&format!("pixel 1 has sample count {bad}")), "{e}");
            assert!(e.contains("1 to 16 (the plan's samples per pixel)"), "{e}");
        }
        // A layout without counts refuses the longer tile.
        assert!(check_tile(2, &rect, ALL, &good).is_err());
    }
}
