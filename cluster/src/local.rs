//! The embedded local cluster: a coordinator and workers as real processes of this same
//! executable (`restauro coordinator`, `restauro worker`), on loopback, that end with this
//! process.

use crate::error::{ClusterError, io_doing, io_error};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A coordinator and workers started as child processes of this executable, on loopback. They
/// exit when this process closes their standard input — on drop, or when it dies.
pub struct LocalCluster {
    children: Vec<Child>,
    pub url: String,
    /// The studio's address, when the coordinator was asked to serve it (`--studio-listen`).
    pub studio_url: Option<String>,
    pub client_token: String,
    /// The file holding `client_token`, for commands run beside the cluster.
    pub client_token_file: PathBuf,
    pub worker_token: String,
    _dir: tempfile::TempDir,
}

/// A fresh secret: 256 bits from the operating system's random source (UUID v4 draws them).
fn random_token() -> String {
    format!("{}{}", uuid::Uuid::new_v4().simple(), uuid::Uuid::new_v4().simple())
}

impl LocalCluster {
    /// Starts a coordinator and `workers` workers sharing this machine's cores; their logs go to
    /// `logs` when given, else into the temporary folder that goes with the cluster.
    pub fn start(workers: usize, logs: Option<&Path>) -> Result<LocalCluster, ClusterError> {
        Self::start_with(workers, logs, &[])
    }

    /// As `start`, with more arguments for the coordinator.
    pub fn start_with(
        workers: usize,
        logs: Option<&Path>,
        coordinator_args: &[&str],
    ) -> Result<LocalCluster, ClusterError> {
        let exe = std::env::current_exe().map_err(io_doing("finding this executable"))?;
        let dir = tempfile::Builder::new()
            .prefix("restauro-cluster-")
            .tempdir()
            .map_err(io_doing("creating the cluster's temporary folder"))?;
        let client_token = random_token();
        let worker_token = random_token();
        let client_file = dir.path().join("client.token");
        let worker_file = dir.path().join("worker.token");
        std::fs::write(&client_file, &client_token).map_err(io_error("writing", &client_file))?;
        std::fs::write(&worker_file, &worker_token).map_err(io_error("writing", &worker_file))?;
        let log_dir = logs.unwrap_or(dir.path()).to_owned();
        std::fs::create_dir_all(&log_dir).map_err(io_error("creating", &log_dir))?;
        let log = |name: &str| -> Result<Stdio, ClusterError> {
            let path = log_dir.join(format!("{name}.log"));
            let file = std::fs::File::create(&path).map_err(io_error("creating", &path))?;
            Ok(Stdio::from(file))
        };
        let mut coordinator = Command::new(&exe)
            .args(["coordinator", "--listen", "127.0.0.1:0", "--exit-with-stdin", "--data"])
            .arg(dir.path().join("data"))
            .arg("--client-token-file")
            .arg(&client_file)
            .arg("--worker-token-file")
            .arg(&worker_file)
            // The workers are this machine's own processes, of this very binary: a second
            // rendering would prove nothing the first did not.
            .args(["--check-rate", "0", "--check-rate-new", "0"])
            .args(coordinator_args)
            .env("RUST_LOG", std::env::var("RUST_LOG").unwrap_or_else(|_| "warn".into()))
            // An operator's setting for one service; here it would put three processes on
            // one port.
            .env_remove("RESTAURO_METRICS_LISTEN")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(log("coordinator")?)
            .spawn()
            .map_err(io_doing("starting the embedded coordinator"))?;
        let stdout = coordinator.stdout.take().expect("piped");
        let mut children = vec![coordinator];
        let mut stdout = BufReader::new(stdout);
        let mut line = String::new();
        stdout.read_line(&mut line).map_err(io_doing("reading the coordinator's address"))?;
        let Some(addr) = line.trim().strip_prefix("listening on ") else {
            let log = std::fs::read_to_string(log_dir.join("coordinator.log")).unwrap_or_default();
            for c in &mut children {
                let _ = c.kill();
            }
            return Err(ClusterError::CoordinatorDidNotStart(log.trim().to_owned()));
        };
        let url = format!("http://{addr}");
        // The studio's address follows when it was asked for (after the metrics', which the
        // embedded cluster never serves).
        let mut studio_url = None;
        if coordinator_args.contains(&"--studio-listen") {
            let mut line = String::new();
            stdout.read_line(&mut line).map_err(io_doing("reading the studio's address"))?;
            studio_url = line.trim().strip_prefix("studio on ").map(str::to_owned);
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let threads = (cores / workers.max(1)).max(1);
        for i in 0..workers {
            let child = Command::new(&exe)
                .args(["worker", "--exit-with-stdin", "--coordinator", &url, "--token-file"])
                .arg(&worker_file)
                .args(["--threads", &threads.to_string(), "--name", &format!("local-{}", i + 1)])
                .arg("--cache")
                .arg(dir.path().join(format!("cache-{i}")))
                .env("RUST_LOG", std::env::var("RUST_LOG").unwrap_or_else(|_| "warn".into()))
                // An operator's setting for one service; here it would put three processes on
                // one port.
                .env_remove("RESTAURO_METRICS_LISTEN")
                .stdin(Stdio::piped())
                .stdout(Stdio::null())
                .stderr(log(&format!("worker-{}", i + 1))?)
                .spawn()
                .map_err(io_doing("starting an embedded worker"))?;
            children.push(child);
        }
        Ok(LocalCluster {
            children,
            url,
            studio_url,
            client_token,
            client_token_file: client_file,
            worker_token,
            _dir: dir,
        })
    }
}

impl LocalCluster {
    /// The coordinator's process id.
    pub fn coordinator_pid(&self) -> u32 {
        self.children[0].id()
    }
}

impl Drop for LocalCluster {
    fn drop(&mut self) {
        // Closing stdin asks each process to stop: the workers first (they drain and leave while
        // the coordinator still answers), then the coordinator.
        let deadline = Instant::now() + Duration::from_secs(10);
        let (coordinator, workers) = self.children.split_at_mut(1);
        for child in workers.iter_mut() {
            drop(child.stdin.take());
        }
        for child in workers.iter_mut() {
            stop_child(child, deadline);
        }
        drop(coordinator[0].stdin.take());
        stop_child(&mut coordinator[0], deadline);
    }
}

/// Waits for a child asked to stop; kills it at the deadline.
fn stop_child(child: &mut Child, deadline: Instant) {
    loop {
        match child.try_wait() {
            Ok(Some(_)) => return,
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(5)),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return;
            }
        }
    }
}
