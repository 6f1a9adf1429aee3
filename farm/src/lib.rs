//! restauro-farm: jobs, tile scheduling, leases, framebuffer assembly, the display pipeline,
//! persistence, the scenes' revisions and the gRPC services. It never links the tracer
//! (restauro-render): it plans a job from the scene alone and assembles what workers send.
//!
//! The domain layer is [`farm`]; [`grpc`] is one door to it, the studio's HTTP API
//! (restauro-studio) another. The process that opens both doors is restauro-coordinator.

pub mod asset_store;
pub mod auth;
#[cfg(feature = "fleet")]
mod blocking;
pub mod callers;
pub mod error;
pub mod farm;
pub mod group_commit;
pub mod grpc;
pub mod ids;
pub mod job;
pub mod lead;
pub mod lease;
pub mod metrics;
pub mod objects;
mod problem;
pub mod recent;
pub mod scheduler;
pub mod store;
