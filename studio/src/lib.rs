//! The studio: the restorer's interactive tool, a web page served by the coordinator over HTTP
//! beside its gRPC port (`--studio-listen ADDR`). The page is static files embedded in the
//! binary ([`page`]: plain ES modules, nothing to build); its JSON API ([`api`]) and live events
//! ([`events`]) are a second door to the same [`Farm`] the gRPC services use. Every `/api/` call
//! but signing in needs the client token or a session made from it ([`session`]).

pub mod api;
pub mod appearance;
pub mod compare;
pub mod demo_scene;
pub mod display;
pub mod edits;
pub mod error;
pub mod events;
pub mod gltf_export;
pub mod grid_views;
pub mod grids;
pub mod note_images;
pub mod page;
pub mod painting;
pub mod pixel;
pub mod preview;
pub mod sequence;
pub mod session;
pub mod snapshot;
pub mod vertex_clustering;
pub mod views;

use crate::error::{Result, StudioError};
use axum::Router;
use axum::extract::connect_info::{ConnectInfo, Connected};
use axum::extract::{Request, State};
use axum::http::{HeaderValue, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use restauro_farm::auth::Tokens;
use restauro_farm::farm::Farm;
use restauro_ops::connections::{Busy, ConnectionLimits, GuardedListener};
use restauro_ops::signal::stopped;
use std::net::SocketAddr;
use std::sync::Arc;
use tokio::net::TcpListener;
use tokio::sync::watch;
use tokio::task::JoinHandle;
use tracing::{info, warn};

/// What every handler shares.
pub struct Studio {
    pub farm: Arc<Farm>,
    pub gate: session::Gate,
    pub events: Arc<events::Events>,
    pub previews: preview::Previews,
    /// True once the coordinator stops: open event streams end, so the server can.
    pub stop: watch::Receiver<bool>,
}

/// Every `/api/` route but `POST /api/session` goes through the gate.
async fn signed_in(State(studio): State<Arc<Studio>>, request: Request, next: Next) -> Response {
    if let Err(e) = studio.gate.check(request.method(), request.headers()) {
        return e.into_response();
    }
    let mut response = next.run(request).await;
    // Answers about live state are never cached (a content-addressed image says otherwise).
    response
        .headers_mut()
        .entry(header::CACHE_CONTROL)
        .or_insert(HeaderValue::from_static("no-store"));
    response
}

/// A connection's [`Busy`]: each request marks itself as work in progress, so that a request
/// the coordinator takes long over (a snapshot waiting for its scene to load) is not cut as an
/// idle connection.
#[derive(Clone)]
struct ConnectionBusy(Busy);

impl Connected<axum::serve::IncomingStream<'_, GuardedListener>> for ConnectionBusy {
    fn connect_info(stream: axum::serve::IncomingStream<'_, GuardedListener>) -> Self {
        ConnectionBusy(stream.io().busy())
    }
}

async fn working(
    ConnectInfo(busy): ConnectInfo<ConnectionBusy>,
    request: Request,
    next: Next,
) -> Response {
    let _working = busy.0.working();
    next.run(request).await
}

async fn no_such_route(request: Request) -> StudioError {
    StudioError::NoSuchPage(request.uri().path().chars().take(200).collect())
}

fn router(studio: Arc<Studio>) -> Router {
    let api = Router::new()
        .route("/api/whoami", get(api::whoami))
        .route("/api/jobs", get(api::jobs))
        .route("/api/jobs/{id}", get(api::job))
        .route("/api/jobs/{id}/cancel", post(api::cancel))
        .route("/api/jobs/{id}/results/{name}", get(api::result))
        .route("/api/workers", get(api::workers))
        .route("/api/events", get(api::events))
        .route(
            "/api/scenes",
            get(api::scenes)
                .post(edits::open_folder)
                .layer(axum::extract::DefaultBodyLimit::max(restauro_farm::farm::MAX_FOLDER_BYTES)),
        )
        .route("/api/scenes/demo", post(demo_scene::open))
        .route("/api/scenes/{id}", get(api::scene))
        .route("/api/scenes/{id}/preview.glb", get(api::scene_glb))
        .route("/api/scenes/{id}/snapshots", post(api::take_snapshot))
        .route("/api/scenes/{id}/sequences", post(sequence::start))
        .route("/api/jobs/{id}/frames", get(sequence::frames))
        .route("/api/scenes/{id}/edits", post(edits::edit))
        .route("/api/scenes/{id}/revert", post(edits::revert))
        .route("/api/scenes/{id}/photometry", post(edits::photometry))
        .route("/api/scenes/{id}/spectrum", post(edits::spectrum))
        .route(
            "/api/scenes/{id}/images",
            post(note_images::upload)
                .layer(axum::extract::DefaultBodyLimit::max(restauro_scene::note_image::MAX_BYTES)),
        )
        .route("/api/images/{reference}", get(note_images::image))
        .route("/api/scenes/{id}/revisions", get(edits::revisions))
        .route("/api/scenes/{id}/scene.json", get(edits::manifest))
        .route("/api/scenes/{id}/download", get(edits::download))
        .route("/api/spectra", get(edits::spectra))
        .route("/api/sun-path", get(edits::sun_path))
        .route("/api/jobs/{id}/display.png", get(display::display))
        .route("/api/jobs/{id}/luminance", get(display::luminance))
        .route("/api/jobs/{id}/luminance.png", get(display::false_colour))
        .route("/api/jobs/{id}/painting.png", get(painting::painting))
        .route("/api/jobs/{id}/pixel", get(pixel::pixel))
        .route("/api/scenes/{id}/grids", post(grids::compute))
        .route("/api/jobs/{id}/illuminance", get(grids::illuminance))
        .route("/api/jobs/{id}/illuminance/{name}", get(grids::file))
        .route("/api/compare", get(compare::compare))
        .route("/api/compare/delta-e.png", get(compare::picture))
        .route_layer(middleware::from_fn_with_state(studio.clone(), signed_in));
    Router::new()
        .route("/api/session", post(api::sign_in).delete(api::sign_out))
        .merge(api)
        .route("/", get(page::index))
        .route("/static/{*file}", get(page::file))
        .fallback(no_such_route)
        .with_state(studio)
}

/// The coordinator's certificate chain and private key (PEM), to serve the studio over TLS.
#[derive(Clone)]
pub struct TlsPem {
    pub cert: Vec<u8>,
    pub key: Vec<u8>,
}

/// A TLS acceptor for `pem` (TLS 1.2 and 1.3, ring, as the gRPC door has).
fn acceptor(pem: &TlsPem) -> Result<tokio_rustls::TlsAcceptor> {
    use tokio_rustls::rustls::pki_types::pem::PemObject;
    use tokio_rustls::rustls::pki_types::{CertificateDer, PrivateKeyDer};
    let chain = CertificateDer::pem_slice_iter(&pem.cert)
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(StudioError::TlsChain)?;
    let key = PrivateKeyDer::from_pem_slice(&pem.key).map_err(StudioError::TlsKey)?;
    let provider = Arc::new(tokio_rustls::rustls::crypto::ring::default_provider());
    let config = tokio_rustls::rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(StudioError::TlsVersions)?
        .with_no_client_auth()
        .with_single_cert(chain, key)
        .map_err(StudioError::TlsPair)?;
    Ok(tokio_rustls::TlsAcceptor::from(Arc::new(config)))
}

/// Binds `listen` (port 0 picks a free port) and serves the studio until `stop` turns true,
/// over TLS when `tls` is given. Returns the bound address and the serving task.
pub async fn serve(
    listen: SocketAddr,
    farm: Arc<Farm>,
    tokens: Tokens,
    stop: watch::Receiver<bool>,
    tls: Option<TlsPem>,
    limits: ConnectionLimits,
) -> Result<(SocketAddr, JoinHandle<()>)> {
    let acceptor = tls.as_ref().map(acceptor).transpose()?;
    let listener = TcpListener::bind(listen)
        .await
        .map_err(|source| StudioError::Listen { addr: listen, source })?;
    let addr = listener.local_addr().map_err(StudioError::LocalAddr)?;
    let listener = GuardedListener::new(listener, limits);
    let events = events::Events::new();
    let studio = Arc::new(Studio {
        farm: farm.clone(),
        gate: session::Gate::new(tokens, acceptor.is_some()),
        events: events.clone(),
        previews: preview::Previews::default(),
        stop: stop.clone(),
    });
    tokio::spawn(events.pump(farm, stopped(stop.clone())));
    let app = router(studio).layer(middleware::from_fn(working));
    let task = match acceptor {
        None => {
            info!(%addr, "studio on http://{addr}/");
            tokio::spawn(async move {
                let app = app.into_make_service_with_connect_info::<ConnectionBusy>();
                let serving = axum::serve(listener, app).with_graceful_shutdown(stopped(stop));
                if let Err(e) = serving.await {
                    warn!(error = %e, "the studio stopped");
                }
            })
        }
        Some(acceptor) => {
            info!(%addr, "studio on https://{addr}/");
            tokio::spawn(serve_tls(listener, acceptor, app, stop))
        }
    };
    Ok((addr, task))
}

/// Accepts TLS connections until `stop`, each served as HTTP/1.1 by the studio's router; a
/// handshake that fails (a client that does not trust the certificate) closes that connection
/// only.
async fn serve_tls(
    listener: GuardedListener,
    acceptor: tokio_rustls::TlsAcceptor,
    app: Router,
    stop: watch::Receiver<bool>,
) {
    let ended = stopped(stop);
    tokio::pin!(ended);
    loop {
        let (tcp, peer) = tokio::select! {
            () = &mut ended => return,
            accepted = listener.accept() => accepted,
        };
        let busy = ConnectInfo(ConnectionBusy(tcp.busy()));
        let (acceptor, app) = (acceptor.clone(), app.clone().layer(axum::Extension(busy)));
        tokio::spawn(async move {
            let tls = match acceptor.accept(tcp).await {
                Ok(tls) => tls,
                Err(e) => {
                    tracing::debug!(%peer, error = %e, "a studio TLS handshake failed");
                    return;
                }
            };
            let service = hyper_util::service::TowerToHyperService::new(app);
            let io = hyper_util::rt::TokioIo::new(tls);
            if let Err(e) =
                hyper::server::conn::http1::Builder::new().serve_connection(io, service).await
            {
                tracing::debug!(%peer, error = %e, "a studio connection ended");
            }
        });
    }
}
