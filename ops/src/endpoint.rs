//! The operations endpoint, plain HTTP beside the gRPC port: `GET /metrics` (Prometheus text,
//! OpenMetrics 1.0, rendered at each scrape), `GET /healthz` (the process runs: liveness) and
//! `GET /readyz` (it can do its work: readiness — a worker that has registered with its
//! coordinator, a coordinator whose store is open).

use crate::connections::{ConnectionLimits, GuardedListener};
use crate::error::{OpsError, Result};
use crate::metrics_access::Access;
use axum::Router;
use axum::extract::State;
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::IntoResponse;
use axum::routing::get;
use prometheus_client::encoding::text::encode;
use prometheus_client::registry::Registry;
use std::net::SocketAddr;
use std::sync::Arc;
use tokio::net::TcpListener;
use tokio::task::JoinHandle;
use tracing::{info, warn};

/// What a process reports.
pub trait Probe: Send + Sync + 'static {
    /// Brings the registry's values up to date for a scrape (gauges read from live state).
    fn refresh(&self) {}
    /// The registry to encode.
    fn registry(&self) -> &Registry;
    /// `Ok` when ready for work, else why not.
    fn ready(&self) -> Result<(), NotReady>;
}

/// Why a process is not ready for work, in words; `/readyz` answers `not ready: <why>`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct NotReady(pub String);

/// The registry in the Prometheus text format.
pub fn encode_registry(registry: &Registry) -> String {
    let mut text = String::new();
    // Writing into a String cannot fail.
    let _ = encode(&mut text, registry);
    text
}

/// What the endpoint's handlers share.
#[derive(Clone)]
struct Served {
    probe: Arc<dyn Probe>,
    access: Access,
}

async fn metrics(State(served): State<Served>, headers: HeaderMap) -> axum::response::Response {
    let authorization = headers.get(header::AUTHORIZATION).and_then(|v| v.to_str().ok());
    if !served.access.admits(authorization) {
        let challenge = [(header::WWW_AUTHENTICATE, "Bearer realm=\"restauro metrics\"")];
        let why = "the metrics need `Authorization: Bearer <token>`, the token of the process's \
                   --metrics-token-file\n";
        return (StatusCode::UNAUTHORIZED, challenge, why).into_response();
    }
    served.probe.refresh();
    (
        [(header::CONTENT_TYPE, "application/openmetrics-text; version=1.0.0; charset=utf-8")],
        encode_registry(served.probe.registry()),
    )
        .into_response()
}

async fn healthz() -> &'static str {
    "ok\n"
}

async fn readyz(State(served): State<Served>) -> (StatusCode, String) {
    match served.probe.ready() {
        Ok(()) => (StatusCode::OK, "ready\n".into()),
        Err(why) => (StatusCode::SERVICE_UNAVAILABLE, format!("not ready: {why}\n")),
    }
}

/// Binds `listen` (port 0 picks a free port) and serves until `stop` resolves, `/metrics` to
/// those `access` admits, each connection within `limits`. Returns the bound address and the
/// serving task.
pub async fn serve(
    listen: SocketAddr,
    probe: Arc<dyn Probe>,
    access: Access,
    limits: ConnectionLimits,
    stop: impl Future<Output = ()> + Send + 'static,
) -> Result<(SocketAddr, JoinHandle<()>)> {
    let listener = TcpListener::bind(listen)
        .await
        .map_err(|error| OpsError::Listen { addr: listen, error })?;
    let addr = listener.local_addr().map_err(OpsError::LocalAddr)?;
    let listener = GuardedListener::new(listener, limits);
    let app = Router::new()
        .route("/metrics", get(metrics))
        .route("/healthz", get(healthz))
        .route("/readyz", get(readyz))
        .with_state(Served { probe, access });
    let guarded = matches!(access, Access::Bearer(_));
    info!(%addr, token = guarded, "metrics and health on http://{addr}/metrics");
    let task = tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, app).with_graceful_shutdown(stop).await {
            warn!(error = %e, "the metrics endpoint stopped");
        }
    });
    Ok((addr, task))
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Nothing(Registry);

    impl Probe for Nothing {
        fn registry(&self) -> &Registry {
            &self.0
        }

        fn ready(&self) -> Result<(), NotReady> {
            Ok(())
        }
    }

    /// A metrics address already taken is refused with that address, not served elsewhere.
    #[test]
    fn a_taken_address_is_refused_with_its_name() {
        let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let at = taken.local_addr().unwrap();
        let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
        let probe: Arc<dyn Probe> = Arc::new(Nothing(Registry::default()));
        let limits = ConnectionLimits::default();
        let serving = serve(at, probe, Access::Open, limits, std::future::pending());
        // As a binary prints it: the error and its cause.
        let error = anyhow::Error::from(runtime.block_on(serving).unwrap_err());
        let message = format!("{error:#}");
        assert!(message.starts_with(&format!("listening for metrics on {at}:")), "{message}");
    }
}
