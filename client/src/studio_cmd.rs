//! `restauro studio`: the studio on an embedded local cluster. The coordinator serves the page
//! (`--studio-listen`); this prints its address, with the client token in the fragment so that
//! the page signs itself in (a fragment never reaches a server or its logs), and how to send a
//! scene to the same cluster from another terminal.

use crate::cli::StudioArgs;
use anyhow::{Context, Result};
use restauro_assets::bundle_scene;
use restauro_cluster::{self as cluster, LocalCluster, runtime};
use restauro_scene::job::{JobName, JobSpec};
use restauro_scene::limits::Limits;
use restauro_scene::plan::RenderOptions;
use std::io::Write as _;
use std::path::Path;

/// Sends `scene` to the cluster with a quick preview render: the studio holds the scenes of its
/// jobs. The job's id.
async fn open_scene(cluster: &LocalCluster, scene: &Path) -> Result<String> {
    let bundle = bundle_scene(scene, &Limits::default())?;
    let stem = scene.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
    let name = JobName::new(stem)
        .map_err(|e| anyhow::anyhow!("the scene's name `{stem}`: {}", e.problem))?;
    let spec = JobSpec { name, render: RenderOptions::quick_preview(), ..JobSpec::default() };
    let mut client = cluster::connect(&cluster.url, &cluster.client_token).await?;
    cluster::upload(&mut client, &bundle).await?;
    let what = format!("opening {}", scene.display());
    let submitted = cluster::submit(&mut client, &bundle, &spec, &what).await?;
    Ok(submitted.id.to_string())
}

pub fn run(args: &StudioArgs) -> Result<String> {
    let listen = args.listen.to_string();
    let cluster = LocalCluster::start_with(
        args.workers.max(1),
        args.cluster_logs.as_deref(),
        &["--studio-listen", &listen],
    )?;
    let studio = cluster.studio_url.clone().context("the embedded coordinator serves no studio")?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "studio on {studio}#token={}", cluster.client_token)?;
        writeln!(
            out,
            "open that address in a browser (it signs you in); to render a scene on this cluster \
             from another terminal:\n  restauro submit --coordinator {} --token-file {} SCENE.toml\n\
             stop with Ctrl-C",
            cluster.url,
            cluster.client_token_file.display()
        )?;
        out.flush()?;
    }
    let runtime = runtime()?;
    if let Some(scene) = &args.scene {
        let job = runtime.block_on(open_scene(&cluster, scene))?;
        let mut out = std::io::stdout().lock();
        writeln!(out, "opened {} (its preview render is job {job})", scene.display())?;
        out.flush()?;
    }
    runtime.block_on(restauro_ops::signal::stop_signal(args.exit_with_stdin));
    drop(cluster);
    Ok("studio stopped\n".to_owned())
}
