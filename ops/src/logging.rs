//! Logs of the coordinator and worker processes: `tracing` to standard error, filtered by
//! `RUST_LOG` (default `info`). Colour codes only when standard error is a terminal, so a log
//! file or a journal holds plain text.
//!
//! `RUST_LOG` takes a default level and per-target levels, `warn,restauro_coordinator=debug`
//! (tracing-subscriber's `Targets`); the span and field filters of its `EnvFilter` are not worth
//! the regex engine they compile into every binary (issue 17: time to first image).

use std::io::IsTerminal as _;
use tracing_subscriber::filter::{LevelFilter, Targets};
use tracing_subscriber::prelude::*;

pub fn init() {
    let (filter, problem) = match std::env::var("RUST_LOG") {
        Ok(text) if !text.trim().is_empty() => match text.parse::<Targets>() {
            Ok(targets) => (targets, None),
            Err(e) => (
                default_filter(),
                Some(format!(
                    "RUST_LOG `{text}` ignored ({e}); give a level or target=level pairs, e.g. warn,restauro_worker=debug"
                )),
            ),
        },
        _ => (default_filter(), None),
    };
    let fmt = tracing_subscriber::fmt::layer()
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(std::io::stderr);
    let _ = tracing_subscriber::registry().with(fmt.with_filter(filter)).try_init();
    if let Some(problem) = problem {
        tracing::warn!("{problem}");
    }
}

fn default_filter() -> Targets {
    Targets::new().with_default(LevelFilter::INFO)
}
