//! restauro-worker: the spectral tracer as a library — scene preparation with a CWBVH
//! ([`prepared`]), the pinhole [`camera`], keyed [`sampler`], the [`bsdf`]s, photometric
//! [`light`]s, the Whitted and path [`integrator`]s and [`tile`] rendering — and, with the
//! cluster, the worker process.

pub mod bsdf;
pub mod camera;
pub mod integrator;
pub mod light;
pub mod metrics;
pub mod prepared;
pub mod process;
pub mod sampler;
pub mod tile;
