//! restauro-coordinator: jobs, tile scheduling, leases, framebuffer assembly, the display
//! pipeline, persistence and the gRPC/HTTP services.
//!
//! Today it holds what the coordinator's pipeline ends with — writing results: image files
//! (OpenEXR and PNG) written whole or not at all. Jobs, tiles and services arrive with the
//! cluster issue. It never links the tracer (restauro-worker).

pub mod atomic_file;
pub mod image_files;
