//! `restauro studio`: the studio on an embedded local cluster. The coordinator serves the page
//! (`--studio-listen`); this prints its address, with the client token in the fragment so that
//! the page signs itself in (a fragment never reaches a server or its logs), and how to send a
//! scene to the same cluster from another terminal.

use crate::cli::StudioArgs;
use crate::cluster::{LocalCluster, runtime};
use anyhow::{Context, Result};
use std::io::Write as _;

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
    runtime()?.block_on(restauro_ops::signal::stop_signal(args.exit_with_stdin));
    drop(cluster);
    Ok("studio stopped\n".to_owned())
}
