use clap::Parser;
use restauro::cli::{Cli, Command};
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    restauro_cluster::progress::set_mode(cli.progress);
    let result = match &cli.command {
        Command::Color(args) => restauro::color::run(args),
        Command::Demo(args) => restauro::demo::run(args),
        Command::Render(args) => restauro::render::run(args),
        Command::Sequence(args) => restauro::sequence::run(args),
        Command::Illuminance(args) => restauro::illuminance::run(args),
        Command::Submit(args) => restauro::jobs_cmd::submit(args),
        Command::Watch(args) => restauro::jobs_cmd::watch(args),
        Command::Fetch(args) => restauro::jobs_cmd::fetch(args),
        Command::Cancel(args) => restauro::jobs_cmd::cancel(args),
        Command::Jobs(args) => restauro::jobs_cmd::jobs(args),
        Command::Workers(args) => restauro::jobs_cmd::workers(args),
        Command::Coordinator(args) => {
            restauro_ops::logging::init();
            restauro_coordinator::server::run(args).map(|()| String::new())
        }
        Command::Worker(args) => {
            restauro_ops::logging::init();
            restauro_worker::process::run(args).map(|()| String::new()).map_err(Into::into)
        }
        Command::Retinex(args) => restauro::retinex::run(args),
        Command::Display(args) => restauro::retinex::run_display(args),
        Command::Compare(args) => restauro::compare::run(args),
        Command::Studio(args) => restauro::studio_cmd::run(args),
        Command::Scene(command) => restauro::scene_cmd::run(command),
        Command::Bench(args) => restauro_bench::run(args).map_err(anyhow::Error::from),
    };
    match result.and_then(|text| Ok(std::io::stdout().lock().write_all(text.as_bytes())?)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // `{:#}` prints the whole chain of context on one line, without a backtrace: the
            // messages themselves say what is wrong and what to do.
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
