//! The image a job assembles from its tiles, and the wire form of one tile's pixels.
//!
//! A tile travels and is stored as little-endian f32: first X, Y, Z of every pixel (row-major
//! within the tile), then, when the scene has a sky, each pixel's sky coverage (the fraction of
//! its camera samples that saw the sky), then, when the job keeps spectra, the 81 bands of every
//! pixel. The first two make the tile's image part, the last its spectral part.
//!
//! Every value must be a radiometric quantity a tracer can produce: finite and not negative
//! (X, Y, Z and spectral radiance), and a coverage between 0 and 1. [`check_tile`] refuses
//! anything else, so a broken or hostile worker cannot put NaN or ∞ into an image.

use restauro_scene::plan::Rect;
use restauro_spectral::grid::BANDS;

#[derive(Debug, thiserror::Error)]
#[error("tile {tile} of {width}×{height} pixels: {problem}")]
pub struct TileDataError {
    pub tile: u32,
    pub width: u32,
    pub height: u32,
    pub problem: String,
}

/// The byte sizes of a tile's two parts: the image (XYZ, and sky coverage when `sky`) and the
/// spectra.
pub fn tile_sizes(rect: &Rect, spectral: bool, sky: bool) -> (usize, usize) {
    let pixels = rect.width as usize * rect.height as usize;
    (pixels * (3 + usize::from(sky)) * 4, if spectral { pixels * BANDS * 4 } else { 0 })
}

/// Checks a tile's wire bytes: the size its rectangle and layout give, and every value in range.
pub fn check_tile(
    index: u32,
    rect: &Rect,
    spectral: bool,
    sky: bool,
    data: &[u8],
) -> Result<(), TileDataError> {
    let refuse = |problem: String| TileDataError {
        tile: index,
        width: rect.width,
        height: rect.height,
        problem,
    };
    let (image_bytes, spectral_bytes) = tile_sizes(rect, spectral, sky);
    if data.len() != image_bytes + spectral_bytes {
        return Err(refuse(format!(
            "{} bytes of pixel data, expected {}",
            data.len(),
            image_bytes + spectral_bytes
        )));
    }
    let xyz_bytes = rect.width as usize * rect.height as usize * 12;
    let value =
        |at: usize| f32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]);
    let part = |at: usize| match at {
        a if a < xyz_bytes => ("XYZ", a / 12),
        a if a < image_bytes => ("sky coverage", (a - xyz_bytes) / 4),
        a => ("spectral radiance", (a - image_bytes) / (BANDS * 4)),
    };
    for at in (0..data.len()).step_by(4) {
        let v = value(at);
        let in_range = if (xyz_bytes..image_bytes).contains(&at) {
            (0.0..=1.0).contains(&v)
        } else {
            v.is_finite() && v >= 0.0
        };
        if !in_range {
            let (what, pixel) = part(at);
            let expected = if what == "sky coverage" { "0 to 1" } else { "finite and ≥ 0" };
            return Err(refuse(format!("pixel {pixel} has {what} {v}, which must be {expected}")));
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
}

impl Framebuffer {
    pub fn new(width: u32, height: u32, spectral: bool, sky: bool) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            xyz: vec![[0.0; 3]; n],
            spectral: spectral.then(|| vec![vec![0.0; n]; BANDS]),
            sky: sky.then(|| vec![0.0; n]),
        }
    }

    /// Places tile `index` at `rect` from its wire bytes, refusing data of the wrong size.
    pub fn place(&mut self, index: u32, rect: &Rect, data: &[u8]) -> Result<(), TileDataError> {
        let (xyz_bytes, _) = tile_sizes(rect, self.spectral.is_some(), self.sky.is_some());
        check_tile(index, rect, self.spectral.is_some(), self.sky.is_some(), data)?;
        if rect.x + rect.width > self.width || rect.y + rect.height > self.height {
            return Err(TileDataError {
                tile: index,
                width: rect.width,
                height: rect.height,
                problem: format!("lies outside the {}×{} image", self.width, self.height),
            });
        }
        let floats = |bytes: &[u8]| -> Vec<f32> {
            bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
        };
        let pixels = rect.width as usize * rect.height as usize;
        let xyz = floats(&data[..pixels * 12]);
        let coverage = floats(&data[pixels * 12..xyz_bytes]);
        let spectral = floats(&data[xyz_bytes..]);
        let w = rect.width as usize;
        for (i, p) in xyz.chunks_exact(3).enumerate() {
            self.xyz[at(self.width, rect, i, w)] = [p[0], p[1], p[2]];
        }
        if let Some(sky) = &mut self.sky {
            for (i, &c) in coverage.iter().enumerate() {
                sky[at(self.width, rect, i, w)] = c;
            }
        }
        if let Some(planes) = &mut self.spectral {
            for (i, bands) in spectral.chunks_exact(BANDS).enumerate() {
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

/// The wire bytes of a tile: XYZ, the sky coverage when given, then the spectra when given
/// (each pixel's 81 bands).
pub fn encode_tile<'a>(
    xyz: &[[f32; 3]],
    sky: Option<&[f32]>,
    spectral: Option<impl Iterator<Item = &'a [f32]>>,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(xyz.len() * 16);
    for v in xyz.iter().flatten().chain(sky.into_iter().flatten()) {
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

    #[test]
    fn tiles_land_where_their_rectangle_says() {
        let mut fb = Framebuffer::new(5, 4, true, true);
        let rect = Rect { x: 3, y: 1, width: 2, height: 3 };
        let xyz: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 10.0 + i as f32, 20.0]).collect();
        let sky: Vec<f32> = (0..6).map(|i| i as f32 / 8.0).collect();
        let spectra: Vec<Vec<f32>> = (0..6).map(|i| vec![i as f32 * 0.5; BANDS]).collect();
        let data = encode_tile(&xyz, Some(&sky), Some(spectra.iter().map(Vec::as_slice)));
        fb.place(7, &rect, &data).unwrap();
        // Pixel 3 of the 2-wide tile is its second row, second column: image (4, 2).
        assert_eq!(fb.xyz[2 * 5 + 4], [3.0, 13.0, 20.0]);
        assert_eq!(fb.sky.as_ref().unwrap()[2 * 5 + 4], 3.0 / 8.0);
        assert_eq!(fb.spectral.as_ref().unwrap()[40][2 * 5 + 4], 1.5);
        assert_eq!(fb.xyz[0], [0.0; 3]);
        let err = fb.place(7, &rect, &data[..data.len() - 4]).unwrap_err();
        assert!(err.to_string().contains("expected"), "{err}");
        let outside = Rect { x: 4, y: 1, width: 2, height: 3 };
        assert!(fb.place(8, &outside, &data).is_err());
    }

    /// NaN, ∞ and negative radiance, and a coverage outside 0–1, are refused wherever they sit.
    #[test]
    fn values_a_tracer_cannot_produce_are_refused() {
        let rect = Rect { x: 0, y: 0, width: 2, height: 2 };
        let xyz = vec![[1.0f32, 2.0, 3.0]; 4];
        let sky = vec![0.5f32; 4];
        let spectra = vec![vec![0.25f32; BANDS]; 4];
        let good = encode_tile(&xyz, Some(&sky), Some(spectra.iter().map(Vec::as_slice)));
        check_tile(0, &rect, true, true, &good).unwrap();
        let image_bytes = 4 * 16;
        for (at, bad, what) in [
            (4, f32::NAN, "XYZ"),
            (40, f32::INFINITY, "XYZ"),
            (0, -1.0, "XYZ"),
            (48 + 4, 1.5, "sky coverage"),
            (image_bytes + 81 * 4 * 3 + 8, f32::NAN, "spectral radiance"),
            (image_bytes, -0.5, "spectral radiance"),
        ] {
            let mut data = good.clone();
            data[at..at + 4].copy_from_slice(&bad.to_le_bytes());
            let e = check_tile(3, &rect, true, true, &data).unwrap_err().to_string();
            assert!(e.contains(what) && e.starts_with("tile 3"), "{e}");
        }
        let e = check_tile(3, &rect, true, true, &good[..good.len() - 4]).unwrap_err();
        assert!(e.to_string().contains("expected"), "{e}");
    }
}
