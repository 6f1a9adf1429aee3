//! restauro-coordinator: jobs, tile scheduling, leases, framebuffer assembly, the display
//! pipeline, persistence and the gRPC services. It never links the tracer (restauro-worker):
//! it plans a job from the scene alone and assembles what workers send.

pub mod atomic_file;
pub mod auth;
pub mod framebuffer;
pub mod group_commit;
pub mod image_files;
pub mod jobs;
pub mod logging;
pub mod metrics;
pub mod results;
pub mod scheduler;
pub mod server;
pub mod service;
pub mod store;
