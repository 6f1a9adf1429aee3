//! restauro-coordinator: jobs, tile scheduling, leases, framebuffer assembly, the display
//! pipeline, persistence and the gRPC services. It never links the tracer (restauro-render):
//! it plans a job from the scene alone and assembles what workers send.

pub mod auth;
pub mod group_commit;
pub mod jobs;
pub mod metrics;
pub mod scheduler;
pub mod server;
pub mod service;
pub mod store;
