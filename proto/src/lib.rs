//! restauro's wire types.
//!
//! This crate will hold the `.proto` files of the client-facing and worker-facing gRPC services
//! and the code tonic/prost generate from them, and nothing else (see `design.md`, "Crates").
//! The services arrive with the cluster; until then the crate carries only the protocol version
//! that every message will carry.

/// The protocol version spoken by this build. A worker or client of another version is refused.
pub const PROTOCOL_VERSION: u32 = 1;
