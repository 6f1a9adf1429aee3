//! The coordinator's two gRPC services, `Render` for clients and `Work` for workers: each call
//! converts its request to domain types (refusing what they cannot hold), calls the [`Farm`],
//! and converts the answer back. No decision is made here.

use crate::callers::next_within;
use crate::error::{FarmError, Result};
use crate::farm::{Expected, Farm, QuarantineRecord, Reported, WorkerStatus};
use crate::ids::{JobId, Session};
use crate::lease::LeaseClaim;
use restauro_proto::convert::WireError;
use restauro_proto::{self as pb, PROTOCOL_VERSION};
use restauro_scene::job::JobSpec;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::{Stream, StreamExt};
use tonic::{Request, Response, Status, Streaming};

type ReplyStream<T> = Pin<Box<dyn Stream<Item = Result<T, Status>> + Send + 'static>>;

/// The client-facing service.
pub struct RenderService(pub Arc<Farm>);
/// The worker-facing service.
pub struct WorkService(pub Arc<Farm>);

impl From<WorkerStatus> for pb::WorkerStatus {
    fn from(w: WorkerStatus) -> Self {
        pb::WorkerStatus {
            worker_id: w.id.0,
            name: w.name,
            capacity: w.capacity,
            leases: w.leases,
            tiles_done: w.done,
            tiles_failed: w.failed,
            last_seen_s: w.last_seen_s,
            build: w.build,
            tiles_confirmed: w.confirmed,
        }
    }
}

impl From<QuarantineRecord> for pb::QuarantinedWorker {
    fn from(q: QuarantineRecord) -> Self {
        pb::QuarantinedWorker {
            name: q.name,
            identity: q.identity,
            reason: q.reason,
            since_unix_ms: q.since_unix_ms,
        }
    }
}

/// A job id from the wire.
fn job_id(text: &str) -> Result<JobId> {
    Ok(JobId::parse(text)?)
}

/// The version a request carries in its body (the interceptor checked the header's).
fn check_version(version: u32, role: &'static str) -> Result<()> {
    if version != PROTOCOL_VERSION {
        let theirs = version.to_string();
        return Err(FarmError::ProtocolVersion { theirs, ours: PROTOCOL_VERSION, role });
    }
    Ok(())
}

fn session(s: Option<&pb::WorkerSession>) -> Result<Session> {
    Ok(Session::try_from(s)?)
}

fn claim(lease: Option<&pb::Lease>) -> Result<LeaseClaim> {
    Ok(LeaseClaim::try_from(lease.ok_or_else(|| WireError::missing("lease"))?)?)
}

#[tonic::async_trait]
impl pb::render_server::Render for RenderService {
    async fn missing_assets(
        &self,
        request: Request<pb::AssetList>,
    ) -> Result<Response<pb::AssetList>, Status> {
        let references = self.0.missing_assets(request.into_inner().references)?;
        Ok(Response::new(pb::AssetList { references }))
    }

    async fn upload_asset(
        &self,
        request: Request<Streaming<pb::Chunk>>,
    ) -> Result<Response<pb::AssetList>, Status> {
        let mut stream = request.into_inner();
        let first = stream.message().await?.ok_or_else(|| {
            FarmError::from(WireError::new("chunk", "an upload needs at least one chunk"))
        })?;
        let reference = first.name.clone();
        let mut upload = self.0.begin_upload(&reference, first.total_bytes).await?;
        upload.write(&first.data).await?;
        let idle = self.0.config.callers.idle();
        let what = || format!("the upload of {reference}");
        while let Some(chunk) = next_within(&mut stream, idle, what).await? {
            upload.write(&chunk.data).await?;
        }
        let bytes = upload.finish().await?;
        self.0.metrics.asset_bytes_received.inc_by(bytes);
        Ok(Response::new(pb::AssetList { references: vec![reference] }))
    }

    async fn submit_job(
        &self,
        request: Request<pb::SubmitJobRequest>,
    ) -> Result<Response<pb::JobStatus>, Status> {
        let req = request.into_inner();
        check_version(req.protocol_version, "client")?;
        let spec = JobSpec::try_from(&req).map_err(FarmError::from)?;
        let status = self.0.submit(req.manifest_json, spec).await?;
        Ok(Response::new(status.into()))
    }

    type WatchJobStream = ReplyStream<pb::JobStatus>;

    async fn watch_job(
        &self,
        request: Request<pb::JobRef>,
    ) -> Result<Response<Self::WatchJobStream>, Status> {
        let id = job_id(&request.into_inner().job_id)?;
        let statuses = self.0.watch(&id)?;
        let stream = ReceiverStream::new(statuses).map(|s| Ok(pb::JobStatus::from(s)));
        Ok(Response::new(Box::pin(stream)))
    }

    type FetchResultStream = ReplyStream<pb::Chunk>;

    async fn fetch_result(
        &self,
        request: Request<pb::FetchResultRequest>,
    ) -> Result<Response<Self::FetchResultStream>, Status> {
        let req = request.into_inner();
        let path = self.0.result_path(&job_id(&req.job_id)?, &req.name)?;
        let farm = self.0.clone();
        let sent = move |n| {
            farm.metrics.result_bytes_sent.inc_by(n);
        };
        Ok(Response::new(self.0.downloads.send(req.name, path, sent)?))
    }

    async fn cancel_job(
        &self,
        request: Request<pb::JobRef>,
    ) -> Result<Response<pb::JobStatus>, Status> {
        let status = self.0.cancel(&job_id(&request.into_inner().job_id)?)?;
        Ok(Response::new(status.into()))
    }

    async fn list_jobs(
        &self,
        _request: Request<pb::ListJobsRequest>,
    ) -> Result<Response<pb::JobList>, Status> {
        let jobs = self.0.jobs().into_iter().map(Into::into).collect();
        Ok(Response::new(pb::JobList { jobs, problem: self.0.problem().unwrap_or_default() }))
    }

    async fn list_workers(
        &self,
        _request: Request<pb::ListWorkersRequest>,
    ) -> Result<Response<pb::WorkerList>, Status> {
        let workers = self.0.workers().into_iter().map(Into::into).collect();
        let quarantined = self.0.quarantined().into_iter().map(Into::into).collect();
        Ok(Response::new(pb::WorkerList { workers, quarantined }))
    }
}

fn reply(accepted: bool, known: bool) -> Response<pb::ReportReply> {
    Response::new(pb::ReportReply { accepted, known })
}

#[tonic::async_trait]
impl pb::work_server::Work for WorkService {
    async fn register(
        &self,
        request: Request<pb::RegisterRequest>,
    ) -> Result<Response<pb::RegisterReply>, Status> {
        let req = request.into_inner();
        check_version(req.protocol_version, "worker")?;
        let (session, heartbeat) =
            self.0.register(&req.name, req.capacity, &req.build, &req.identity)?;
        Ok(Response::new(pb::RegisterReply {
            session: Some(session.into()),
            heartbeat_ms: u32::try_from(heartbeat.as_millis()).unwrap_or(u32::MAX),
        }))
    }

    async fn heartbeat(
        &self,
        request: Request<pb::HeartbeatRequest>,
    ) -> Result<Response<pb::HeartbeatReply>, Status> {
        let session = session(request.get_ref().session.as_ref())?;
        Ok(Response::new(pb::HeartbeatReply { known: self.0.heartbeat(&session) }))
    }

    async fn pull_leases(
        &self,
        request: Request<pb::PullRequest>,
    ) -> Result<Response<pb::PullReply>, Status> {
        let req = request.into_inner();
        let session = session(req.session.as_ref())?;
        let wait = Duration::from_millis(u64::from(req.wait_ms));
        Ok(Response::new(match self.0.pull(&session, req.max, wait).await {
            Some(leases) => pb::PullReply { leases, known: true },
            None => pb::PullReply { leases: Vec::new(), known: false },
        }))
    }

    async fn report_tile(
        &self,
        request: Request<Streaming<pb::TileChunk>>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let mut stream = request.into_inner();
        let header = match stream.message().await?.and_then(|c| c.part) {
            Some(pb::tile_chunk::Part::Header(h)) => h,
            _ => {
                return Err(FarmError::from(WireError::new(
                    "header",
                    "a tile report starts with its header",
                ))
                .into());
            }
        };
        let session = session(header.session.as_ref())?;
        let claim = claim(header.lease.as_ref())?;
        let span = tracing::Span::current();
        span.record("job", claim.job.as_str());
        span.record("tile", claim.tile);
        span.record("worker", session.worker.0);
        // Decided before the pixels are read: a stale or unknown report is answered at once.
        let (rect, layout) = match self.0.expect_report(&session, &claim)? {
            Expected::UnknownSession => return Ok(reply(false, false)),
            Expected::Stale => return Ok(reply(false, true)),
            Expected::Tile { rect, layout } => (rect, layout),
        };
        let (image_bytes, spectral_bytes) = restauro_image::framebuffer::tile_sizes(&rect, layout);
        let tile_error = |problem: String| FarmError::TileData {
            job: claim.job.clone(),
            tile: claim.tile,
            problem,
        };
        if header.xyz_bytes != image_bytes as u64 || header.spectral_bytes != spectral_bytes as u64
        {
            return Err(tile_error(format!(
                "{} + {} bytes announced, expected {image_bytes} + {spectral_bytes}",
                header.xyz_bytes, header.spectral_bytes
            ))
            .into());
        }
        let expected = image_bytes + spectral_bytes;
        let mut data = Vec::with_capacity(expected);
        let idle = self.0.config.callers.idle();
        let what = || format!("the report of tile {} of job {}", claim.tile, claim.job);
        while let Some(chunk) = next_within(&mut stream, idle, what).await? {
            match chunk.part {
                Some(pb::tile_chunk::Part::Data(d)) if data.len() + d.len() <= expected => {
                    data.extend_from_slice(&d);
                }
                Some(pb::tile_chunk::Part::Data(_)) => {
                    return Err(
                        tile_error(format!("more than the {expected} bytes announced")).into()
                    );
                }
                _ => return Err(tile_error("a tile report has one header".into()).into()),
            }
        }
        if data.len() != expected {
            return Err(
                tile_error(format!("{} bytes received, {expected} announced", data.len())).into()
            );
        }
        Ok(match self.0.report(&session, &claim, header.render_s, data).await? {
            Reported::UnknownSession => reply(false, false),
            Reported::Stale => reply(false, true),
            Reported::Accepted => reply(true, true),
        })
    }

    async fn fail_tile(
        &self,
        request: Request<pb::FailRequest>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let req = request.into_inner();
        let session = session(req.session.as_ref())?;
        let claim = claim(req.lease.as_ref())?;
        Ok(match self.0.fail(&session, &claim, &req.reason, req.retryable)? {
            None => reply(false, false),
            Some(accepted) => reply(accepted, true),
        })
    }

    async fn return_leases(
        &self,
        request: Request<pb::ReturnRequest>,
    ) -> Result<Response<pb::ReportReply>, Status> {
        let req = request.into_inner();
        let session = session(req.session.as_ref())?;
        let claims: Vec<LeaseClaim> =
            req.leases.iter().map(|l| claim(Some(l))).collect::<Result<_>>()?;
        Ok(match self.0.return_leases(&session, &claims, req.leaving)? {
            None => reply(false, false),
            Some(any) => reply(any, true),
        })
    }

    async fn fetch_job(
        &self,
        request: Request<pb::FetchJobRequest>,
    ) -> Result<Response<pb::WorkerJob>, Status> {
        let req = request.into_inner();
        let session = session(req.session.as_ref())?;
        let id = job_id(&req.job_id)?;
        let job = self.0.worker_job(&session, &id, req.frame)?;
        Ok(Response::new(pb::WorkerJob {
            job_id: id.to_string(),
            manifest_json: job.manifest_json,
            plan: Some((&job.plan).into()),
            limits: Some((&job.limits).into()),
            first_tile: job.first_tile,
        }))
    }

    type FetchAssetStream = ReplyStream<pb::Chunk>;

    async fn fetch_asset(
        &self,
        request: Request<pb::FetchAssetRequest>,
    ) -> Result<Response<Self::FetchAssetStream>, Status> {
        let req = request.into_inner();
        let session = session(req.session.as_ref())?;
        let path = self.0.asset_path(&session, &req.reference)?;
        let farm = self.0.clone();
        let sent = move |n| {
            farm.metrics.asset_bytes_sent.inc_by(n);
        };
        Ok(Response::new(self.0.downloads.send(req.reference, path, sent)?))
    }
}
