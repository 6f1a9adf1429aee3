//! Photo textures (PNG or JPEG), decoded once at load. restauro never takes a photo for an
//! albedo: a texture only modulates a material's measured reflectance as a relative detail map
//! (`restauro_render::texture`), so it is kept as the file gives it, sRGB-encoded.

use crate::error::{Result, SceneError};
use crate::guard;
use crate::scene_file::PixelRect;
use restauro_spectral::rgb_space::Transfer;
use std::path::Path;

/// The extensions a texture may have.
pub const EXTENSIONS: [&str; 3] = ["png", "jpg", "jpeg"];

/// Why a photo cannot be used: a white-balance patch that does not fit it, or a file that does
/// not decode (each says what to do).
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    #[error(
        "the rectangle of {} × {} pixels at ({}, {}) is not inside the photo's {width} × \
         {height} pixels; give the grey patch's top-left pixel (x from the left, y from the top) \
         and its size",
        patch.width, patch.height, patch.x, patch.y
    )]
    PatchOutside { patch: PixelRect, width: u32, height: u32 },
    #[error("the patch is black in {channel}; choose a grey patch that the light reaches")]
    PatchBlack { channel: &'static str },
    #[error(
        "{width} × {height} texels is more than the {max_pixels} allowed; scale the image down, \
         or raise the limit with --max-pixels"
    )]
    TooManyTexels { width: u64, height: u64, max_pixels: u64 },
    #[error("not a PNG image restauro can read ({0})")]
    NotPng(png::DecodingError),
    #[error("the PNG image is too large to decode")]
    PngTooLarge,
    #[error("not a JPEG image restauro can read ({0:?})")]
    NotJpeg(zune_jpeg::errors::DecodeErrors),
    #[error("the JPEG image has no frame header")]
    NoJpegFrame,
    #[error("the JPEG image decoded to fewer texels than its header gives")]
    JpegShort,
}

/// A decoded image: rows from the top, each texel's sRGB-encoded red, green and blue scaled to
/// 0..=65535 (8-bit files times 257, so both depths share one type).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u16; 3]>,
}

impl Texture {
    /// Texel (x, y), x from the left and y from the top, as linear sRGB in 0..1 (IEC
    /// 61966-2-1's decoding function).
    pub fn linear_rgb(&self, x: u32, y: u32) -> [f32; 3] {
        let t = self.texels[(y * self.width + x) as usize];
        t.map(|c| Transfer::Srgb.decode(f64::from(c) / 65535.0) as f32)
    }

    /// Why `patch` cannot white-balance this photo, in words: it reaches beyond the image, is
    /// empty, or is black in a channel (no gain makes that grey).
    pub fn check_patch(&self, patch: PixelRect) -> std::result::Result<(), TextureError> {
        let PixelRect { x, y, width, height } = patch;
        let inside = u64::from(x) + u64::from(width) <= u64::from(self.width)
            && u64::from(y) + u64::from(height) <= u64::from(self.height);
        if width == 0 || height == 0 || !inside {
            return Err(TextureError::PatchOutside {
                patch,
                width: self.width,
                height: self.height,
            });
        }
        let mean = self.patch_mean(patch);
        if let Some(k) = (0..3).find(|&k| mean[k] <= 1e-4) {
            let channel = ["red", "green", "blue"][k];
            return Err(TextureError::PatchBlack { channel });
        }
        Ok(())
    }

    /// The photo white-balanced on a grey patch (von Kries scaling in linear sRGB, as camera
    /// raw converters balance on a grey card): each channel is scaled so that the patch's mean
    /// becomes a neutral grey of the same luminance (BT.709 weights); a texel pushed beyond
    /// full scale is held there. `patch` must pass [`Texture::check_patch`].
    pub fn white_balanced(&self, patch: PixelRect) -> Texture {
        let mean = self.patch_mean(patch);
        let y = f64::from(luminance(mean.map(|c| c as f32)));
        let gains = mean.map(|c| y / c);
        let texels = self
            .texels
            .iter()
            .map(|t| {
                std::array::from_fn(|k| {
                    let linear = Transfer::Srgb.decode(f64::from(t[k]) / 65535.0) * gains[k];
                    (Transfer::Srgb.encode(linear.min(1.0)) * 65535.0).round() as u16
                })
            })
            .collect();
        Texture { width: self.width, height: self.height, texels }
    }

    /// The patch's mean linear colour.
    fn patch_mean(&self, patch: PixelRect) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for row in patch.y..patch.y + patch.height {
            for col in patch.x..patch.x + patch.width {
                let c = self.linear_rgb(col, row);
                (0..3).for_each(|k| sum[k] += f64::from(c[k]));
            }
        }
        sum.map(|s| s / (f64::from(patch.width) * f64::from(patch.height)))
    }
}

/// Rec. ITU-R BT.709 relative luminance of linear sRGB (the primaries sRGB shares).
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// Decode a texture file by its extension, refusing one of more than `max_pixels` texels
/// before its texels are allocated. Messages name `path`.
pub fn decode(bytes: &[u8], extension: &str, path: &Path, max_pixels: u64) -> Result<Texture> {
    let (format, decoded) = match extension {
        "png" => ("PNG", guard::catch(|| decode_png(bytes, max_pixels))),
        "jpg" | "jpeg" => ("JPEG", guard::catch(|| decode_jpeg(bytes, max_pixels))),
        other => {
            return Err(SceneError::invalid(
                path,
                "texture",
                format!("`.{other}` is not an image restauro reads; use a PNG or JPEG file"),
            ));
        }
    };
    let texture = decoded
        .map_err(|_| SceneError::invalid(path, "texture", guard::gave_up(format)))?
        .map_err(|problem| SceneError::invalid(path, "texture", problem.to_string()))?;
    if texture.width == 0 || texture.height == 0 {
        return Err(SceneError::invalid(path, "texture", "the image has no pixels"));
    }
    Ok(texture)
}

fn too_big(width: u64, height: u64, max_pixels: u64) -> Option<TextureError> {
    (width * height > max_pixels).then_some(TextureError::TooManyTexels {
        width,
        height,
        max_pixels,
    })
}

fn decode_png(bytes: &[u8], max_pixels: u64) -> std::result::Result<Texture, TextureError> {
    let not_png = TextureError::NotPng;
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Palettes and grey levels below 8 bits become 8-bit channels; 16 bits stay 16.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(not_png)?;
    let (width, height) = (reader.info().width, reader.info().height);
    if let Some(problem) = too_big(u64::from(width), u64::from(height), max_pixels) {
        return Err(problem);
    }
    let size = reader.output_buffer_size().ok_or(TextureError::PngTooLarge)?;
    let mut buffer = vec![0; size];
    let frame = reader.next_frame(&mut buffer).map_err(not_png)?;
    let channels = frame.color_type.samples();
    let sixteen = frame.bit_depth == png::BitDepth::Sixteen;
    let bytes_per_texel = channels * if sixteen { 2 } else { 1 };
    let sample = |t: &[u8], k: usize| -> u16 {
        if sixteen { u16::from_be_bytes([t[2 * k], t[2 * k + 1]]) } else { u16::from(t[k]) * 257 }
    };
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for row in buffer[..frame.buffer_size()].chunks_exact(frame.line_size) {
        for t in row.chunks_exact(bytes_per_texel).take(width as usize) {
            // Grey (with or without alpha) is the same in every channel; alpha is dropped.
            texels.push(if channels < 3 {
                [sample(t, 0); 3]
            } else {
                std::array::from_fn(|k| sample(t, k))
            });
        }
    }
    Ok(Texture { width, height, texels })
}

fn decode_jpeg(bytes: &[u8], max_pixels: u64) -> std::result::Result<Texture, TextureError> {
    use zune_core::bytestream::ZCursor;
    use zune_core::colorspace::ColorSpace;
    use zune_core::options::DecoderOptions;
    let not_jpeg = TextureError::NotJpeg;
    let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGB);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder.decode_headers().map_err(not_jpeg)?;
    let info = decoder.info().ok_or(TextureError::NoJpegFrame)?;
    let (width, height) = (u32::from(info.width), u32::from(info.height));
    if let Some(problem) = too_big(u64::from(width), u64::from(height), max_pixels) {
        return Err(problem);
    }
    let rgb = decoder.decode().map_err(not_jpeg)?;
    if rgb.len() != width as usize * height as usize * 3 {
        return Err(TextureError::JpegShort);
    }
    let texels =
        rgb.chunks_exact(3).map(|t| [t[0], t[1], t[2]].map(|c| u16::from(c) * 257)).collect();
    Ok(Texture { width, height, texels })
}
