//! Talking to a coordinator as a client: upload a scene's assets, submit, watch with a progress
//! bar, fetch the results. A job's status is read from the wire once, here ([`read_status`]):
//! what these calls return is the domain's [`JobStatus`].

use crate::error::{ClusterError, io_doing, io_error};
use crate::progress::Progress;
use restauro_image::atomic_file;
use restauro_proto::job_status::JobStatus;
use restauro_proto::pb::render_client::RenderClient;
use restauro_proto::transport::Failover;
use restauro_proto::{self as pb, CHUNK_BYTES, Credentials, PROTOCOL_VERSION};
use restauro_scene::bundle::Bundle;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tonic::service::interceptor::InterceptedService;

pub type Client = RenderClient<InterceptedService<Failover, Credentials>>;

type Result<T, E = ClusterError> = std::result::Result<T, E>;

/// A Tokio runtime for a command's network calls.
pub fn runtime() -> Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(io_doing("starting the async runtime"))
}

/// Explains a refusal of the coordinator in the user's terms.
pub fn refused(what: &str, status: tonic::Status) -> ClusterError {
    let code = match status.code() {
        tonic::Code::Unauthenticated => "unauthenticated",
        tonic::Code::PermissionDenied => "forbidden",
        tonic::Code::InvalidArgument => "invalid",
        tonic::Code::NotFound => "not found",
        tonic::Code::FailedPrecondition => "refused",
        tonic::Code::ResourceExhausted => "over a limit",
        tonic::Code::Unavailable => "coordinator unreachable",
        _ => "failed",
    };
    ClusterError::Refused { what: what.to_owned(), code, message: status.message().to_owned() }
}

/// A client of a local (plaintext) coordinator.
pub async fn connect(url: &str, token: &str) -> Result<Client> {
    connect_as(url, token, None, PROTOCOL_VERSION).await
}

/// A client of the coordinator at `url` (`https://` for TLS, trusting `tls_ca` besides the
/// system's authorities), or of the one leading among several (`url`: their URLs separated by
/// commas; see `restauro_proto::transport::Failover`).
pub async fn connect_as(
    url: &str,
    token: &str,
    tls_ca: Option<&Path>,
    protocol_version: u32,
) -> Result<Client> {
    let credentials = Credentials::new(token, protocol_version)
        .map_err(|e| ClusterError::Token(e.to_string()))?;
    let endpoints = restauro_proto::transport::endpoints(url, tls_ca)?;
    let channel = restauro_proto::transport::connect(&endpoints).await.map_err(|(url, e)| {
        ClusterError::Connect { url, chain: restauro_proto::transport::error_chain(&e) }
    })?;
    Ok(RenderClient::with_interceptor(channel, credentials).max_decoding_message_size(8 << 20))
}

/// Uploads whichever of the bundle's files the coordinator lacks.
pub async fn upload(client: &mut Client, bundle: &Bundle) -> Result<()> {
    let references = bundle.references();
    let missing = client
        .missing_assets(pb::AssetList { references })
        .await
        .map_err(|s| refused("checking assets", s))?
        .into_inner()
        .references;
    for reference in missing {
        let hash = reference
            .strip_prefix("blake3:")
            .and_then(|r| r.split_once('.'))
            .map(|(h, _)| h)
            .ok_or_else(|| ClusterError::BadReference(reference.clone()))?;
        let data =
            bundle.files.get(hash).ok_or_else(|| ClusterError::NotInBundle(reference.clone()))?;
        let total = data.len() as u64;
        let mut chunks: Vec<pb::Chunk> = data
            .chunks(CHUNK_BYTES)
            .map(|c| pb::Chunk { name: String::new(), total_bytes: total, data: c.to_vec() })
            .collect();
        if chunks.is_empty() {
            chunks.push(pb::Chunk { name: String::new(), total_bytes: 0, data: Vec::new() });
        }
        chunks[0].name = reference.clone();
        client
            .upload_asset(tokio_stream::iter(chunks))
            .await
            .map_err(|s| refused(&format!("uploading {reference}"), s))?;
    }
    Ok(())
}

/// Submits a job of `bundle`, whose files are uploaded; `what` says what was being done in a
/// refusal (`submitting aosta.toml`).
pub async fn submit(
    client: &mut Client,
    bundle: &Bundle,
    spec: &restauro_scene::job::JobSpec,
    what: &str,
) -> Result<JobStatus> {
    let sent = client
        .submit_job(pb::convert::submit_request(bundle.canonical_json(), spec))
        .await
        .map_err(|s| refused(what, s))?
        .into_inner();
    read_status(sent)
}

/// A job status as the coordinator sent it, read once: one that holds no job (an id that is no
/// UUID, an unknown or unspecified state) is refused, naming the field.
pub fn read_status(sent: pb::JobStatus) -> Result<JobStatus> {
    Ok(JobStatus::try_from(sent)?)
}

/// Whether a watch that failed with `status` may simply be opened again: the coordinator
/// restarting (the connection reset, `h2 protocol error`, unreachable) rather than refusing.
fn transient(status: &tonic::Status) -> bool {
    matches!(
        status.code(),
        tonic::Code::Unavailable
            | tonic::Code::Unknown
            | tonic::Code::Internal
            | tonic::Code::Cancelled
            | tonic::Code::Aborted
            | tonic::Code::DeadlineExceeded
    )
}

/// How long a watch waits for an unreachable coordinator before it gives up.
const WATCH_PATIENCE: Duration = Duration::from_secs(600);

/// Follows a job to its end, with a progress bar (tiles done, rate, ETA) when asked. A
/// coordinator that restarts meanwhile is waited for (with back-off, up to ten minutes) and the
/// watch resumes where it was.
pub async fn watch(client: &mut Client, job_id: &str, show: bool) -> Result<JobStatus> {
    let bar = if show {
        Progress::new(
            "render",
            "tiles",
            Some(0),
            "{msg:>16} {bar:40} {pos}/{len} tiles, {per_sec}, {elapsed} elapsed, eta {eta}",
        )?
    } else {
        Progress::hidden()
    };
    let mut backoff = Duration::from_millis(100);
    let mut unreachable_since: Option<Instant> = None;
    let what = format!("watching job {job_id}");
    loop {
        let opened = client.watch_job(pb::JobRef { job_id: job_id.to_owned() }).await;
        // Why the watch stopped short of the job's end.
        let status: tonic::Status = match opened {
            Ok(stream) => {
                let mut stream = stream.into_inner();
                loop {
                    match stream.message().await {
                        Ok(Some(sent)) => {
                            let status =
                                read_status(sent).inspect_err(|_| bar.finish_and_clear())?;
                            unreachable_since = None;
                            backoff = Duration::from_millis(100);
                            bar.set_length(u64::from(status.tiles_total));
                            bar.set_position(u64::from(status.tiles_done));
                            bar.set_message(match status.frames_total {
                                0 => status.state.wire_name().to_owned(),
                                total => format!("frames {}/{total}", status.frames_ready),
                            });
                            if status.state.is_final() {
                                bar.finish_and_clear();
                                return Ok(status);
                            }
                        }
                        // The coordinator closed the stream before the end (it is stopping).
                        Ok(None) => break tonic::Status::unavailable("the watch ended early"),
                        Err(status) => break status,
                    }
                }
            }
            Err(status) => status,
        };
        if !transient(&status) {
            bar.finish_and_clear();
            return Err(refused(&what, status));
        }
        let since = *unreachable_since.get_or_insert_with(Instant::now);
        if since.elapsed() > WATCH_PATIENCE {
            bar.finish_and_clear();
            return Err(refused(&format!("{what} (gave up after ten minutes)"), status));
        }
        bar.set_message("reconnecting");
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(Duration::from_secs(2));
    }
}

/// Downloads every result file of a finished job into `out`, each written atomically; the
/// files travel at once, each written as soon as it has arrived.
pub async fn fetch(client: &Client, status: &JobStatus, out: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out).map_err(io_error("creating", out))?;
    let mut downloads = tokio::task::JoinSet::new();
    for (index, name) in status.results.iter().enumerate() {
        // Only a plain file name is accepted from the coordinator: nothing lands outside `out`.
        if name.contains(['/', '\\']) || name.starts_with('.') || name.is_empty() {
            return Err(ClusterError::ResultName(name.clone()));
        }
        let (mut client, name, path) = (client.clone(), name.clone(), out.join(name));
        let job_id = status.id.clone();
        downloads.spawn(async move {
            let data = fetch_file(&mut client, &job_id, &name).await?;
            let written = path.clone();
            tokio::task::spawn_blocking(move || atomic_file::write(&path, &data))
                .await?
                .map_err(io_error("writing", &written))?;
            Ok::<_, ClusterError>((index, written))
        });
    }
    let mut written = Vec::new();
    while let Some(done) = downloads.join_next().await {
        written.push(done??);
    }
    written.sort();
    Ok(written.into_iter().map(|(_, path)| path).collect())
}

/// One result file of a job, whole: a coordinator sending as many files as it sends at once
/// (`--max-downloads`) is asked again, after a pause that doubles, for up to a minute; a
/// coordinator that restarts (or whose connection breaks) mid-file is waited for as a watch
/// waits, and the file fetched again from its start; a file that ends short of the size it
/// announced is refused.
async fn fetch_file(client: &mut Client, job_id: &str, name: &str) -> Result<Vec<u8>> {
    let what = format!("fetching {name}");
    let mut pause = std::time::Duration::from_millis(250);
    let (mut busy, mut away) = (Duration::ZERO, Duration::ZERO);
    loop {
        let status = match fetch_once(client, job_id, name).await {
            Ok((data, announced)) if data.len() as u64 == announced => return Ok(data),
            Ok((data, announced)) => {
                return Err(ClusterError::ShortFile { what, sent: data.len(), announced });
            }
            Err(status) => status,
        };
        let (waited, patience) = if status.code() == tonic::Code::ResourceExhausted {
            (&mut busy, Duration::from_secs(60))
        } else if transient(&status) {
            (&mut away, WATCH_PATIENCE)
        } else {
            return Err(refused(&what, status));
        };
        if *waited >= patience {
            return Err(refused(&what, status));
        }
        tokio::time::sleep(pause).await;
        *waited += pause;
        pause = (pause * 2).min(Duration::from_secs(5));
    }
}

/// One attempt at a result file: its bytes and the size the coordinator announced.
async fn fetch_once(
    client: &mut Client,
    job_id: &str,
    name: &str,
) -> Result<(Vec<u8>, u64), tonic::Status> {
    let request = pb::FetchResultRequest { job_id: job_id.to_owned(), name: name.to_owned() };
    let mut stream = client.fetch_result(request).await?.into_inner();
    let (mut data, mut announced) = (Vec::new(), 0);
    while let Some(chunk) = stream.message().await? {
        announced = chunk.total_bytes;
        data.extend_from_slice(&chunk.data);
    }
    Ok((data, announced))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_status_that_holds_no_job_is_refused_naming_its_field() {
        let done = pb::JobState::Done as i32;
        let sent = pb::JobStatus { job_id: "j".into(), state: done, ..Default::default() };
        assert_eq!(
            read_status(sent).unwrap_err().to_string(),
            "the coordinator sent a job status this client cannot read: job_id: `j` is not a job id"
        );
        let id = "0b7e7c5c-7b1e-4a43-9c8e-4f3f5f2b9a10";
        let unknown = pb::JobStatus { job_id: id.into(), state: 99, ..Default::default() };
        assert!(
            read_status(unknown).unwrap_err().to_string().ends_with("state: 99 is not a job state")
        );
        let good = pb::JobStatus { job_id: id.into(), state: done, ..Default::default() };
        assert_eq!(read_status(good).unwrap().id.as_str(), id);
    }
}
