//! restauro's wire types: `proto/restauro.proto` — the client-facing `Render` service and the
//! worker-facing `Work` service — the code tonic/prost generate from it, and the one conversion
//! of each wire type to its domain type and back ([`convert`]): a wire value is checked once, at
//! the edge, and only domain types travel further. A job's id, state and status, which both the
//! coordinator and the command line hold, live here too ([`job_status`]), with their conversions.

/// The protocol version spoken by this build. A worker or client of another version is refused.
/// 3: a worker registers with its identity, to which its leases are bound. 4: sequences (a job
/// of frames; a lease names its frame, and a worker fetches the frame's scene and plan).
pub const PROTOCOL_VERSION: u32 = 4;

/// The metadata key that carries the caller's protocol version on every call.
pub const PROTOCOL_HEADER: &str = "x-restauro-protocol";

/// Files and tile data travel in chunks of this many bytes, far below gRPC's 4 MiB default
/// message limit.
pub const CHUNK_BYTES: usize = 1 << 20;

#[allow(clippy::all, missing_docs)]
pub mod pb {
    tonic::include_proto!("restauro.v1");
}

pub use pb::*;

/// The encoded `FileDescriptorSet` of `restauro.proto`, for the gRPC reflection service.
pub const FILE_DESCRIPTOR_SET: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/restauro_descriptor.bin"));

pub mod convert;
pub mod job_status;
pub mod transport;

/// Adds the protocol version and a bearer token to every outgoing request (clients and workers).
#[derive(Clone)]
pub struct Credentials {
    authorization: tonic::metadata::MetadataValue<tonic::metadata::Ascii>,
    version: tonic::metadata::MetadataValue<tonic::metadata::Ascii>,
}

impl Credentials {
    /// Fails when the token holds characters a header cannot carry.
    pub fn new(token: &str, protocol_version: u32) -> Result<Self, transport::DialError> {
        let authorization =
            format!("Bearer {}", token.trim()).parse().map_err(|_| transport::DialError::Token)?;
        let version = protocol_version.to_string().parse().expect("digits are ASCII");
        Ok(Self { authorization, version })
    }
}

impl tonic::service::Interceptor for Credentials {
    fn call(
        &mut self,
        mut request: tonic::Request<()>,
    ) -> Result<tonic::Request<()>, tonic::Status> {
        request.metadata_mut().insert("authorization", self.authorization.clone());
        request.metadata_mut().insert(PROTOCOL_HEADER, self.version.clone());
        Ok(request)
    }
}
