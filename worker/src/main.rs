//! `restauro-worker`: the worker process (see `restauro_worker::process`).

use clap::Parser;
use restauro_worker::process::{WorkerArgs, run};

#[derive(Parser)]
#[command(
    name = "restauro-worker",
    version,
    about = "restauro's worker: renders the tiles a coordinator leases to it"
)]
struct Cli {
    #[command(flatten)]
    args: WorkerArgs,
}

fn main() -> anyhow::Result<()> {
    restauro_ops::logging::init();
    Ok(run(&Cli::parse().args)?)
}
