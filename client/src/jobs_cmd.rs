//! `submit`, `watch`, `fetch`, `cancel`, `jobs`, `workers`: a client of a running coordinator.

use crate::cli::{ConnectArgs, FetchArgs, JobArgs, SubmitArgs};
use crate::connect::{client_token, shown};
use crate::render::{checked_bundle, job_spec};
use anyhow::{Result, bail};
use restauro_cluster::{self as cluster, Client, refused};
use restauro_proto as pb;
use restauro_proto::job_status::JobState;
use std::fmt::Write as _;

fn with_client<T>(c: &ConnectArgs, f: impl AsyncFnOnce(&mut Client) -> Result<T>) -> Result<T> {
    let token = client_token(c.token_file.as_deref())?;
    cluster::runtime()?.block_on(async {
        let mut client =
            cluster::connect_as(&c.coordinator, &token, c.tls_ca.as_deref(), c.protocol_version)
                .await?;
        f(&mut client).await
    })
}

pub fn submit(args: &SubmitArgs) -> Result<String> {
    let r = &args.render;
    let Some(coordinator) = &r.run.connect.coordinator else {
        bail!(
            "submit needs --coordinator URL (or RESTAURO_COORDINATOR); `restauro render` renders on an embedded cluster"
        );
    };
    let connect = ConnectArgs {
        coordinator: coordinator.clone(),
        token_file: r.run.connect.token_file.clone(),
        tls_ca: r.run.connect.tls_ca.clone(),
        protocol_version: pb::PROTOCOL_VERSION,
    };
    let spec = job_spec(r, args.priority)?;
    let (bundle, _plan) = checked_bundle(r)?;
    with_client(&connect, async |client| {
        cluster::upload(client, &bundle).await?;
        let what = format!("submitting {}", r.scene.display());
        let status = cluster::submit(client, &bundle, &spec, &what).await?;
        let mut s = format!("{}\n", status.id);
        if args.wait {
            let status = cluster::watch(client, &status.id, true).await?;
            if status.state != JobState::Done {
                bail!(
                    "job {} is {}: {}",
                    status.id,
                    status.state.wire_name(),
                    shown(&status.error)
                );
            }
            for f in cluster::fetch(client, &status, &r.out).await? {
                let _ = writeln!(s, "wrote {}", f.display());
            }
        }
        Ok(s)
    })
}

pub fn watch(args: &JobArgs) -> Result<String> {
    with_client(&args.connect, async |client| {
        let status = cluster::watch(client, &args.job, true).await?;
        Ok(format!(
            "job {} {}{}\n",
            status.id,
            status.state.wire_name(),
            if status.error.is_empty() {
                String::new()
            } else {
                format!(": {}", shown(&status.error))
            }
        ))
    })
}

pub fn fetch(args: &FetchArgs) -> Result<String> {
    with_client(&args.connect, async |client| {
        let list = client
            .list_jobs(pb::ListJobsRequest {})
            .await
            .map_err(|s| refused("listing jobs", s))?
            .into_inner();
        let Some(sent) = list.jobs.into_iter().find(|j| j.job_id == args.job) else {
            bail!("no job {} on this coordinator", args.job);
        };
        let status = cluster::read_status(sent)?;
        let mut s = String::new();
        for f in cluster::fetch(client, &status, &args.out).await? {
            let _ = writeln!(s, "wrote {}", f.display());
        }
        Ok(s)
    })
}

pub fn cancel(args: &JobArgs) -> Result<String> {
    with_client(&args.connect, async |client| {
        let sent = client
            .cancel_job(pb::JobRef { job_id: args.job.clone() })
            .await
            .map_err(|s| refused(&format!("cancelling {}", args.job), s))?
            .into_inner();
        let status = cluster::read_status(sent)?;
        Ok(format!("job {} {}\n", status.id, status.state.wire_name()))
    })
}

pub fn jobs(args: &ConnectArgs) -> Result<String> {
    with_client(args, async |client| {
        let list = client
            .list_jobs(pb::ListJobsRequest {})
            .await
            .map_err(|s| refused("listing jobs", s))?
            .into_inner();
        let mut s = String::new();
        if !list.problem.is_empty() {
            let _ = writeln!(s, "coordinator: {}", shown(&list.problem));
        }
        for sent in list.jobs {
            let j = cluster::read_status(sent)?;
            let frames = match j.frames_total {
                0 => String::new(),
                total => format!(", frames {}/{total} ready", j.frames_ready),
            };
            let _ = writeln!(
                s,
                "{} {:<16} {:>5}/{:<5} tiles  {:>8.1} s  {}{frames}{}",
                j.id,
                j.state.wire_name(),
                j.tiles_done,
                j.tiles_total,
                j.elapsed_s,
                shown(&j.name),
                if j.error.is_empty() { String::new() } else { format!(" ({})", shown(&j.error)) }
            );
        }
        Ok(s)
    })
}

/// Seconds from a Unix time in milliseconds to now (0 for a time to come).
fn seconds_since(unix_ms: u64) -> f64 {
    let now_ms = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    now_ms.saturating_sub(unix_ms) as f64 / 1000.0
}

pub fn workers(args: &ConnectArgs) -> Result<String> {
    with_client(args, async |client| {
        let list = client
            .list_workers(pb::ListWorkersRequest {})
            .await
            .map_err(|s| refused("listing workers", s))?
            .into_inner();
        let mut s = String::new();
        for w in list.workers {
            let _ = writeln!(
                s,
                "{:x} {:<24} capacity {:>2}  leases {:>2}  done {:>6}  confirmed {:>5}  failed {:>3}  seen {:.1} s ago  {}",
                w.worker_id,
                shown(&w.name),
                w.capacity,
                w.leases,
                w.tiles_done,
                w.tiles_confirmed,
                w.tiles_failed,
                w.last_seen_s,
                shown(&w.build)
            );
        }
        for q in list.quarantined {
            let _ = writeln!(
                s,
                "quarantined {:<24} identity {}  {:.0} s ago: {}",
                shown(&q.name),
                shown(&q.identity),
                seconds_since(q.since_unix_ms),
                shown(&q.reason)
            );
        }
        Ok(s)
    })
}
