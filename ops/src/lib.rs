//! restauro-ops: what every restauro process shares to be operated — the signals that stop it,
//! the token files it reads, its logs, and the HTTP endpoint an operator's tools scrape and probe
//! (Prometheus `/metrics`, `/healthz`, `/readyz`) and who may read it, and what a connection to any of its
//! listeners may hold.

pub mod connections;
pub mod endpoint;
pub mod error;
pub mod logging;
pub mod metric;
pub mod metrics_access;
pub mod signal;
pub mod token;

pub use error::{OpsError, Result};
