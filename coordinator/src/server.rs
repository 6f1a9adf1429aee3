//! The coordinator process: its command line, and serving both services on one address until
//! asked to stop.

use anyhow::{Context, Result, bail};
use restauro_farm::auth::{Role, Tokens};
use restauro_farm::callers::CallerLimits;
use restauro_farm::error::FarmError;
use restauro_farm::farm::{CheckPolicy, Config, Farm, open_store};
use restauro_farm::grpc::{RenderService, WorkService};
use restauro_farm::lead::{Lead, LeadConfig, StandbyProbe, StandbyState};
use restauro_farm::scheduler;
use restauro_farm::store::Store;
use restauro_ops::connections::{ConnectionLimits, GuardedListener, GuardedStream};
use restauro_ops::signal::stop_signal;
use restauro_ops::signal::stopped;
use restauro_ops::token::read_token;
use restauro_proto::pb::render_server::RenderServer;
use restauro_proto::pb::work_server::WorkServer;
use restauro_scene::limits::{LimitArgs, Limits};
use std::io::Write as _;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use tokio::net::TcpListener;
use tonic::service::interceptor::InterceptedService;
use tracing::info;

/// The largest request the coordinator decodes: a chunk of an asset or a tile is 1 MiB.
pub const MAX_MESSAGE_BYTES: usize = 4 << 20;

#[derive(clap::Args, Clone, Debug)]
pub struct CoordinatorArgs {
    /// The address to serve on; port 0 picks a free port (printed as `listening on ADDR`).
    #[arg(long, default_value = "127.0.0.1:7878")]
    pub listen: SocketAddr,
    /// The folder of the store and the results; a restart on the same folder resumes its jobs.
    #[arg(long, default_value = "restauro-data")]
    pub data: PathBuf,
    /// A file holding the clients' bearer token (else RESTAURO_CLIENT_TOKEN).
    #[arg(long)]
    pub client_token_file: Option<PathBuf>,
    /// Keep the store in this PostgreSQL database (`postgres://USER[:PASSWORD]@HOST[:PORT]/DB`,
    /// else RESTAURO_STORE) instead of the file `store.redb` in --data. Its schema is created
    /// and migrated at start. Several coordinators may share it: one leads, the others stand
    /// by (--lead-ttl-s). The assets and results stay in --data, unless --objects names a bucket.
    /// TLS as libpq's sslmode says (`?sslmode=verify-full&sslrootcert=CA.pem` to check the
    /// server's certificate).
    #[arg(long, env = "RESTAURO_STORE", hide_env_values = true)]
    pub store: Option<String>,
    /// Keep the scenes' files and the results in this S3 bucket too (`s3://BUCKET[/PREFIX]`,
    /// else RESTAURO_OBJECTS), so every coordinator of a fleet finds them; --data is then a
    /// working copy. The endpoint and credentials come from AWS_ENDPOINT_URL, AWS_REGION,
    /// AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY (AWS_ALLOW_HTTP=true for plain HTTP).
    #[arg(long, env = "RESTAURO_OBJECTS")]
    pub objects: Option<String>,
    /// With --store postgres://…: seconds the lead among coordinators on that database lives
    /// unrenewed. One coordinator leads (it renews every third of this); the others stand by,
    /// not ready, and one takes over once the lead lapses. A leader that cannot renew within
    /// two thirds of it stops serving and exits. From 1 to 3600.
    #[arg(long, default_value_t = 6.0)]
    pub lead_ttl_s: f64,
    /// A file holding the workers' bearer token (else RESTAURO_WORKER_TOKEN).
    #[arg(long)]
    pub worker_token_file: Option<PathBuf>,
    /// Seconds a leased tile may take before it is given to another worker.
    #[arg(long, default_value_t = 120.0)]
    pub lease_timeout_s: f64,
    /// Seconds of silence after which a worker is dropped and its tiles requeued.
    #[arg(long, default_value_t = 10.0)]
    pub heartbeat_timeout_s: f64,
    /// Unfinished jobs accepted at once.
    #[arg(long, default_value_t = 64)]
    pub max_jobs: usize,
    /// Uploads in progress at once, in MiB: an upload waits for room, and is refused after a
    /// minute without.
    #[arg(long, default_value_t = 1024)]
    pub max_upload_mb: u64,
    /// Scenes loaded at once — to check a submission, to build the studio's view of a scene —
    /// each holding its whole scene in memory; more wait their turn.
    #[arg(long, default_value_t = 2)]
    pub max_scene_loads: usize,
    /// What a job's scene and render may ask (sent to the workers with each job).
    #[command(flatten)]
    pub limits: LimitArgs,
    /// Connections open at once on each listener (gRPC, studio, metrics); a connection beyond
    /// it is closed as it comes.
    #[arg(long, default_value_t = 512)]
    pub max_connections: usize,
    /// Seconds a new connection has to send the start of its first request.
    #[arg(long, default_value_t = 10.0)]
    pub first_request_timeout_s: f64,
    /// Seconds a connection, a download's reader or an upload may stay silent before it is
    /// cut (and an upload's share of the budget given back).
    #[arg(long, default_value_t = 120.0)]
    pub idle_timeout_s: f64,
    /// Requests (HTTP/2 streams) open at once on one gRPC connection.
    #[arg(long, default_value_t = 64)]
    pub max_streams_per_connection: u32,
    /// Files (results to clients, assets to workers) sent at once; a request beyond it is
    /// refused, to be tried again.
    #[arg(long, default_value_t = 32)]
    pub max_downloads: usize,
    /// The share of a trusted worker's tile results rendered a second time on a worker of
    /// another identity and compared byte for byte (tiles are bit-identical whichever worker
    /// renders them). A mismatch is settled by a third worker, and the worker found wrong is
    /// quarantined. 0 checks nothing.
    #[arg(long, default_value_t = 0.05)]
    pub check_rate: f64,
    /// The share of a new worker's results checked, until --trust-after of them are confirmed.
    #[arg(long, default_value_t = 0.5)]
    pub check_rate_new: f64,
    /// Results of a worker confirmed by checks before --check-rate applies to it.
    #[arg(long, default_value_t = 4)]
    pub trust_after: u32,
    /// Skip the Retinex stage (and its files).
    #[arg(long)]
    pub no_retinex: bool,
    /// Serve TLS with this certificate chain (PEM; needs --tls-key; else RESTAURO_TLS_CERT).
    #[arg(long, env = "RESTAURO_TLS_CERT", requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// The private key of --tls-cert (PEM; else RESTAURO_TLS_KEY).
    #[arg(long, env = "RESTAURO_TLS_KEY", requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// The operations endpoint: where /metrics and health are served, and who may read them.
    #[command(flatten)]
    pub metrics: restauro_ops::metrics_access::MetricsArgs,
    /// Serve the studio, the restorer's web page, over HTTP on this address (else
    /// RESTAURO_STUDIO_LISTEN; off when neither is given). Port 0 picks a free port, printed as
    /// `studio on http://ADDR/`.
    #[arg(long, env = "RESTAURO_STUDIO_LISTEN")]
    pub studio_listen: Option<SocketAddr>,
    /// Let scenes sent to the studio name files on loopback, private and link-local addresses
    /// (an intranet's servers). Off by default: the coordinator fetches for its users, who must
    /// not reach the farm's own network through it.
    #[arg(long)]
    pub fetch_private_urls: bool,
    /// Exit when standard input closes (an embedded cluster's processes end with their parent).
    #[arg(long, hide = true)]
    pub exit_with_stdin: bool,
    /// Fault injection for tests: hold every store commit this many milliseconds (a slow
    /// disk), so that a test can act while a tile is being committed.
    #[arg(long, hide = true, default_value_t = 0)]
    pub fault_commit_delay_ms: u64,
}

/// The server's TLS certificate and key, read and checked before anything listens.
fn tls_identity(args: &CoordinatorArgs) -> Result<Option<restauro_studio::TlsPem>> {
    let (Some(cert), Some(key)) = (&args.tls_cert, &args.tls_key) else {
        return Ok(None);
    };
    let read = |path: &Path, what: &str, marker: &str| -> Result<Vec<u8>> {
        let pem = std::fs::read(path)
            .with_context(|| format!("reading the TLS {what} {}", path.display()))?;
        if !String::from_utf8_lossy(&pem).contains(marker) {
            bail!("the TLS {what} {} is not PEM (no `{marker}` line)", path.display());
        }
        Ok(pem)
    };
    let cert = read(cert, "certificate", "-----BEGIN CERTIFICATE-----")?;
    let key = read(key, "key", "PRIVATE KEY-----")?;
    Ok(Some(restauro_studio::TlsPem { cert, key }))
}

/// The caller limits of the flags.
fn caller_limits(args: &CoordinatorArgs) -> Result<CallerLimits> {
    let counts = [
        args.max_connections,
        args.max_streams_per_connection as usize,
        args.max_downloads,
        args.max_scene_loads,
    ];
    if counts.contains(&0) {
        bail!(
            "--max-connections, --max-streams-per-connection, --max-downloads and \
             --max-scene-loads must be at least 1"
        );
    }
    Ok(CallerLimits {
        connections: ConnectionLimits {
            max_connections: args.max_connections,
            first_bytes: ConnectionLimits::default().first_bytes,
            first_bytes_timeout: seconds(
                args.first_request_timeout_s,
                "--first-request-timeout-s",
            )?,
            idle_timeout: seconds(args.idle_timeout_s, "--idle-timeout-s")?,
        },
        max_streams_per_connection: args.max_streams_per_connection,
        max_downloads: args.max_downloads,
    })
}

fn share(value: f64, flag: &str) -> Result<f64> {
    if !(0.0..=1.0).contains(&value) {
        bail!("{flag} {value}: use a share between 0 (no check) and 1 (every result)");
    }
    Ok(value)
}

fn seconds(value: f64, flag: &str) -> Result<Duration> {
    if !(value.is_finite() && value > 0.0 && value < 1e6) {
        bail!("{flag} {value}: use a number of seconds above 0");
    }
    Ok(Duration::from_secs_f64(value))
}

/// The lead's time to live: renewed every third of it, so shorter than a second would renew
/// faster than a loaded database answers; longer than an hour would leave the farm without a
/// leader that long after a crash.
fn lead_ttl(value: f64) -> Result<Duration> {
    if !(1.0..=3600.0).contains(&value) {
        bail!(
            "--lead-ttl-s {value}: give seconds from 1 to 3600 (a standby takes over within \
             about that long after the leader is lost; 6 by default)"
        );
    }
    Ok(Duration::from_secs_f64(value))
}

pub fn run(args: &CoordinatorArgs) -> Result<()> {
    let client = read_token(
        args.client_token_file.as_deref(),
        "RESTAURO_CLIENT_TOKEN",
        "--client-token-file",
    )?;
    let worker = read_token(
        args.worker_token_file.as_deref(),
        "RESTAURO_WORKER_TOKEN",
        "--worker-token-file",
    )?;
    if client == worker {
        bail!("the client and worker tokens are the same; give each role its own token");
    }
    // Files that scenes sent to the studio name by URL: fetched into the data folder.
    restauro_assets::remote::set_policy(restauro_assets::remote::Policy {
        public_only: !args.fetch_private_urls,
        cache_dir: Some(args.data.join("downloads")),
    });
    let config = Config {
        store: args.store.clone(),
        objects: args.objects.clone(),
        data_dir: args.data.clone(),
        tokens: Tokens::new(&client, &worker),
        limits: Limits::from(&args.limits),
        max_jobs: args.max_jobs.max(1),
        max_upload_bytes: args.max_upload_mb.max(1).saturating_mul(1 << 20),
        max_scene_loads: args.max_scene_loads,
        scheduler: scheduler::Config {
            lease_timeout: seconds(args.lease_timeout_s, "--lease-timeout-s")?,
            heartbeat_timeout: seconds(args.heartbeat_timeout_s, "--heartbeat-timeout-s")?,
            ..scheduler::Config::default()
        },
        checks: CheckPolicy {
            rate: share(args.check_rate, "--check-rate")?,
            new_worker_rate: share(args.check_rate_new, "--check-rate-new")?,
            trust_after: args.trust_after,
        },
        retinex: !args.no_retinex,
        commit_delay: Duration::from_millis(args.fault_commit_delay_ms),
        callers: caller_limits(args)?,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let tls = tls_identity(args)?;
    let exit_with_stdin = args.exit_with_stdin;
    let metrics = args.metrics.endpoint()?;
    let endpoints = Endpoints { grpc: args.listen, metrics, studio: args.studio_listen };
    let lead = LeadConfig::for_process(&args.listen.to_string(), lead_ttl(args.lead_ttl_s)?);
    let served =
        runtime.block_on(serve(config, endpoints, tls, lead, stop_signal(exit_with_stdin)));
    // A store call may hang (a database cut off); the process ends all the same.
    runtime.shutdown_timeout(Duration::from_secs(2));
    served
}

/// Where the coordinator serves.
#[derive(Clone, Copy, Debug)]
pub struct Endpoints {
    /// Both gRPC services, gRPC health and reflection.
    pub grpc: SocketAddr,
    /// Prometheus metrics and HTTP health, when given, and who may read the metrics.
    pub metrics: Option<(SocketAddr, restauro_ops::metrics_access::Access)>,
    /// The studio, when given.
    pub studio: Option<SocketAddr>,
}

/// Serves until `stop` resolves: opens the store, takes the lead among the coordinators on it
/// (standing by meanwhile, see [`stand_by`]), opens the farm, binds the gRPC address and the side
/// doors (metrics, studio), prints where each listens, then serves the gRPC services until the
/// stop — or until the lead is lost, which ends the process with an error (a supervisor
/// restarts it, as a standby).
pub async fn serve(
    config: Config,
    mut endpoints: Endpoints,
    tls: Option<restauro_studio::TlsPem>,
    lead: LeadConfig,
    stop: impl Future<Output = ()> + Send + 'static,
) -> Result<()> {
    let listen = endpoints.grpc;
    // One stop for every server.
    let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
    tokio::spawn(async move {
        stop.await;
        let _ = stop_tx.send(true);
    });
    let callers = config.callers;
    let server = grpc_server(callers, tls.as_ref())?;
    let tokens = config.tokens.clone();
    let data = config.data_dir.clone();
    let opening = config.clone();
    let store = tokio::task::spawn_blocking(move || open_store(&opening))
        .await?
        .map_err(FarmError::StoreAtStart)?;
    let store = Arc::new(store);
    let Some(lead) = stand_by(&store, &lead, &mut endpoints, callers, &stop_rx).await? else {
        info!("stopped while standing by");
        return Ok(());
    };
    let farm = tokio::task::spawn_blocking(move || Farm::open_on(config, store)).await??;
    let listener =
        TcpListener::bind(listen).await.with_context(|| format!("listening on {listen}"))?;
    let addr = listener.local_addr()?;
    info!(%addr, data = %data.display(), tls = tls.is_some(), "coordinator listening");
    let doors = SideDoors::open(&endpoints, &farm, &tokens, tls, callers, &stop_rx).await?;
    doors.print(addr)?;
    let listener = GuardedListener::new(listener, callers.connections);
    let incoming = restauro_ops::connections::incoming(listener, Connection);
    let timer = tokio::spawn(farm.clone().run_timer());
    let services = grpc_services(server, farm, &tokens).await?;
    tokio::select! {
        served = services.serve_with_incoming_shutdown(incoming, stopped(stop_rx)) => served?,
        why = lead.lost() => {
            tracing::error!("the lead is lost: {why}; this coordinator stops serving");
            bail!("the lead is lost: {why}");
        }
    }
    timer.abort();
    for (_, task) in doors.metrics.into_iter().chain(doors.studio) {
        let _ = task.await;
    }
    lead.release();
    info!("coordinator stopped");
    Ok(())
}

/// Waits to lead on `store` (at once on a file store). Meanwhile the operations endpoint, if
/// asked for, serves a standby's probe — alive, not ready, saying who leads — and is printed as
/// `standby, metrics on ADDR`; it is closed before the leader's opens on the same address.
/// `None` when a stop came first.
async fn stand_by(
    store: &Arc<Store>,
    config: &LeadConfig,
    endpoints: &mut Endpoints,
    callers: CallerLimits,
    stop: &tokio::sync::watch::Receiver<bool>,
) -> Result<Option<Lead>> {
    let state = StandbyState::default();
    // A coordinator that leads at once never stands by.
    if let Some(lead) = restauro_farm::lead::try_once(store, config, &state).await {
        return Ok(Some(lead));
    }
    let mut door = None;
    if let Some((at, access)) = endpoints.metrics {
        let (close, closed) = tokio::sync::watch::channel(false);
        let probe: Arc<dyn restauro_ops::endpoint::Probe> =
            Arc::new(StandbyProbe::new(state.clone()));
        let (bound, task) =
            restauro_ops::endpoint::serve(at, probe, access, callers.connections, stopped(closed))
                .await?;
        let mut out = std::io::stdout().lock();
        writeln!(out, "standby, metrics on {bound}")?;
        out.flush()?;
        endpoints.metrics = Some((bound, access));
        door = Some((close, task));
    }
    let lead = restauro_farm::lead::take(store, config, &state, &mut stop.clone()).await;
    if let Some((close, task)) = door {
        let _ = close.send(true);
        let _ = task.await;
    }
    Ok(lead)
}

/// The gRPC server within the caller limits, over TLS when `tls` is given. Every call is in a
/// span named by its method, so a log line says which call it belongs to; calls about one tile
/// record its job, tile and worker in the span. HTTP/2 pings a quiet connection, so that one
/// whose peer has gone (or will not answer) is closed, and an honest one is never silent long
/// enough for the idle timeout.
fn grpc_server(
    callers: CallerLimits,
    tls: Option<&restauro_studio::TlsPem>,
) -> Result<tonic::transport::Server> {
    let ping = callers.idle().min(Duration::from_secs(30)) / 2;
    let mut server = tonic::transport::Server::builder()
        .max_concurrent_streams(callers.max_streams_per_connection)
        .http2_keepalive_interval(Some(ping))
        .http2_keepalive_timeout(Some(ping))
        .trace_fn(|request| {
            tracing::info_span!(
                "grpc",
                method = %request.uri().path(),
                job = tracing::field::Empty,
                tile = tracing::field::Empty,
                worker = tracing::field::Empty,
            )
        });
    if let Some(pem) = tls {
        let identity = tonic::transport::Identity::from_pem(&pem.cert, &pem.key);
        server = server
            .tls_config(tonic::transport::ServerTlsConfig::new().identity(identity))
            .context("configuring TLS")?;
    }
    Ok(server)
}

/// A side door's bound address and its serving task.
type Door = (SocketAddr, tokio::task::JoinHandle<()>);

/// The listeners beside the gRPC one: the operations endpoint and the studio, when asked for.
struct SideDoors {
    metrics: Option<Door>,
    studio: Option<Door>,
    tls: bool,
}

impl SideDoors {
    async fn open(
        endpoints: &Endpoints,
        farm: &Arc<Farm>,
        tokens: &Tokens,
        tls: Option<restauro_studio::TlsPem>,
        callers: CallerLimits,
        stop: &tokio::sync::watch::Receiver<bool>,
    ) -> Result<SideDoors> {
        let has_tls = tls.is_some();
        let metrics = match endpoints.metrics {
            Some((at, access)) => {
                let probe: Arc<dyn restauro_ops::endpoint::Probe> = farm.clone();
                let (limits, stop) = (callers.connections, stopped(stop.clone()));
                Some(restauro_ops::endpoint::serve(at, probe, access, limits, stop).await?)
            }
            None => None,
        };
        let studio = match endpoints.studio {
            Some(at) => {
                let (tokens, stop, limits) = (tokens.clone(), stop.clone(), callers.connections);
                Some(restauro_studio::serve(at, farm.clone(), tokens, stop, tls, limits).await?)
            }
            None => None,
        };
        Ok(SideDoors { metrics, studio, tls: has_tls })
    }

    /// Where each listens, on standard output: the embedded cluster and the tests read the
    /// addresses from here.
    fn print(&self, grpc: SocketAddr) -> Result<()> {
        let mut out = std::io::stdout().lock();
        writeln!(out, "listening on {grpc}")?;
        if let Some((at, _)) = &self.metrics {
            writeln!(out, "metrics on {at}")?;
        }
        if let Some((at, _)) = &self.studio {
            let scheme = if self.tls { "https" } else { "http" };
            writeln!(out, "studio on {scheme}://{at}/")?;
        }
        out.flush()?;
        Ok(())
    }
}

/// The services on the gRPC address: `Render` for clients and `Work` for workers, each behind
/// its role's token; the standard gRPC health service, without a token (probes carry none); and
/// reflection, so that `grpcurl` lists and calls the services without the .proto file.
async fn grpc_services(
    mut server: tonic::transport::Server,
    farm: Arc<Farm>,
    tokens: &Tokens,
) -> Result<tonic::transport::server::Router> {
    let render = InterceptedService::new(
        RenderServer::new(RenderService(farm.clone())).max_decoding_message_size(MAX_MESSAGE_BYTES),
        tokens.interceptor(Role::Client),
    );
    let work = InterceptedService::new(
        WorkServer::new(WorkService(farm)).max_decoding_message_size(MAX_MESSAGE_BYTES),
        tokens.interceptor(Role::Worker),
    );
    let (health, health_service) = tonic_health::server::health_reporter();
    health.set_serving::<RenderServer<RenderService>>().await;
    health.set_serving::<WorkServer<WorkService>>().await;
    let reflection = || {
        tonic_reflection::server::Builder::configure()
            .register_encoded_file_descriptor_set(restauro_proto::FILE_DESCRIPTOR_SET)
            .register_encoded_file_descriptor_set(tonic_health::pb::FILE_DESCRIPTOR_SET)
    };
    // Both versions of reflection: older grpcurl and other tools speak only v1alpha.
    let reflection_v1 = reflection().build_v1().context("building the reflection service")?;
    let reflection_v1alpha =
        reflection().build_v1alpha().context("building the reflection service")?;
    Ok(server
        .add_service(health_service)
        .add_service(reflection_v1)
        .add_service(reflection_v1alpha)
        .add_service(render)
        .add_service(work))
}

/// An accepted gRPC connection, within the caller limits, as tonic takes it.
struct Connection(GuardedStream);

impl tonic::transport::server::Connected for Connection {
    type ConnectInfo = tonic::transport::server::TcpConnectInfo;

    fn connect_info(&self) -> Self::ConnectInfo {
        self.0.tcp().connect_info()
    }
}

impl tokio::io::AsyncRead for Connection {
    fn poll_read(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        buf: &mut tokio::io::ReadBuf<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::pin::Pin::new(&mut self.0).poll_read(cx, buf)
    }
}

impl tokio::io::AsyncWrite for Connection {
    fn poll_write(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
        data: &[u8],
    ) -> std::task::Poll<std::io::Result<usize>> {
        std::pin::Pin::new(&mut self.0).poll_write(cx, data)
    }

    fn poll_flush(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::pin::Pin::new(&mut self.0).poll_flush(cx)
    }

    fn poll_shutdown(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::pin::Pin::new(&mut self.0).poll_shutdown(cx)
    }
}
