//! Progress as a person follows it: a bar on a terminal, and plain lines at a steady interval in
//! a log file, under `nohup`, in CI or a job scheduler (where a bar draws nothing, and a long
//! render would otherwise print nothing for minutes).
//!
//! `--progress auto|bar|plain|none` chooses (auto: a bar when standard error is a terminal,
//! plain lines otherwise). A plain line says the stage, the count done of the total with its
//! unit, the percentage, the time elapsed and the estimated time left:
//!
//! ```text
//! restauro: demo: render 120/480 tiles (25 %), 1m02s elapsed, about 3m06s left
//! ```
//!
//! one every [`PLAIN_INTERVAL`] (`RESTAURO_PROGRESS_INTERVAL_S` sets another), and one when the
//! stage ends if any was printed before it.

use crate::error::ClusterError;
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::thread::JoinHandle;
use std::time::Duration;

/// How progress is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum ProgressMode {
    /// A bar on a terminal, plain lines otherwise.
    #[default]
    Auto,
    /// A bar (drawn only on a terminal).
    Bar,
    /// Plain lines at a steady interval.
    Plain,
    /// Nothing.
    None,
}

/// The interval between plain lines.
pub const PLAIN_INTERVAL: Duration = Duration::from_secs(10);

static MODE: OnceLock<ProgressMode> = OnceLock::new();

/// Sets the mode for the whole process (from `--progress`); the first call wins.
pub fn set_mode(mode: ProgressMode) {
    let _ = MODE.set(mode);
}

fn mode() -> ProgressMode {
    match MODE.get().copied().unwrap_or_default() {
        ProgressMode::Auto if std::io::stderr().is_terminal() => ProgressMode::Bar,
        ProgressMode::Auto => ProgressMode::Plain,
        other => other,
    }
}

fn interval() -> Duration {
    std::env::var("RESTAURO_PROGRESS_INTERVAL_S")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .map_or(PLAIN_INTERVAL, Duration::from_secs_f64)
}

/// Says what a long command is doing now, on a line of its own on standard error (unless
/// `--progress none`): for stages that have no count to show.
pub fn say(what: &str) {
    if mode() != ProgressMode::None {
        let _ = std::io::stderr().lock().write_all(format!("restauro: {what}\n").as_bytes());
    }
}

/// `1m02s`, `45s`, `2h03m`.
fn duration(d: Duration) -> String {
    let s = d.as_secs();
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s / 60 % 60),
    }
}

/// One plain line for the state of `bar`.
fn plain_line(bar: &ProgressBar, stage: &str, unit: &str) -> String {
    let message = bar.message();
    let message = message.trim();
    let stage = if message.is_empty() || message == stage {
        stage.to_owned()
    } else {
        format!("{stage}: {message}")
    };
    let elapsed = duration(bar.elapsed());
    match bar.length().filter(|&l| l > 0) {
        Some(total) => {
            let done = bar.position().min(total);
            let percent = 100 * done / total;
            let left = if done == 0 || done == total {
                String::new()
            } else {
                format!(", about {} left", duration(bar.eta()))
            };
            format!(
                "restauro: {stage} {done}/{total} {unit} ({percent} %), {elapsed} elapsed{left}\n"
            )
        }
        None => format!("restauro: {stage}, {elapsed} elapsed\n"),
    }
}

/// The thread that prints plain lines, and how to stop it.
struct Plain {
    stop: Arc<(Mutex<bool>, Condvar)>,
    thread: Option<JoinHandle<bool>>,
    stage: String,
    unit: String,
}

/// A progress display: use it as the [`ProgressBar`] it derefs to.
pub struct Progress {
    bar: ProgressBar,
    plain: Option<Plain>,
}

impl std::ops::Deref for Progress {
    type Target = ProgressBar;
    fn deref(&self) -> &ProgressBar {
        &self.bar
    }
}

impl Progress {
    /// A display of `stage` (the bar's message, when it has none), counting `unit` up to
    /// `length`, drawn as a bar with `template` (an indicatif template).
    pub fn new(
        stage: &str,
        unit: &str,
        length: Option<u64>,
        template: &str,
    ) -> Result<Self, ClusterError> {
        let style =
            ProgressStyle::with_template(template).map_err(ClusterError::ProgressTemplate)?;
        let target = match mode() {
            ProgressMode::Bar => ProgressDrawTarget::stderr(),
            _ => ProgressDrawTarget::hidden(),
        };
        let bar = ProgressBar::with_draw_target(length, target);
        bar.set_style(style);
        let plain = (mode() == ProgressMode::Plain).then(|| Plain::start(&bar, stage, unit));
        Ok(Progress { bar, plain })
    }

    /// A display that shows nothing.
    pub fn hidden() -> Self {
        Progress { bar: ProgressBar::hidden(), plain: None }
    }
}

impl Plain {
    fn start(bar: &ProgressBar, stage: &str, unit: &str) -> Plain {
        let stop = Arc::new((Mutex::new(false), Condvar::new()));
        let (bar, every) = (bar.clone(), interval());
        let (signal, stage_name, unit_name) = (stop.clone(), stage.to_owned(), unit.to_owned());
        let thread = std::thread::spawn(move || {
            let (lock, wake) = &*signal;
            let mut printed = false;
            let mut stopped = lock.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                let (guard, timeout) =
                    wake.wait_timeout(stopped, every).unwrap_or_else(|e| e.into_inner());
                stopped = guard;
                if *stopped {
                    return printed;
                }
                if timeout.timed_out() {
                    let line = plain_line(&bar, &stage_name, &unit_name);
                    let _ = std::io::stderr().lock().write_all(line.as_bytes());
                    printed = true;
                }
            }
        });
        Plain { stop, thread: Some(thread), stage: stage.to_owned(), unit: unit.to_owned() }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        let Some(plain) = &mut self.plain else { return };
        let (lock, wake) = &*plain.stop;
        *lock.lock().unwrap_or_else(|e| e.into_inner()) = true;
        wake.notify_all();
        let printed = plain.thread.take().and_then(|t| t.join().ok()).unwrap_or(false);
        if printed {
            let line = plain_line(&self.bar, &plain.stage, &plain.unit);
            let _ = std::io::stderr().lock().write_all(line.as_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_people_write_them() {
        assert_eq!(duration(Duration::from_secs(45)), "45s");
        assert_eq!(duration(Duration::from_secs(62)), "1m02s");
        assert_eq!(duration(Duration::from_secs(7380)), "2h03m");
    }

    #[test]
    fn a_plain_line_says_stage_count_and_time() {
        let bar = ProgressBar::hidden();
        bar.set_length(480);
        bar.set_position(120);
        bar.set_message("render");
        let line = plain_line(&bar, "demo", "tiles");
        assert!(line.starts_with("restauro: demo: render 120/480 tiles (25 %), "), "{line}");
        bar.set_message("demo");
        assert!(plain_line(&bar, "demo", "tiles").starts_with("restauro: demo 120/480 tiles"));
        assert!(line.contains("elapsed, about "), "{line}");
        let spinner = ProgressBar::hidden();
        assert!(plain_line(&spinner, "analysis", "").starts_with("restauro: analysis, "));
    }
}
