//! restauro-render: the spectral tracer as a library — scene preparation with a CWBVH
//! ([`prepared`]), the pinhole [`camera`], keyed [`sampler`], the [`bsdf`]s, photometric
//! [`light`]s and the [`sky`], the Whitted and path [`integrator`]s (rays leave surfaces by
//! the local [`frame`]), the calculation grids' [`sensor`]s, photo
//! [`texture`]s as detail over measured spectra, and [`tile`] rendering, with [`adaptive`]
//! sampling. It knows nothing of the network: the worker process and `restauro render
//! --in-process` both call it.

pub mod adaptive;
pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod degradation;
pub mod frame;
pub mod glass;
pub mod integrator;
pub mod light;
pub(crate) mod material_detail;
pub mod prepared;
pub mod sampler;
pub mod sensor;
pub mod sky;
pub mod soiling;
pub mod spherical_rectangle;
pub mod texture;
pub mod tile;
pub mod vertex_colour;
