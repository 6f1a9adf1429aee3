//! restauro-image: what restauro writes and reads as image files — OpenEXR with absolute XYZ and
//! spectral layers, PNG with its colour space ([`image_files`]), every file written atomically
//! ([`atomic_file`]) — the framebuffer that tiles are assembled into and the byte layout tiles
//! travel in ([`framebuffer`]), the bound on every radiometric value ([`radiometric_bound`]), and a finished render's files with the Retinex and the display
//! transform ([`results`]), with one error type for all of it ([`ImageError`]). The coordinator
//! and the client both use it; neither needs the other to write a file.

pub mod atomic_file;
pub mod delta_e;
pub mod error;
pub mod false_colour;
pub mod framebuffer;
pub mod illuminance;
pub mod image_files;
pub mod radiometric_bound;
pub mod results;

pub use error::ImageError;
