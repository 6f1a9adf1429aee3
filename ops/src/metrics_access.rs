//! Who may read a process's metrics, and where it serves them: the flags every restauro process
//! with an operations endpoint takes, and the rule that turns them into an [`Access`].
//!
//! `/metrics` tells its reader the farm's jobs, workers, load and failures, so it is not served
//! open where other machines can reach it unless the operator says so:
//!
//! * on a loopback address (`127.0.0.1:9464`, `[::1]:9464`) it is open: only this machine's
//!   processes (a node exporter, a sidecar, an SSH tunnel) reach it;
//! * with `--metrics-token-file FILE` (or `RESTAURO_METRICS_TOKEN`) a scraper must send
//!   `Authorization: Bearer <token>` — Prometheus does with
//!   `authorization: { credentials_file: FILE }` in its scrape config;
//! * on any other address without a token the process refuses to start, unless
//!   `--metrics-public` says the network already guards it (a Kubernetes NetworkPolicy, a
//!   private monitoring VLAN).
//!
//! `/healthz` and `/readyz` stay open in every case: they say only whether the process runs and
//! is ready, and the probes that ask (kubelet, a load balancer) send no token.

use crate::error::{OpsError, Result};
use crate::token::read_token;
use std::net::SocketAddr;
use std::path::PathBuf;

/// The environment variable that holds the metrics token when no file is given.
pub const METRICS_TOKEN_VARIABLE: &str = "RESTAURO_METRICS_TOKEN";

/// The operations endpoint's flags.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct MetricsArgs {
    /// Serve Prometheus metrics (/metrics) and health (/healthz, /readyz) over HTTP on this
    /// address (else RESTAURO_METRICS_LISTEN; off when neither is given). Port 0 picks a free
    /// port, printed as `metrics on ADDR`. On an address other than loopback /metrics needs
    /// --metrics-token-file or --metrics-public.
    #[arg(long, env = "RESTAURO_METRICS_LISTEN")]
    pub metrics_listen: Option<SocketAddr>,
    /// A file holding the bearer token a scraper must send for /metrics (else
    /// RESTAURO_METRICS_TOKEN); /healthz and /readyz stay open.
    #[arg(long)]
    pub metrics_token_file: Option<PathBuf>,
    /// Serve /metrics without a token on an address other machines can reach: for a network
    /// that already guards the port (a NetworkPolicy, a private monitoring network).
    #[arg(long)]
    pub metrics_public: bool,
}

/// Who may read `/metrics`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Anyone who reaches the address.
    Open,
    /// A caller whose bearer token has this BLAKE3 hash (which compares in constant time).
    Bearer(blake3::Hash),
}

impl Access {
    /// Whether an `Authorization` header's value lets its sender read the metrics.
    pub fn admits(&self, authorization: Option<&str>) -> bool {
        match self {
            Access::Open => true,
            Access::Bearer(hash) => authorization
                .and_then(|v| v.strip_prefix("Bearer "))
                .is_some_and(|token| blake3::hash(token.trim().as_bytes()) == *hash),
        }
    }
}

impl MetricsArgs {
    /// Where to serve and who may read, or `None` when the endpoint is off; refuses an open
    /// endpoint on an address other machines can reach, saying what to give.
    pub fn endpoint(&self) -> Result<Option<(SocketAddr, Access)>> {
        let Some(at) = self.metrics_listen else { return Ok(None) };
        let has_variable =
            std::env::var(METRICS_TOKEN_VARIABLE).is_ok_and(|v| !v.trim().is_empty());
        if self.metrics_token_file.is_some() || has_variable {
            let token = read_token(
                self.metrics_token_file.as_deref(),
                METRICS_TOKEN_VARIABLE,
                "--metrics-token-file",
            )?;
            return Ok(Some((at, Access::Bearer(blake3::hash(token.as_bytes())))));
        }
        if at.ip().is_loopback() || self.metrics_public {
            return Ok(Some((at, Access::Open)));
        }
        Err(OpsError::OpenMetrics { at })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(listen: &str) -> MetricsArgs {
        MetricsArgs { metrics_listen: Some(listen.parse().unwrap()), ..MetricsArgs::default() }
    }

    /// Runs only where the process has no metrics token in its environment (CI, a developer's
    /// shell): the rules without a token depend on it.
    fn without_variable() -> bool {
        std::env::var(METRICS_TOKEN_VARIABLE).is_err()
    }

    #[test]
    fn loopback_is_open_and_elsewhere_needs_a_token_or_a_word() {
        if !without_variable() {
            return;
        }
        assert_eq!(MetricsArgs::default().endpoint().unwrap(), None);
        for at in ["127.0.0.1:9464", "[::1]:0"] {
            assert_eq!(args(at).endpoint().unwrap().unwrap().1, Access::Open, "{at}");
        }
        for at in ["0.0.0.0:9464", "[::]:9464", "192.168.1.5:9464"] {
            let message = args(at).endpoint().unwrap_err().to_string();
            assert!(
                message.starts_with(&format!("--metrics-listen {at} can be reached")),
                "{message}"
            );
            assert!(
                message.contains("--metrics-token-file FILE")
                    && message.contains("--metrics-public")
            );
            let public = MetricsArgs { metrics_public: true, ..args(at) };
            assert_eq!(public.endpoint().unwrap().unwrap().1, Access::Open);
        }
    }

    #[test]
    fn a_token_file_guards_the_metrics_on_any_address() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("metrics.token");
        std::fs::write(&file, "scrape-me\n").unwrap();
        for at in ["0.0.0.0:9464", "127.0.0.1:0"] {
            let with = MetricsArgs { metrics_token_file: Some(file.clone()), ..args(at) };
            let (_, access) = with.endpoint().unwrap().unwrap();
            assert!(access.admits(Some("Bearer scrape-me")));
            for wrong in [None, Some("Bearer scrape"), Some("scrape-me"), Some("Basic scrape-me")] {
                assert!(!access.admits(wrong), "{wrong:?}");
            }
        }
        let empty = dir.path().join("empty.token");
        std::fs::write(&empty, "\n").unwrap();
        let with = MetricsArgs { metrics_token_file: Some(empty), ..args("0.0.0.0:1") };
        let message = with.endpoint().unwrap_err().to_string();
        assert!(
            message.contains("give --metrics-token-file FILE or set RESTAURO_METRICS_TOKEN"),
            "{message}"
        );
    }
}
