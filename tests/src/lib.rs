//! Integration tests that start restauro's real binaries (coordinator, workers, client) on
//! loopback: bit-identity against the in-process render, fault injection, authentication.
//!
//! The binaries are the ones `cargo test --workspace` builds beside this crate's test
//! executables (`target/<profile>/`); this module finds them and starts processes.

pub mod browser;
pub mod fleet;
pub mod http;
pub mod load;
pub mod raw;
pub mod relief;
pub mod web;
pub mod wire;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The path of one of restauro's binaries, built by `cargo test --workspace`.
pub fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    // target/<profile>/deps/<test> → target/<profile>/<name>; the load benchmark runs from
    // target/<profile>/ itself.
    let mut dir = exe.parent().expect("a target folder");
    if dir.ends_with("deps") {
        dir = dir.parent().expect("a target folder");
    }
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is not built; run `cargo test --workspace`, which builds every binary",
        path.display()
    );
    path
}

/// A coordinator process on a free loopback port.
pub struct Coordinator {
    pub child: Child,
    pub url: String,
    /// The address of its metrics endpoint, when started with `--metrics-listen`.
    pub metrics: Option<String>,
    /// The studio's `HOST:PORT`, when started with `--studio-listen`.
    pub studio: Option<String>,
    /// The folder of its log (and of its workers' logs), shown when a test fails.
    dir: PathBuf,
}

pub const CLIENT_TOKEN: &str = "client-token-for-tests";
pub const WORKER_TOKEN: &str = "worker-token-for-tests";

/// Token files for both roles in `dir`.
pub fn token_files(dir: &Path) -> (PathBuf, PathBuf) {
    let (c, w) = (dir.join("client.token"), dir.join("worker.token"));
    // Written to a temporary name and renamed: a process started a moment ago may be reading
    // the file, and must never see it empty.
    for (path, token) in [(&c, CLIENT_TOKEN), (&w, WORKER_TOKEN)] {
        let temporary = path.with_extension(format!("tmp-{}", std::process::id()));
        std::fs::write(&temporary, token).unwrap();
        std::fs::rename(&temporary, path).unwrap();
    }
    (c, w)
}

impl Coordinator {
    /// Starts `restauro-coordinator` with its store in `data`, on `listen` (port 0: any).
    /// A coordinator on `dir/data` serving the studio too; with the studio page's address.
    pub fn with_studio(dir: &Path) -> (Coordinator, String) {
        let c =
            Self::start(dir, &dir.join("data"), "127.0.0.1:0", &["--studio-listen", "127.0.0.1:0"]);
        let page = format!("http://{}/", c.studio.as_deref().expect("the studio's address"));
        (c, page)
    }

    /// What a studio test starts from: a coordinator serving the studio, one worker
    /// (`local-1`), and the Aosta scene of `width × height` px in `dir`; with the page's address,
    /// the scene's path and the client token's file.
    pub fn studio_farm(dir: &Path, width: u32, height: u32) -> StudioFarm {
        let (coordinator, page) = Self::with_studio(dir);
        let worker = Worker::start(dir, &coordinator.url, "local-1", &[]);
        let scene = aosta_scene(dir, width, height);
        StudioFarm { coordinator, _worker: worker, page, scene, token: dir.join("client.token") }
    }

    pub fn start(dir: &Path, data: &Path, listen: &str, extra: &[&str]) -> Coordinator {
        Self::start_under(&[], dir, data, listen, extra)
    }

    /// As [`Coordinator::start`], run by the command `prefix` (e.g. `prlimit …`): the process
    /// that `prefix` finally executes is the coordinator, with the same process id.
    pub fn start_under(
        prefix: &[&str],
        dir: &Path,
        data: &Path,
        listen: &str,
        extra: &[&str],
    ) -> Coordinator {
        let coordinator = binary("restauro-coordinator");
        let command = match prefix.split_first() {
            Some((first, rest)) => {
                let mut command = Command::new(first);
                command.args(rest).arg(coordinator);
                command
            }
            None => Command::new(coordinator),
        };
        let mut child = coordinator_command(command, dir, data, listen, "coordinator.log")
            .args(extra)
            .spawn()
            .unwrap();
        let mut line = String::new();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        stdout.read_line(&mut line).unwrap();
        let addr = line.trim().strip_prefix("listening on ").unwrap_or_else(|| {
            panic!(
                "coordinator did not start: {}",
                std::fs::read_to_string(dir.join("coordinator.log")).unwrap_or_default()
            )
        });
        let url = format!("http://{addr}");
        let metrics = extra.contains(&"--metrics-listen").then(|| {
            let mut line = String::new();
            stdout.read_line(&mut line).unwrap();
            line.trim().strip_prefix("metrics on ").expect("the metrics address").to_owned()
        });
        let studio = extra.contains(&"--studio-listen").then(|| {
            let mut line = String::new();
            stdout.read_line(&mut line).unwrap();
            let line = line.trim();
            let url = line
                .strip_prefix("studio on http://")
                .or_else(|| line.strip_prefix("studio on https://"));
            let url = url.expect("the studio's address");
            url.trim_end_matches('/').to_owned()
        });
        Coordinator { child, url, metrics, studio, dir: dir.to_owned() }
    }
}

/// See [`Coordinator::studio_farm`].
pub struct StudioFarm {
    pub coordinator: Coordinator,
    _worker: Worker,
    pub page: String,
    pub scene: String,
    pub token: PathBuf,
}

/// Downloads the scene revision the studio's page shows, by its own link, as a folder under
/// `d/downloaded`: the path of its `scene.toml`.
pub fn download_shown(b: &mut browser::Browser, c: &Coordinator, d: &Path) -> PathBuf {
    let href = b.eval("document.getElementById('download').getAttribute('href')");
    let bearer = format!("Bearer {CLIENT_TOKEN}");
    let auth = [("Authorization", bearer.as_str())];
    let tar =
        http::request(c.studio.as_deref().unwrap(), "GET", href.as_str().unwrap(), &auth, b"");
    assert_eq!(tar.status, 200, "{}", tar.text());
    let disposition = tar.header("content-disposition").unwrap().to_owned();
    let name = disposition.split('"').nth(1).unwrap().trim_end_matches(".tar").to_owned();
    tar::Archive::new(std::io::Cursor::new(tar.body)).unpack(d.join("downloaded")).unwrap();
    d.join("downloaded").join(name).join("scene.toml")
}

impl StudioFarm {
    /// The studio's page in a headless Chromium of `width × height`, signed in by the token in
    /// its address, once it has opened the scene the farm holds (send one first).
    pub fn page_in_browser(&self, width: u32, height: u32) -> browser::Browser {
        let mut b = browser::Browser::launch(width, height);
        b.goto(&format!("{}#token={CLIENT_TOKEN}", self.page));
        b.wait_for("the model", "document.getElementById('view').dataset.scene");
        b
    }
}

/// `command` (which runs the coordinator) with the arguments every test coordinator has: its
/// address, data folder and token files (in `dir`), standard output piped, its log `log` in `dir`.
fn coordinator_command(
    mut command: Command,
    dir: &Path,
    data: &Path,
    listen: &str,
    log: &str,
) -> Command {
    let (c, w) = token_files(dir);
    command
        .args(["--listen", listen, "--data"])
        .arg(data)
        .arg("--client-token-file")
        .arg(&c)
        .arg("--worker-token-file")
        .arg(&w)
        .stdout(Stdio::piped())
        .stderr(Stdio::from(appending(&dir.join(log))));
    command
}

/// A coordinator started beside a leading one on the same PostgreSQL store (`--store` in its
/// arguments, and `--metrics-listen`): it stands by, its operations endpoint not ready, until it
/// takes the lead. Its log is `standby.log` in its folder.
pub struct Standby {
    pub child: Child,
    stdout: Option<BufReader<std::process::ChildStdout>>,
    /// Its metrics and health address.
    pub metrics: String,
    pub url: String,
    dir: PathBuf,
}

impl Standby {
    /// Starts it on `listen` (a free port: the workers and clients are given its URL before it
    /// listens) and waits until it says it stands by.
    pub fn start(dir: &Path, data: &Path, listen: &str, extra: &[&str]) -> Standby {
        let command = Command::new(binary("restauro-coordinator"));
        let mut child = coordinator_command(command, dir, data, listen, "standby.log")
            .args(["--metrics-listen", "127.0.0.1:0"])
            .args(extra)
            .spawn()
            .unwrap();
        let mut stdout = BufReader::new(child.stdout.take().unwrap());
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
        let metrics = line
            .trim()
            .strip_prefix("standby, metrics on ")
            .unwrap_or_else(|| panic!("the standby did not stand by: {line:?}\n{}", logs(dir)));
        let metrics = metrics.to_owned();
        let url = format!("http://{listen}");
        Standby { child, stdout: Some(stdout), metrics, url, dir: dir.to_owned() }
    }

    /// Waits (within [`patience`]) until it leads — it prints where it listens — and says how
    /// long that took.
    pub fn wait_to_lead(mut self) -> (Coordinator, Duration) {
        let start = Instant::now();
        let mut stdout = self.stdout.take().unwrap();
        let (lines, said) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for _ in 0..2 {
                let mut line = String::new();
                let _ = stdout.read_line(&mut line);
                let _ = lines.send(line);
            }
        });
        let next = || {
            said.recv_timeout(patience()).unwrap_or_else(|_| {
                panic!("the standby did not take the lead in time\n{}", logs(&self.dir))
            })
        };
        let line = next();
        let took = start.elapsed();
        let addr = line.trim().strip_prefix("listening on ").unwrap_or_else(|| {
            panic!("the standby did not take the lead: {line:?}\n{}", logs(&self.dir))
        });
        let url = format!("http://{addr}");
        assert_eq!(url, self.url);
        assert_eq!(next().trim(), format!("metrics on {}", self.metrics));
        let child = std::mem::replace(&mut self.child, Command::new("true").spawn().unwrap());
        let metrics = Some(self.metrics.clone());
        (Coordinator { child, url, metrics, studio: None, dir: self.dir.clone() }, took)
    }
}

/// Waits up to `limit` for `child` to exit by itself, and says how it ended; a process still
/// running then is killed and the test fails.
pub fn wait_for_exit(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the process did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

impl Drop for Standby {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A loopback address with a free port, to give a process that binds it later.
pub fn free_loopback_addr() -> String {
    let socket = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    socket.local_addr().unwrap().to_string()
}

impl Drop for Coordinator {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        // A failing test says what its processes were doing (the harness shows what a failed
        // test wrote).
        if std::thread::panicking() {
            eprintln!("the processes' logs:\n{}", logs(&self.dir));
        }
    }
}

/// A worker process.
pub struct Worker(pub Child);

impl Worker {
    pub fn start(dir: &Path, url: &str, name: &str, extra: &[&str]) -> Worker {
        let (_, w) = token_files(dir);
        Self::start_with_token(dir, url, name, &w, extra)
    }

    /// A worker presenting the token in file `token`.
    pub fn start_with_token(
        dir: &Path,
        url: &str,
        name: &str,
        token: &Path,
        extra: &[&str],
    ) -> Worker {
        let w = token;
        let child = Command::new(binary("restauro-worker"))
            .args(["--coordinator", url, "--threads", "1", "--name", name, "--token-file"])
            .arg(w)
            .arg("--cache")
            .arg(dir.join(format!("cache-{name}")))
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::from(std::fs::File::create(dir.join(format!("{name}.log"))).unwrap()))
            .spawn()
            .unwrap();
        Worker(child)
    }
}

impl Worker {
    /// A worker serving its metrics on a free port; the worker and the endpoint's address.
    pub fn start_with_metrics(
        dir: &Path,
        url: &str,
        name: &str,
        extra: &[&str],
    ) -> (Worker, String) {
        let (_, token) = token_files(dir);
        let mut child = Command::new(binary("restauro-worker"))
            .args(["--coordinator", url, "--threads", "1", "--name", name, "--token-file"])
            .arg(&token)
            .arg("--cache")
            .arg(dir.join(format!("cache-{name}")))
            .args(["--metrics-listen", "127.0.0.1:0"])
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::from(std::fs::File::create(dir.join(format!("{name}.log"))).unwrap()))
            .spawn()
            .unwrap();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let addr =
            line.trim().strip_prefix("metrics on ").expect("the worker's metrics").to_owned();
        (Worker(child), addr)
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Runs the `restauro` client with `args`.
pub fn restauro(args: &[&str]) -> Output {
    let mut command = Command::new(binary("restauro"));
    command.args(args).env_remove("RESTAURO_COORDINATOR");
    output_within(&mut command, patience())
}

/// How long a test waits for one command before it kills it and fails: ten minutes, or
/// `RESTAURO_TEST_PATIENCE_S` seconds. A command that hangs fails its test with what it had
/// written, rather than holding the whole test run until CI gives up on it.
pub fn patience() -> Duration {
    let seconds = std::env::var("RESTAURO_TEST_PATIENCE_S").ok().and_then(|s| s.parse().ok());
    Duration::from_secs(seconds.unwrap_or(600))
}

/// Runs `command` to its end as `Command::output` does, killing it after `limit`, with every
/// process it started (its own process group): then the test fails, showing the command and
/// what it wrote.
pub fn output_within(command: &mut Command, limit: Duration) -> Output {
    use std::os::unix::process::CommandExt as _;
    let mut child = command
        .process_group(0)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {command:?}: {e}"));
    let drain = |mut pipe: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            bytes
        })
    };
    let stdout = drain(Box::new(child.stdout.take().expect("piped")));
    let stderr = drain(Box::new(child.stderr.take().expect("piped")));
    let deadline = Instant::now() + limit;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if Instant::now() >= deadline {
            let group = format!("-{}", child.id());
            let _ = Command::new("kill").args(["-KILL", "--", &group]).status();
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let stdout = stdout.join().unwrap_or_default();
    let stderr = stderr.join().unwrap_or_default();
    let Some(status) = status else {
        panic!(
            "{command:?} was still running after {} s and was killed; it had written:\n{}{}",
            limit.as_secs(),
            String::from_utf8_lossy(&stdout),
            String::from_utf8_lossy(&stderr)
        );
    };
    Output { status, stdout, stderr }
}

/// Runs a client command of `restauro` against the coordinator at `url`, with the client
/// token in the file `token`.
pub fn client(args: &[&str], url: &str, token: &Path) -> Output {
    let token = token.to_str().expect("a UTF-8 path");
    let all: Vec<&str> =
        args.iter().copied().chain(["--coordinator", url, "--token-file", token]).collect();
    restauro(&all)
}

/// Submits `scene` with `extra` options; the job's id.
pub fn submit(scene: &str, extra: &[&str], url: &str, token: &Path) -> String {
    let args: Vec<&str> = ["submit", scene].into_iter().chain(extra.iter().copied()).collect();
    let o = client(&args, url, token);
    assert!(o.status.success(), "{}", text(&o));
    String::from_utf8_lossy(&o.stdout).trim().to_owned()
}

/// The output of a finished process, stdout and stderr together.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Writes the procedural Aosta scene of `width × height` pixels into `dir/aosta`; its path.
pub fn aosta_scene(dir: &Path, width: u32, height: u32) -> String {
    let scene = dir.join("aosta");
    let (w, h) = (width.to_string(), height.to_string());
    let o = restauro(&[
        "scene",
        "aosta",
        "--out",
        scene.to_str().unwrap(),
        "--width",
        &w,
        "--height",
        &h,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    scene.join("aosta.toml").to_str().unwrap().to_owned()
}

/// `GET path` on `addr` (plain HTTP/1.1): the status code and the body.
pub fn http_get(addr: &str, path: &str) -> (u16, String) {
    let response = http::request(addr, "GET", path, &[], b"");
    (response.status, response.text())
}

/// The value of the unlabelled sample `name` in a Prometheus scrape.
pub fn sample(scrape: &str, name: &str) -> f64 {
    scrape
        .lines()
        .find_map(|l| l.strip_prefix(name).and_then(|rest| rest.strip_prefix(' ')))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no sample `{name}` in:\n{scrape}"))
}

/// Waits until `ok`, polling; fails the test naming `what` after `timeout`.
pub fn wait_for(what: &str, timeout: std::time::Duration, mut ok: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + timeout;
    while !ok() {
        assert!(std::time::Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// `path` opened for appending: a coordinator restarted on the same directory keeps its
/// predecessor's log.
fn appending(path: &Path) -> std::fs::File {
    std::fs::OpenOptions::new().create(true).append(true).open(path).unwrap()
}

/// The tiles of job `job` that workers rendered, as their `--tile-log` files say (a line `job
/// tile attempt` each), in the order of `logs` and of their lines; a log not yet written holds
/// none.
pub fn tiles_rendered(logs: &[PathBuf], job: &str) -> Vec<u32> {
    logs.iter()
        .flat_map(|log| {
            std::fs::read_to_string(log)
                .unwrap_or_default()
                .lines()
                .filter(|line| line.split(' ').next() == Some(job))
                .map(|line| line.split(' ').nth(1).unwrap().parse().unwrap())
                .collect::<Vec<u32>>()
        })
        .collect()
}

/// The last lines of every process log (`*.log`) in `dir`, for a failure's message: a test
/// that times out waiting on processes says what they were doing.
pub fn logs(dir: &Path) -> String {
    let mut out = String::new();
    let Ok(entries) = std::fs::read_dir(dir) else { return out };
    let mut paths: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    paths.sort();
    for path in paths.iter().filter(|p| p.extension().is_some_and(|e| e == "log")) {
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let lines: Vec<&str> = text.lines().collect();
        let tail = &lines[lines.len().saturating_sub(40)..];
        out.push_str(&format!(
            "--- {} (last {} lines)\n{}\n",
            path.display(),
            tail.len(),
            tail.join("\n")
        ));
    }
    out
}

/// Sends `sig` (`-STOP`, `-CONT`, `-TERM`, …) to a process.
pub fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill").args([sig, &child.id().to_string()]).status().unwrap();
    assert!(ok.success());
}

/// The values of channel `name` of the EXR at `path` (its first layer), or `None` when it has
/// no such channel.
/// The XYZ pixels of an EXR the farm or the client wrote.
pub fn exr_pixels(path: &Path) -> Vec<[f32; 3]> {
    restauro_image::image_files::read_exr(path, 1 << 24)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .pixels
}

/// Bit-identical: compares every float's bits.
pub fn assert_identical(a: &[[f32; 3]], b: &[[f32; 3]]) {
    assert_eq!(a.len(), b.len());
    let differ =
        a.iter().zip(b).filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits)).count();
    assert_eq!(differ, 0, "{differ} of {} pixels differ", a.len());
}

pub fn exr_channel(path: &Path, name: &str) -> Option<Vec<f32>> {
    use exr::prelude::{ReadChannels as _, ReadLayers as _};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let list = image.layer_data.channel_data.list;
    let channel = list.iter().find(|c| c.name.to_string() == name)?;
    Some(channel.sample_data.values_as_f32().collect())
}
