//! restauro-demo: what `restauro demo` shows, and the procedural scenes the tests and benchmarks
//! render: the south facade of the Roman theatre of Aosta ([`scenes::aosta`]), the paper's board
//! of stone samples ([`scenes::samples`]), blocks of pudding stone with a photograph as detail
//! ([`scenes::photo_block`]) and a relief of many triangles ([`scenes::relief`]). Each is written
//! as a restorer would write it: a scene file with its meshes, spectra and luminaires.
//!
//! The demo itself, without the cluster that renders it: what it renders ([`plan`]), and from
//! the renders fetched its analysis, contact sheets and report ([`report`]), drawn with
//! [`sheet`] and [`picture`]. Its one error is [`DemoError`].

pub mod error;
pub mod picture;
pub mod plan;
pub mod report;
pub mod scene_files;
pub mod scenes;
pub mod sheet;

pub use error::DemoError;
