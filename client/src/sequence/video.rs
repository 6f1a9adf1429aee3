//! A sequence as a video: an animated PNG (APNG, W3C PNG third edition).
//!
//! Why APNG: the `png` crate restauro already uses for every PNG writes it, so it needs no new
//! dependency and no tool on the machine (the README's two commands stay as they are); every
//! current browser plays it (the studio and a shared link show it as it is), ffmpeg-based
//! players (mpv, VLC, ffplay) play it, and it is lossless, so a stone's colour is the frame's to
//! the last bit. Its cost is size: a lossless frame is about what the frame's PNG is, so a long
//! walk is better encoded afresh from the frames (`ffmpeg -framerate 25 -i
//! scene-%04d-retinex.png -pix_fmt yuv420p walk.mp4` makes H.264 of them).
//!
//! Frames are read and written one at a time, so a sequence of any length needs the memory of
//! one frame.

use anyhow::{Context, Result, bail};
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// An 8-bit RGB frame read from a PNG: its size and its bytes.
pub struct RgbFrame {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

/// Reads an 8-bit RGB PNG (as restauro writes them).
pub fn read_rgb_png(path: &Path) -> Result<RgbFrame> {
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().with_context(|| format!("reading {}", path.display()))?;
    let size = reader.output_buffer_size().context("a PNG too large to read")?;
    let mut data = vec![0; size];
    let frame =
        reader.next_frame(&mut data).with_context(|| format!("reading {}", path.display()))?;
    if frame.color_type != png::ColorType::Rgb || frame.bit_depth != png::BitDepth::Eight {
        bail!("{}: not an 8-bit RGB PNG", path.display());
    }
    data.truncate(frame.buffer_size());
    Ok(RgbFrame { width: frame.width, height: frame.height, data })
}

/// The delay between frames at `fps` as APNG writes it: a fraction of u16s.
fn frame_delay(fps: f64) -> (u16, u16) {
    let den = (100.0 * fps).round().clamp(1.0, f64::from(u16::MAX)) as u16;
    (100, den)
}

/// Writes the PNGs `frames` (one size, sRGB) as an APNG at `fps` that plays in a loop; nothing
/// is left at `path` (nor beside it) unless the whole video is.
pub fn write_apng(path: &Path, frames: &[PathBuf], fps: f64) -> Result<()> {
    let temporary = path.with_extension("apng.partial");
    let written = encode(&temporary, frames, fps)
        .and_then(|()| std::fs::rename(&temporary, path).context("renaming the finished video"));
    if written.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    written.with_context(|| format!("writing {}", path.display()))
}

fn encode(temporary: &Path, frames: &[PathBuf], fps: f64) -> Result<()> {
    let Some(first) = frames.first() else { bail!("no frames to make a video of") };
    let first = read_rgb_png(first)?;
    let file = std::fs::File::create(temporary)
        .with_context(|| format!("writing {}", temporary.display()))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), first.width, first.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    encoder.set_animated(frames.len() as u32, 0)?;
    let (num, den) = frame_delay(fps);
    encoder.set_frame_delay(num, den)?;
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&first.data)?;
    for path in &frames[1..] {
        let frame = read_rgb_png(path)?;
        if (frame.width, frame.height) != (first.width, first.height) {
            bail!("{}: a frame of another size than the first", path.display());
        }
        writer.write_image_data(&frame.data)?;
    }
    writer.finish()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_delay_is_one_over_the_rate() {
        assert_eq!(frame_delay(25.0), (100, 2500));
        assert_eq!(frame_delay(2.0), (100, 200));
        assert_eq!(frame_delay(0.5), (100, 50));
    }
}
