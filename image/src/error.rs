//! The one error type of restauro-image, [`ImageError`]: every message names the file where
//! there is one, says what is wrong, and what to do about it.

use std::io;
use std::path::PathBuf;

/// What went wrong in restauro-image: with an image file, the seen image of a render's
/// results, or a false-colour scale. The underlying error is worded into each message and not
/// kept as the error's `source`, so that a caller printing the whole chain (`anyhow`'s `{:#}`)
/// says it once.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: {}", path.display(), restauro_scene::error::io_problem(error))]
    Io { path: PathBuf, error: io::Error },
    #[error("{}: not a readable OpenEXR file: {problem}", path.display())]
    Exr { path: PathBuf, problem: String },
    #[error(
        "{}: not a regular file (a FIFO, a device or a folder); give the path of an OpenEXR file",
        path.display()
    )]
    NotAFile { path: PathBuf },
    #[error(
        "{}: no colour channels; restauro reads X, Y, Z or R, G, B, and this file has {}",
        path.display(),
        if channels.is_empty() { "none".to_owned() } else { channels.join(", ") }
    )]
    NoColourChannels { path: PathBuf, channels: Vec<String> },
    #[error(
        "{}: {width}×{height} is larger than the limit of {max} pixels; crop or downscale it",
        path.display()
    )]
    TooLarge { path: PathBuf, width: usize, height: usize, max: usize },
    #[error(
        "{}: {channels} channels of {width}×{height} pixels are more than the limit of {max} \
         samples; keep fewer channels (e.g. drop the spectral layers) or crop the image",
        path.display()
    )]
    TooManySamples { path: PathBuf, width: usize, height: usize, channels: usize, max: usize },
    #[error(
        "{}: channel {channel} at pixel ({x}, {y}) is {value:e}; colour values must be finite \
         and within ±{bound:e} (cd/m² for absolute XYZ); scale the image into that range",
        path.display(),
        bound = crate::radiometric_bound::MAX_RADIOMETRIC
    )]
    OutOfRange { path: PathBuf, channel: String, x: usize, y: usize, value: f32 },
    #[error("{}: cannot write the PNG: {error}", path.display())]
    Png { path: PathBuf, error: png::EncodingError },
    /// The seen image of a render's results could not be made.
    #[error("retinex: {0}")]
    Retinex(restauro_spectral::Error),
    /// A false-colour scale of another name than log or linear.
    #[error("`{text}` is not a scale; use log or linear")]
    UnknownScale { text: String },
    /// A false-colour range that is no range: not finite, negative, or empty.
    #[error("the range {min_cd_m2}:{max_cd_m2} cd/m²: give MIN:MAX with 0 ≤ MIN < MAX")]
    EmptyRange { min_cd_m2: f64, max_cd_m2: f64 },
    /// A false-colour range from 0 on a log scale.
    #[error("the range {min_cd_m2}:{max_cd_m2} cd/m²: a log scale starts above 0 cd/m²")]
    LogRangeFromZero { min_cd_m2: f64, max_cd_m2: f64 },
    /// A calculation of grids that is not of the scene's grids.
    #[error(
        "{}: {width}×{height} values, but the scene's grids have {points} points (2 rows each); \
         was it computed from another scene?",
        path.display()
    )]
    GridsMismatch { path: PathBuf, width: usize, height: usize, points: usize },
}
