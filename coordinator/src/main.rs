//! `restauro-coordinator`: the coordinator process (see `restauro_coordinator::server`).

use clap::Parser;
use restauro_coordinator::server::{CoordinatorArgs, run};

#[derive(Parser)]
#[command(
    name = "restauro-coordinator",
    version,
    about = "restauro's coordinator: jobs, tile leases, assembly, Retinex, results"
)]
struct Cli {
    #[command(flatten)]
    args: CoordinatorArgs,
}

fn main() -> anyhow::Result<()> {
    restauro_ops::logging::init();
    run(&Cli::parse().args)
}
