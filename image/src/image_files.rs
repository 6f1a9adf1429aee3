//! Image files in and out: OpenEXR (any XYZ or RGB image in; X, Y, Z with RGB preview and
//! optional spectral layers out) and PNG (8 or 16 bits, tagged with its colour space). Every
//! file is written whole or not at all ([`crate::atomic_file`]).

use crate::atomic_file;
use crate::error::ImageError;
use crate::radiometric_bound::is_colour_value;
use exr::prelude::*;
use restauro_spectral::colorimetry::Chromaticity;
use restauro_spectral::rgb_space::RgbSpace;
use std::io;
use std::path::Path;

/// Images larger than this are refused before their pixels are read (16384 × 16384).
pub const MAX_PIXELS: usize = 1 << 28;

/// Also refused before the pixels are read: more samples (pixels × channels) than this, 8 GiB
/// of 32-bit values. A header costs a few bytes to write and says how much memory the reader
/// must reserve, so it is checked first (restauro's own spectral images, 88 channels, stay under
/// it up to about 4900 × 4900 pixels).
pub const MAX_SAMPLES: usize = 1 << 31;

/// An error of the exr crate in plain words, with what to do.
fn exr_problem(error: &exr::error::Error) -> String {
    use exr::error::Error;
    match error {
        Error::Io(e) if e.kind() == io::ErrorKind::UnexpectedEof => {
            "the file ends early (it is truncated); copy or export it again".into()
        }
        Error::Io(e) => restauro_scene::error::io_problem(e),
        Error::Invalid(what) => format!(
            "the file is damaged or not OpenEXR ({what}); check that it is the right file, or \
             export it again"
        ),
        Error::NotSupported(what) => format!(
            "it uses an OpenEXR feature restauro cannot read ({what}); save it again as a \
             scanline or tiled image with ZIP, PIZ, RLE or no compression"
        ),
        Error::Aborted => "reading was cancelled".into(),
    }
}

type Result<T, E = ImageError> = std::result::Result<T, E>;

/// A linear image as CIE XYZ (any scale: absolute cd/m² from the renderer, relative otherwise).
#[derive(Clone, Debug, PartialEq)]
pub struct XyzImage {
    pub width: usize,
    pub height: usize,
    /// Row-major.
    pub pixels: Vec<[f32; 3]>,
    /// Pixels marked as light sources (a channel named `emitter`, nonzero for emitters).
    pub emitter: Option<Vec<bool>>,
    /// Which of the scene's lights light each pixel (a channel named `lit_by`: bit k for light k,
    /// the sky not counted, as an integer below 2²⁴ so that f32 holds it exactly). Pixels with
    /// the same mask are the Retinex's frameworks of illumination.
    pub lit_by: Option<Vec<u32>>,
    /// Each pixel's adapting white, as restauro's renders record it (channels `white.X`,
    /// `white.Y`, `white.Z` and `white.scotopic`): X, Y, Z (Y in cd/m²) and the scotopic
    /// luminance of a perfect white diffuser at the pixel's surface, zero where the pixel
    /// shows no surface. What the seen image adapts to.
    pub white: Option<Vec<[f32; 4]>>,
}

/// The EXR channels of the adapting white, in the order of [`XyzImage::white`]'s values.
pub const WHITE_CHANNELS: [&str; 4] = ["white.X", "white.Y", "white.Z", "white.scotopic"];

impl XyzImage {
    /// An image without light-source or light masks.
    pub fn new(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> Self {
        XyzImage { width, height, pixels, emitter: None, lit_by: None, white: None }
    }
}

/// Read an OpenEXR file as XYZ. Channels X, Y, Z are taken as they are; otherwise R, G, B are
/// converted with the file's `chromaticities` attribute (Rec. 709 primaries and D65, the
/// OpenEXR default, when it has none).
pub fn read_exr(path: &Path, max_pixels: usize) -> Result<XyzImage> {
    use std::io::{Seek, SeekFrom};
    let mut reader = io::BufReader::new(open_regular_file(path)?);
    // The header first, so that an enormous image is refused before it is allocated.
    let meta = guarded(path, || exr::meta::MetaData::read_from_buffered(&mut reader, false))?;
    check_size(path, &meta.headers, max_pixels)?;
    reader
        .seek(SeekFrom::Start(0))
        .map_err(|error| ImageError::Io { path: path.to_owned(), error })?;
    let image = guarded(path, || {
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(reader)
    })?;
    let (width, height) = (image.layer_data.size.width(), image.layer_data.size.height());
    let list = &image.layer_data.channel_data.list;
    let channels =
        Channels { path, width, names: list.iter().map(|c| c.name.to_string()).collect(), list };
    let pixels = channels.xyz(height, image.attributes.chromaticities)?;
    let (emitter, lit_by) = (channels.emitter(), channels.lit_by());
    let white = channels.white(height)?;
    Ok(XyzImage { width, height, pixels, emitter, lit_by, white })
}

/// The file at `path`, opened only if it is a regular file: a FIFO would block the open
/// itself, and a device never end.
fn open_regular_file(path: &Path) -> Result<std::fs::File> {
    let io_err = |error| ImageError::Io { path: path.to_owned(), error };
    let not_a_file = || ImageError::NotAFile { path: path.to_owned() };
    if !std::fs::metadata(path).map_err(io_err)?.is_file() {
        return Err(not_a_file());
    }
    let file = std::fs::File::open(path).map_err(io_err)?;
    if !file.metadata().map_err(io_err)?.is_file() {
        return Err(not_a_file());
    }
    Ok(file)
}

/// What the exr crate reads with `read`, its panic and its error each worded as a refusal of
/// the file. The exr crate is fed hostile files too: it runs inside the panic guard, on this
/// thread (`non_parallel`, so that a panic cannot happen on a worker thread outside the guard).
fn guarded<T>(
    path: &Path,
    read: impl FnOnce() -> std::result::Result<T, exr::error::Error>,
) -> Result<T> {
    restauro_scene::guard::catch(read)
        .map_err(|_| ImageError::Exr {
            path: path.to_owned(),
            problem: restauro_scene::guard::gave_up("OpenEXR"),
        })?
        .map_err(|e| ImageError::Exr { path: path.to_owned(), problem: exr_problem(&e) })
}

/// Refuses a file any of whose layers has more than `max_pixels` pixels or [`MAX_SAMPLES`]
/// samples, from its headers alone.
fn check_size(path: &Path, headers: &[exr::meta::header::Header], max_pixels: usize) -> Result<()> {
    for header in headers {
        let (width, height) = (header.layer_size.width(), header.layer_size.height());
        let pixels = width.checked_mul(height);
        if pixels.is_none_or(|n| n > max_pixels) {
            return Err(ImageError::TooLarge {
                path: path.to_owned(),
                width,
                height,
                max: max_pixels,
            });
        }
        let channels = header.channels.list.len();
        if pixels.and_then(|n| n.checked_mul(channels)).is_none_or(|n| n > MAX_SAMPLES) {
            return Err(ImageError::TooManySamples {
                path: path.to_owned(),
                width,
                height,
                channels,
                max: MAX_SAMPLES,
            });
        }
    }
    Ok(())
}

/// The channels of a layer read, by name.
struct Channels<'a> {
    path: &'a Path,
    width: usize,
    names: Vec<String>,
    list: &'a [AnyChannel<FlatSamples>],
}

impl Channels<'_> {
    fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Channel `i`'s values, refused at the first that is no colour value.
    fn values(&self, i: usize) -> Result<Vec<f32>> {
        let v: Vec<f32> = self.list[i].sample_data.values_as_f32().collect();
        if let Some(bad) = v.iter().position(|&x| !is_colour_value(x)) {
            return Err(ImageError::OutOfRange {
                path: self.path.to_owned(),
                channel: self.names[i].clone(),
                x: bad % self.width,
                y: bad / self.width,
                value: v[bad],
            });
        }
        Ok(v)
    }

    /// The pixels as XYZ: X, Y, Z as they are, else R, G, B by the primaries and white of
    /// `chromaticities` (Rec. 709 and D65 without).
    fn xyz(
        &self,
        height: usize,
        chromaticities: Option<exr::meta::attribute::Chromaticities>,
    ) -> Result<Vec<[f32; 3]>> {
        let find = |name| self.find(name);
        let (planes, to_xyz) = if let (Some(x), Some(y), Some(z)) =
            (find("X"), find("Y"), find("Z"))
        {
            ([self.values(x)?, self.values(y)?, self.values(z)?], None)
        } else if let (Some(r), Some(g), Some(b)) = (find("R"), find("G"), find("B")) {
            let m = match chromaticities {
                Some(c) => {
                    let xy =
                        |v: exr::math::Vec2<f32>| Chromaticity::new(f64::from(v.0), f64::from(v.1));
                    rgb_to_xyz_matrix([xy(c.red), xy(c.green), xy(c.blue)], xy(c.white))
                }
                None => RgbSpace::Srgb.rgb_to_xyz().transpose().to_cols_array_2d(),
            };
            ([self.values(r)?, self.values(g)?, self.values(b)?], Some(m))
        } else {
            return Err(ImageError::NoColourChannels {
                path: self.path.to_owned(),
                channels: self.names.clone(),
            });
        };
        let pixels = (0..self.width * height)
            .map(|i| {
                let p = [planes[0][i], planes[1][i], planes[2][i]];
                match &to_xyz {
                    None => p,
                    Some(m) => std::array::from_fn(|r| {
                        (m[r][0] * f64::from(p[0])
                            + m[r][1] * f64::from(p[1])
                            + m[r][2] * f64::from(p[2])) as f32
                    }),
                }
            })
            .collect();
        Ok(pixels)
    }

    /// The `emitter` mask: nonzero for light sources.
    fn emitter(&self) -> Option<Vec<bool>> {
        let i = self.find("emitter")?;
        Some(self.list[i].sample_data.values_as_f32().map(|v| v != 0.0).collect())
    }

    /// The `lit_by` masks. A mask is a whole number below 2²⁴; anything else (NaN, negative, a
    /// fraction from a resampling tool) is no mask, and its pixel is put with the unlit ones.
    fn lit_by(&self) -> Option<Vec<u32>> {
        let i = self.find("lit_by")?;
        let mask = |v: f32| {
            if v.fract() == 0.0 && (0.0..16_777_216.0).contains(&v) { v as u32 } else { 0 }
        };
        Some(self.list[i].sample_data.values_as_f32().map(mask).collect())
    }

    /// The adapting white, when all of [`WHITE_CHANNELS`] are there.
    fn white(&self, height: usize) -> Result<Option<Vec<[f32; 4]>>> {
        let [Some(x), Some(y), Some(z), Some(s)] = WHITE_CHANNELS.map(|n| self.find(n)) else {
            return Ok(None);
        };
        let planes = [self.values(x)?, self.values(y)?, self.values(z)?, self.values(s)?];
        Ok(Some((0..self.width * height).map(|i| planes.each_ref().map(|p| p[i])).collect()))
    }
}

/// The RGB → XYZ matrix (rows) of arbitrary primaries and white, as restauro's display spaces
/// compute theirs (SMPTE RP 177).
fn rgb_to_xyz_matrix(primaries: [Chromaticity; 3], white: Chromaticity) -> [[f64; 3]; 3] {
    use glam::{DMat3, DVec3};
    let col = |c: Chromaticity| {
        let v = c.to_xyz(1.0);
        DVec3::new(v.x, v.y, v.z)
    };
    let m = DMat3::from_cols(col(primaries[0]), col(primaries[1]), col(primaries[2]));
    let w = col(white);
    let s = m.inverse() * w;
    DMat3::from_cols(m.x_axis * s.x, m.y_axis * s.y, m.z_axis * s.z).transpose().to_cols_array_2d()
}

/// Write an OpenEXR file of named f32 channels (each row-major, `width` × `height`) with string
/// attributes, losslessly compressed.
pub fn write_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
    attributes: &[(&str, &str)],
) -> Result<()> {
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|(name, values)| AnyChannel::new(name.as_str(), FlatSamples::F32(values)))
        .collect();
    let mut attrs = LayerAttributes::default();
    for (k, v) in attributes {
        attrs.other.insert(Text::from(*k), AttributeValue::Text(Text::from(*v)));
    }
    let layer = Layer::new(
        (width, height),
        attrs,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(list)),
    );
    let image = Image::from_layer(layer);
    atomic_file::write_with(path, |w| {
        let mut buffer = io::Cursor::new(Vec::new());
        image.write().to_buffered(&mut buffer).map_err(io::Error::other)?;
        let mut bytes = buffer.into_inner();
        sort_header_attributes(&mut bytes);
        io::Write::write_all(w, &bytes)
    })
    .map_err(|error| ImageError::Io { path: path.to_owned(), error })
}

/// Puts the attributes of a single-part OpenEXR header in name order. The exr crate keeps them
/// in a `HashMap`, whose order differs from one map to the next, so the same image would be
/// written as different bytes by different processes; OpenEXR readers take attributes in any
/// order. The header keeps its length, so the offset table after it stays valid. Files it does
/// not recognise (multi-part, malformed) are left as they are.
fn sort_header_attributes(bytes: &mut [u8]) {
    // OpenEXR 2.0 §"File Layout": magic (4 bytes), version and flags (4), then attributes
    // `name\0 type\0 size:i32 value[size]`, ended by a null byte.
    const MULTIPART: u32 = 0x1000;
    let Some(version) = bytes.get(4..8).and_then(|v| v.try_into().ok()).map(u32::from_le_bytes)
    else {
        return;
    };
    if version & MULTIPART != 0 {
        return;
    }
    let start = 8;
    let mut at = start;
    let mut attributes: Vec<std::ops::Range<usize>> = Vec::new();
    let null_after =
        |from: usize| bytes.get(from..)?.iter().position(|&b| b == 0).map(|i| from + i);
    loop {
        match bytes.get(at) {
            Some(0) => break,
            Some(_) => {}
            None => return,
        }
        let Some(name_end) = null_after(at) else { return };
        let Some(type_end) = null_after(name_end + 1) else { return };
        let Some(size) = bytes
            .get(type_end + 1..type_end + 5)
            .map(|s| i32::from_le_bytes(s.try_into().expect("four bytes")))
        else {
            return;
        };
        let Ok(size) = usize::try_from(size) else { return };
        let end = type_end + 5 + size;
        if end > bytes.len() {
            return;
        }
        attributes.push(at..end);
        at = end;
    }
    let name = |r: &std::ops::Range<usize>| {
        let n = &bytes[r.start..];
        &n[..n.iter().position(|&b| b == 0).unwrap_or(0)]
    };
    attributes.sort_by(|a, b| name(a).cmp(name(b)));
    let mut header = Vec::with_capacity(at - start);
    for r in attributes {
        header.extend_from_slice(&bytes[r]);
    }
    bytes[start..at].copy_from_slice(&header);
}

/// Write an XYZ image as OpenEXR: channels X, Y, Z and linear sRGB-primaries R, G, B preview
/// channels (so ordinary viewers show it), plus the `emitter` and `lit_by` masks and the
/// adapting white when there are any.
pub fn write_xyz_exr(path: &Path, image: &XyzImage, attributes: &[(&str, &str)]) -> Result<()> {
    write_xyz_exr_with(path, image, Vec::new(), attributes)
}

fn write_xyz_exr_with(
    path: &Path,
    image: &XyzImage,
    extra: Vec<(String, Vec<f32>)>,
    attributes: &[(&str, &str)],
) -> Result<()> {
    let plane = |f: &dyn Fn(&[f32; 3]) -> f32| image.pixels.iter().map(f).collect::<Vec<f32>>();
    let m = RgbSpace::Srgb.xyz_to_rgb().transpose().to_cols_array_2d();
    let rgb = |r: usize| {
        plane(&|p| {
            (m[r][0] * f64::from(p[0]) + m[r][1] * f64::from(p[1]) + m[r][2] * f64::from(p[2]))
                as f32
        })
    };
    let mut channels = vec![
        ("X".to_owned(), plane(&|p| p[0])),
        ("Y".to_owned(), plane(&|p| p[1])),
        ("Z".to_owned(), plane(&|p| p[2])),
        ("R".to_owned(), rgb(0)),
        ("G".to_owned(), rgb(1)),
        ("B".to_owned(), rgb(2)),
    ];
    if let Some(mask) = &image.emitter {
        channels
            .push(("emitter".to_owned(), mask.iter().map(|&e| f32::from(u8::from(e))).collect()));
    }
    if let Some(masks) = &image.lit_by {
        // Exact: a mask has at most 24 bits.
        channels.push(("lit_by".to_owned(), masks.iter().map(|&m| m as f32).collect()));
    }
    if let Some(white) = &image.white {
        for (i, name) in WHITE_CHANNELS.iter().enumerate() {
            channels.push(((*name).to_owned(), white.iter().map(|w| w[i]).collect()));
        }
    }
    channels.extend(extra);
    write_exr(path, image.width, image.height, channels, attributes)
}

/// The channel name of one wavelength band in the spectral OpenEXR layout of Fichet,
/// Pacanowski & Wilkie (JCGT 10(3), 2021): Stokes component 0, the wavelength with a comma as
/// decimal separator (a point separates EXR layers), and its unit: `S0.380,000000nm`.
pub fn spectral_channel_name(wavelength_nm: f64) -> String {
    format!("S0.{}nm", format!("{wavelength_nm:.6}").replace('.', ","))
}

/// Write an XYZ image with its spectral radiance (W·sr⁻¹·m⁻²·nm⁻¹ per band, band-major: one
/// `Vec` per wavelength) as one OpenEXR: X, Y, Z, RGB preview and the `S0.<λ>nm` channels, with
/// the layout's `spectralLayoutVersion` and `emissiveUnits` attributes.
pub fn write_spectral_exr(
    path: &Path,
    image: &XyzImage,
    bands: Vec<(f64, Vec<f32>)>,
    attributes: &[(&str, &str)],
) -> Result<()> {
    write_render_exr(path, image, Some(bands), None, attributes)
}

/// The EXR channel of a render with adaptive sampling that holds the samples each pixel took
/// (whole numbers, exact in f32 up to 2²⁴).
pub const SAMPLES_CHANNEL: &str = "samples";

/// A render's EXR: [`write_xyz_exr`]'s, or [`write_spectral_exr`]'s when it has `bands`, and,
/// with adaptive sampling, each pixel's count of samples in [`SAMPLES_CHANNEL`].
pub fn write_render_exr(
    path: &Path,
    image: &XyzImage,
    bands: Option<Vec<(f64, Vec<f32>)>>,
    samples: Option<&[u32]>,
    attributes: &[(&str, &str)],
) -> Result<()> {
    let counts = samples
        .map(|n| (SAMPLES_CHANNEL.to_owned(), n.iter().map(|&n| n as f32).collect::<Vec<f32>>()));
    match bands {
        Some(bands) => {
            let mut attrs: Vec<(&str, &str)> =
                vec![("spectralLayoutVersion", "1.0"), ("emissiveUnits", "W.m^-2.sr^-1")];
            attrs.extend_from_slice(attributes);
            let extra = counts
                .into_iter()
                .chain(bands.into_iter().map(|(l, v)| (spectral_channel_name(l), v)))
                .collect();
            write_xyz_exr_with(path, image, extra, &attrs)
        }
        None => write_xyz_exr_with(path, image, counts.into_iter().collect(), attributes),
    }
}

/// Code values for a PNG.
pub enum PngPixels {
    Eight(Vec<u8>),
    Sixteen(Vec<u16>),
    /// 8-bit RGB with alpha (0: transparent), four values a pixel.
    EightWithAlpha(Vec<u8>),
}

/// Write an RGB PNG in the given display space: sRGB is marked with an sRGB chunk; the other
/// spaces with their primaries (cHRM) and transfer exponent (gAMA).
pub fn write_png(
    path: &Path,
    width: usize,
    height: usize,
    pixels: &PngPixels,
    space: RgbSpace,
) -> Result<()> {
    let bytes = encode_png(width, height, pixels, space)
        .map_err(|error| ImageError::Png { path: path.to_owned(), error })?;
    atomic_file::write(path, &bytes)
        .map_err(|error| ImageError::Io { path: path.to_owned(), error })
}

/// The PNG file of `pixels` (RGB, row by row), tagged with `space`, as bytes.
pub fn encode_png(
    width: usize,
    height: usize,
    pixels: &PngPixels,
    space: RgbSpace,
) -> std::result::Result<Vec<u8>, png::EncodingError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width as u32, height as u32);
        encoder.set_color(png::ColorType::Rgb);
        match space {
            RgbSpace::Srgb => encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual),
            other => {
                let [r, g, b] = other.primaries().map(|c| (c.x as f32, c.y as f32));
                let w = other.white().chromaticity().expect("white has a chromaticity");
                encoder.set_source_chromaticities(png::SourceChromaticities::new(
                    (w.x as f32, w.y as f32),
                    r,
                    g,
                    b,
                ));
                let gamma = match other.transfer() {
                    restauro_spectral::rgb_space::Transfer::Srgb => 1.0 / 2.2,
                    restauro_spectral::rgb_space::Transfer::Gamma(g) => 1.0 / g,
                };
                encoder.set_source_gamma(png::ScaledFloat::new(gamma as f32));
            }
        }
        let data: Vec<u8> = match pixels {
            PngPixels::Eight(v) => {
                encoder.set_depth(png::BitDepth::Eight);
                v.clone()
            }
            PngPixels::Sixteen(v) => {
                encoder.set_depth(png::BitDepth::Sixteen);
                v.iter().flat_map(|x| x.to_be_bytes()).collect()
            }
            PngPixels::EightWithAlpha(v) => {
                encoder.set_color(png::ColorType::Rgba);
                encoder.set_depth(png::BitDepth::Eight);
                v.clone()
            }
        };
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&data)?;
        writer.finish()?;
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("restauro-img-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn xyz_exr_round_trips() {
        let dir = scratch("rt");
        let image = XyzImage {
            width: 3,
            height: 2,
            pixels: vec![
                [0.1, 0.2, 0.3],
                [1.0, 2.0, 3.0],
                [0.0; 3],
                [5.0, 5.0, 5.0],
                [0.5, 0.25, 0.125],
                [9.0, 8.0, 7.0],
            ],
            emitter: Some(vec![false, false, false, true, false, false]),
            // The largest mask is exact in f32.
            lit_by: Some(vec![0, 1, 3, 0, (1 << 24) - 1, 1 << 23]),
            white: Some((0..6).map(|i| [i as f32, 2.0 * i as f32, 0.5, 4.0]).collect()),
        };
        let path = dir.join("a.exr");
        write_xyz_exr(&path, &image, &[("restauroNote", "test")]).unwrap();
        assert_eq!(read_exr(&path, MAX_PIXELS).unwrap(), image);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The same image is the same bytes, however the exr crate's map ordered its attributes
    /// (each write builds a new map with its own random order), and it still reads back.
    #[test]
    fn the_same_image_is_the_same_bytes() {
        let dir = scratch("same-bytes");
        let image = XyzImage {
            width: 2,
            height: 1,
            pixels: vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
            emitter: Some(vec![false, true]),
            lit_by: None,
            white: None,
        };
        let attributes: Vec<(String, String)> =
            (0..8).map(|i| (format!("restauroNote{i}"), format!("value {i}"))).collect();
        let attributes: Vec<(&str, &str)> =
            attributes.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        let mut first: Option<Vec<u8>> = None;
        for i in 0..12 {
            let path = dir.join(format!("{i}.exr"));
            write_spectral_exr(&path, &image, vec![(380.0, vec![0.5, 0.25])], &attributes).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            match &first {
                Some(f) => assert!(*f == bytes, "write {i} differs from the first"),
                None => first = Some(bytes),
            }
            assert_eq!(read_exr(&path, MAX_PIXELS).unwrap(), image);
        }
        // Not sorting would have been caught: the names do appear in order in the header.
        let bytes = first.unwrap();
        let at = |needle: &str| bytes.windows(needle.len()).position(|w| w == needle.as_bytes());
        let positions: Vec<usize> =
            (0..8).map(|i| at(&format!("restauroNote{i}")).unwrap()).collect();
        assert!(positions.windows(2).all(|p| p[0] < p[1]), "{positions:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn spectral_channels_follow_the_layout() {
        assert_eq!(spectral_channel_name(380.0), "S0.380,000000nm");
        assert_eq!(spectral_channel_name(557.5), "S0.557,500000nm");
        let dir = scratch("spectral");
        let path = dir.join("s.exr");
        let image = XyzImage::new(1, 2, vec![[1.0, 2.0, 3.0]; 2]);
        write_spectral_exr(
            &path,
            &image,
            vec![(380.0, vec![0.5, 0.25]), (385.0, vec![1.0, 2.0])],
            &[],
        )
        .unwrap();
        let read = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(&path)
            .unwrap();
        let names: Vec<String> =
            read.layer_data.channel_data.list.iter().map(|c| c.name.to_string()).collect();
        assert!(
            names.contains(&"S0.380,000000nm".to_owned())
                && names.contains(&"S0.385,000000nm".to_owned()),
            "{names:?}"
        );
        let attr = |k: &str| read.layer_data.attributes.other.get(&Text::from(k)).cloned();
        assert_eq!(attr("emissiveUnits"), Some(AttributeValue::Text(Text::from("W.m^-2.sr^-1"))));
        assert_eq!(attr("spectralLayoutVersion"), Some(AttributeValue::Text(Text::from("1.0"))));
        // The XYZ still reads back as it was.
        assert_eq!(read_exr(&path, MAX_PIXELS).unwrap(), image);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn rgb_exr_is_converted_with_rec709_primaries() {
        let dir = scratch("rgb");
        let path = dir.join("rgb.exr");
        let ch = |n: &str, v: f32| (n.to_owned(), vec![v; 4]);
        write_exr(&path, 2, 2, vec![ch("R", 1.0), ch("G", 1.0), ch("B", 1.0)], &[]).unwrap();
        let img = read_exr(&path, MAX_PIXELS).unwrap();
        // R = G = B = 1 is the D65 white.
        let p = img.pixels[0];
        assert!(
            (p[0] - 0.9505).abs() < 1e-3
                && (p[1] - 1.0).abs() < 1e-5
                && (p[2] - 1.089).abs() < 1e-3,
            "{p:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_exr_files_are_refused_with_their_name() {
        let dir = scratch("bad");
        let text = dir.join("text.exr");
        std::fs::write(&text, "not an exr").unwrap();
        let err = read_exr(&text, MAX_PIXELS).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!("{}: not a readable OpenEXR file", text.display())),
            "{err}"
        );

        let alpha = dir.join("alpha.exr");
        write_exr(&alpha, 2, 2, vec![("A".into(), vec![1.0; 4])], &[]).unwrap();
        let err = read_exr(&alpha, MAX_PIXELS).unwrap_err().to_string();
        assert!(
            err.contains(
                "no colour channels; restauro reads X, Y, Z or R, G, B, and this file has A"
            ),
            "{err}"
        );

        let nan = dir.join("nan.exr");
        let mut y = vec![1.0; 4];
        y[3] = f32::NAN;
        write_exr(
            &nan,
            2,
            2,
            vec![("X".into(), vec![1.0; 4]), ("Y".into(), y), ("Z".into(), vec![1.0; 4])],
            &[],
        )
        .unwrap();
        let err = read_exr(&nan, MAX_PIXELS).unwrap_err().to_string();
        assert!(err.contains("channel Y at pixel (1, 1) is NaN"), "{err}");
        // Finite but beyond the bound: 3.4e38 would overflow the first matrix applied to it.
        let huge = dir.join("huge.exr");
        let channels = ["R", "G", "B"].map(|c| (c.to_owned(), vec![1.0f32, 3.4e38, 1.0, 1.0]));
        write_exr(&huge, 2, 2, channels.to_vec(), &[]).unwrap();
        let err = read_exr(&huge, MAX_PIXELS).unwrap_err().to_string();
        assert!(
            err.contains(
                "channel R at pixel (1, 0) is 3.4e38; colour values must be finite and \
                          within ±1e30 (cd/m² for absolute XYZ); scale the image"
            ),
            "{err}"
        );

        let big = dir.join("big.exr");
        write_exr(&big, 4, 3, vec![("Y".into(), vec![1.0; 12])], &[]).unwrap();
        let err = read_exr(&big, 10).unwrap_err().to_string();
        assert!(
            err.contains("4×3 is larger than the limit of 10 pixels; crop or downscale it"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What `anyhow`'s `{:#}` prints: the message and each source's, joined by ": ".
    fn chain(e: &(dyn std::error::Error + 'static)) -> String {
        let mut out = e.to_string();
        let mut source = e.source();
        while let Some(s) = source {
            out += &format!(": {s}");
            source = s.source();
        }
        out
    }

    #[test]
    fn a_damaged_exr_is_described_once_in_plain_words() {
        let dir = scratch("damaged");
        let good = dir.join("good.exr");
        let image = XyzImage::new(8, 4, vec![[1.0, 2.0, 3.0]; 32]);
        write_xyz_exr(&good, &image, &[]).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        let cut = dir.join("cut.exr");
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        let err = read_exr(&cut, MAX_PIXELS).unwrap_err();
        let text = chain(&err);
        assert!(
            text.starts_with(&format!("{}: not a readable OpenEXR file: ", cut.display())),
            "{text}"
        );
        assert!(text.contains("export it again"), "{text}");
        // Said once: the first sentence of the problem does not come back through a `source`.
        let problem = text.split(": not a readable OpenEXR file: ").nth(1).unwrap();
        let first = &problem[..problem.find(';').unwrap_or(problem.len())];
        assert_eq!(text.matches(first).count(), 1, "{text}");
        let missing = read_exr(&dir.join("none.exr"), MAX_PIXELS).unwrap_err();
        let text = chain(&missing);
        assert!(text.contains("does not exist") && !text.contains("os error"), "{text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_not_waited_on() {
        let dir = scratch("fifo");
        let fifo = dir.join("pipe.exr");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let (send, receive) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = send.send(read_exr(&path, MAX_PIXELS).map(|_| ()).unwrap_err().to_string());
        });
        let err = receive
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("read_exr on a FIFO did not return within 20 s");
        assert!(err.starts_with(&format!("{}: not a regular file", fifo.display())), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_files_decode_with_their_depth_and_colour_space() {
        let dir = scratch("png");
        for (name, pixels, space) in [
            ("a8.png", PngPixels::Eight(vec![255, 0, 10, 1, 2, 3]), RgbSpace::Srgb),
            ("a16.png", PngPixels::Sixteen(vec![65535, 0, 1000, 1, 2, 3]), RgbSpace::DisplayP3),
            (
                "rgba.png",
                PngPixels::EightWithAlpha(vec![255, 0, 10, 0, 1, 2, 3, 255]),
                RgbSpace::Srgb,
            ),
        ] {
            let path = dir.join(name);
            write_png(&path, 2, 1, &pixels, space).unwrap();
            let decoder =
                png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
            let mut reader = decoder.read_info().unwrap();
            let info = reader.info().clone();
            assert_eq!((info.width, info.height), (2, 1));
            let mut buf = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut buf).unwrap();
            match pixels {
                PngPixels::Eight(v) => {
                    assert_eq!(info.bit_depth, png::BitDepth::Eight);
                    assert!(info.srgb.is_some());
                    assert_eq!(buf, v);
                }
                PngPixels::Sixteen(v) => {
                    assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
                    let c = info.chromaticities().unwrap();
                    assert!((c.red.0.into_value() - 0.68).abs() < 1e-4);
                    let back: Vec<u16> =
                        buf.chunks(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
                    assert_eq!(back, v);
                }
                PngPixels::EightWithAlpha(v) => {
                    assert_eq!(
                        (info.color_type, info.bit_depth),
                        (png::ColorType::Rgba, png::BitDepth::Eight)
                    );
                    assert_eq!(buf, v);
                }
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
