//! Images as a display shows them, for the contact sheets: an XYZ image (or a part of it)
//! encoded as 8-bit sRGB with an exposure, and a CIEDE2000 map in its colour scale.

use crate::scenes::samples::PixelRect;
use crate::sheet::Rgb8;
use restauro_image::delta_e::{DeltaEMap, map_rgb};
use restauro_image::image_files::XyzImage;
use restauro_spectral::display::{DisplayParams, Exposure, encode, to_u8};
use restauro_spectral::rgb_space::RgbSpace;

/// The map as an image: viridis up to `scale_max`, light sources grey.
pub fn map_picture(map: &DeltaEMap, width: usize, height: usize, scale_max: f64) -> Rgb8 {
    Rgb8 { width: width as u32, height: height as u32, data: map_rgb(map, scale_max) }
}

/// An image as the display shows it (sRGB, 8 bits) with `exposure`.
pub fn picture(image: &XyzImage, exposure: Exposure) -> Rgb8 {
    let encoded = encode(&image.pixels, &DisplayParams { space: RgbSpace::Srgb, exposure });
    Rgb8 { width: image.width as u32, height: image.height as u32, data: to_u8(&encoded) }
}

/// The sRGB picture of the pixels of `r`.
pub fn crop_picture(image: &XyzImage, r: PixelRect, exposure: Exposure) -> Rgb8 {
    let mut pixels = Vec::new();
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            pixels.push(image.pixels[y as usize * image.width + x as usize]);
        }
    }
    let cropped = XyzImage {
        width: (r.x1 - r.x0) as usize,
        height: (r.y1 - r.y0) as usize,
        pixels,
        emitter: None,
        lit_by: None,
        white: None,
    };
    picture(&cropped, exposure)
}
