use clap::Parser;
use restauro::cli::{Cli, Command};
use std::io::Write;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Color(args) => restauro::color::run(args),
        Command::Demo(args) => restauro::demo::run(args),
        Command::Render(args) => restauro::render::run(args),
        Command::Retinex(args) => restauro::retinex::run(args),
        Command::Display(args) => restauro::retinex::run_display(args),
        Command::Scene(command) => restauro::scene_cmd::run(command),
        Command::Bench(args) => restauro::bench::run(args),
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
