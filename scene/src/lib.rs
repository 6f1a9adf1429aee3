//! restauro-scene: what a restorer has on disk (a survey mesh, measured spectra, a luminaire's
//! photometric file) turned into a validated scene that any worker renders identically.

pub mod error;
pub mod mesh;
pub mod sun;
pub mod texture;

pub use error::{Result, SceneError};
pub use mesh::{Bounds, Group, Mesh};
/// Spectrum files are read by restauro-spectral's reader.
pub use restauro_spectral::csv as spectrum_csv;
pub mod area_light;
pub mod assets;
pub mod bundle;
pub mod cie_sky;
pub mod edit;
pub mod formats;
pub mod glazing;
pub mod grid;
pub mod grid_edit;
pub mod guard;
pub mod job;
pub mod limits;
pub mod load;
pub mod lod;
pub mod note_image;
pub mod origin;
pub mod pins;
pub mod plan;
pub mod scene_file;
pub mod sequence;
pub mod upright;
pub mod web_url;
