//! restauro-worker: the worker process. It dials a coordinator, registers, pulls tile leases,
//! fetches each job's scene once, renders the tiles with restauro-render and reports them
//! ([`process`]), and serves its own metrics ([`metrics`]). What stops it is a [`WorkerError`]
//! ([`error`]); what fails one tile is a [`failure::JobError`], reported and survived.

pub mod error;
pub mod failure;
pub mod metrics;
pub mod process;
pub mod scene_cache;

pub use error::WorkerError;
