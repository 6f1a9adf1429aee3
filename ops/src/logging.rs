//! Logs of the coordinator and worker processes: `tracing` to standard error, filtered by
//! `RUST_LOG` (default `info`). Colour codes only when standard error is a terminal, so a log
//! file or a journal holds plain text.

use std::io::IsTerminal as _;

pub fn init() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr)
        .try_init();
}
