//! restauro-scene: what a restorer has on disk (a survey mesh, measured spectra, a luminaire's
//! photometric file) turned into a validated scene that any worker renders identically.
//!
//! The scene schema, the mesh importers (OBJ, glTF, PLY, VRML97), the IES LM-63 and EULUMDAT
//! readers, validation, asset bundles and the procedural Aosta theatre arrive with the scene issue.
//! Spectral CSV files are read by [`restauro_spectral::csv`], which this crate re-exports.

pub use restauro_spectral::csv as spectrum_csv;
