//! The real servers the fleet tests run against (issue 40): a PostgreSQL server, named by
//! `RESTAURO_TEST_POSTGRES` (a URL whose user may create databases), and an S3-compatible one,
//! by `RESTAURO_TEST_S3` and the `AWS_*` variables (`.ci/run` starts both and sets them). Without it a fleet test says it is skipped and passes, unless
//! `RESTAURO_REQUIRE_FLEET` is set (as CI sets it), when it fails.

/// A fresh database for the test `name` on the test server, as a URL; `None` (the test is
/// skipped, saying so) when there is no server to test against.
pub fn database(name: &str) -> Option<String> {
    let admin = server("RESTAURO_TEST_POSTGRES", "postgres://…", name)?;
    let db = format!("restauro_{name}_{}", std::process::id());
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    runtime.block_on(async {
        let (client, connection) = tokio_postgres::connect(&admin, tokio_postgres::NoTls)
            .await
            .unwrap_or_else(|e| panic!("RESTAURO_TEST_POSTGRES={admin}: {e}"));
        tokio::spawn(connection);
        client.batch_execute(&format!("DROP DATABASE IF EXISTS {db} WITH (FORCE)")).await.unwrap();
        client.batch_execute(&format!("CREATE DATABASE {db}")).await.unwrap();
    });
    let (base, query) = admin.split_once('?').map_or((admin.as_str(), None), |(b, q)| (b, Some(q)));
    let server = base.rsplit_once('/').map_or(base, |(server, _)| server);
    Some(match query {
        Some(q) => format!("{server}/{db}?{q}"),
        None => format!("{server}/{db}"),
    })
}

/// A TCP proxy on loopback to a server, which a test can cut: from then on it forwards nothing
/// either way, and takes new connections without answering — packets dropped, as when a network
/// partition separates a coordinator from its database (no reset the client could notice).
pub struct Proxy {
    pub addr: std::net::SocketAddr,
    cut: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Proxy {
    pub fn start(target: std::net::SocketAddr) -> Proxy {
        use std::sync::atomic::Ordering;
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let cut = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let cutting = cut.clone();
        std::thread::spawn(move || {
            // Held open once cut: the far side sees silence, not a closed connection.
            let mut held = Vec::new();
            for client in listener.incoming().flatten() {
                if cutting.load(Ordering::SeqCst) {
                    held.push(client);
                    continue;
                }
                let Ok(server) = std::net::TcpStream::connect(target) else { continue };
                for (from, to) in [(&client, &server), (&server, &client)] {
                    let (mut from, mut to) = (from.try_clone().unwrap(), to.try_clone().unwrap());
                    let cut = cutting.clone();
                    std::thread::spawn(move || forward(&mut from, &mut to, &cut));
                }
                held.push(client);
                held.push(server);
            }
        });
        Proxy { addr, cut }
    }

    /// Forwards nothing from now on.
    pub fn cut(&self) {
        self.cut.store(true, std::sync::atomic::Ordering::SeqCst);
    }

    /// `url` (a PostgreSQL URL) through this proxy: its host and port replaced.
    pub fn url(&self, url: &str) -> String {
        let (scheme, rest) = url.split_once("://").unwrap();
        let (user, rest) = rest.split_once('@').unwrap();
        let path = rest.split_once('/').map_or("", |(_, p)| p);
        format!("{scheme}://{user}@{}/{path}", self.addr)
    }
}

/// Copies `from` to `to` until either closes or the proxy is cut; once cut it reads nothing
/// more, so the sender's data waits unacknowledged.
fn forward(
    from: &mut std::net::TcpStream,
    to: &mut std::net::TcpStream,
    cut: &std::sync::atomic::AtomicBool,
) {
    use std::io::{Read, Write};
    let _ = from.set_read_timeout(Some(std::time::Duration::from_millis(50)));
    let mut buffer = vec![0; 64 << 10];
    while !cut.load(std::sync::atomic::Ordering::SeqCst) {
        match from.read(&mut buffer) {
            Ok(0) => {
                let _ = to.shutdown(std::net::Shutdown::Write);
                return;
            }
            Ok(n) => {
                if cut.load(std::sync::atomic::Ordering::SeqCst)
                    || to.write_all(&buffer[..n]).is_err()
                {
                    return;
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(_) => return,
        }
    }
}

/// The `HOST:PORT` of a PostgreSQL URL.
pub fn server_addr(url: &str) -> std::net::SocketAddr {
    use std::net::ToSocketAddrs;
    let rest = url.split_once('@').map_or(url, |(_, r)| r);
    let host_port = rest.split(['/', '?']).next().unwrap();
    host_port.to_socket_addrs().unwrap().next().unwrap()
}

/// A fresh prefix in the test bucket for the test `name`, as an `s3://` URL; `None` (the test
/// is skipped, saying so) without an S3-compatible server to test against. The server is named
/// by `RESTAURO_TEST_S3` (`s3://BUCKET`), its endpoint and credentials by the usual `AWS_*`
/// variables (`.ci/run` starts SeaweedFS and sets them all); the coordinators a test starts
/// inherit them.
pub fn objects(name: &str) -> Option<String> {
    let bucket = server("RESTAURO_TEST_S3", "s3://BUCKET (and AWS_*)", name)?;
    Some(format!("{}/{name}-{}", bucket.trim_end_matches('/'), std::process::id()))
}

/// The server the variable `var` names for the test `name`; `None`, saying the test is
/// skipped, without it — unless `RESTAURO_REQUIRE_FLEET` is set, when the test fails.
fn server(var: &str, example: &str, name: &str) -> Option<String> {
    let Ok(value) = std::env::var(var) else {
        assert!(
            std::env::var_os("RESTAURO_REQUIRE_FLEET").is_none(),
            "RESTAURO_REQUIRE_FLEET is set and {var} is not: no server to test {name} against"
        );
        eprintln!("skipped {name}: set {var}={example} to test against a real server");
        return None;
    };
    Some(value)
}

/// A PostgreSQL server of a test's own (which it may restart), started by `.ci/postgres.sh`
/// on a free port in `dir`; stopped when dropped. `None` (the test is skipped) without a
/// PostgreSQL to test against, as [`database`] says.
pub struct OwnPostgres {
    dir: std::path::PathBuf,
    /// The URL of its database `restauro`.
    pub url: String,
}

/// Runs `.ci/SCRIPT COMMAND DIR` (a CI server's script), with the port in the variable `port.0`
/// when given; what it printed.
fn script(name: &str, command: &str, dir: &std::path::Path, port: Option<(&str, u16)>) -> String {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../.ci").join(name);
    let mut run = std::process::Command::new("bash");
    run.arg(script).arg(command).arg(dir);
    if let Some((var, port)) = port {
        run.env(var, port.to_string());
    }
    let out = run.output().unwrap();
    assert!(out.status.success(), "{name} {command}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().to_owned()
}

fn postgres_script(command: &str, dir: &std::path::Path, port: Option<u16>) -> String {
    script("postgres.sh", command, dir, port.map(|p| ("RESTAURO_PG_PORT", p)))
}

impl OwnPostgres {
    pub fn start(name: &str, dir: &std::path::Path) -> Option<OwnPostgres> {
        server("RESTAURO_TEST_POSTGRES", "postgres://…", name)?;
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        // The server runs as the package's user when the tests run as root: it must reach its
        // folder.
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        let dir = dir.join("postgres");
        std::fs::create_dir_all(&dir).unwrap();
        let admin = postgres_script("start", &dir, Some(port));
        let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
        runtime.block_on(async {
            let (client, connection) =
                tokio_postgres::connect(&admin, tokio_postgres::NoTls).await.unwrap();
            tokio::spawn(connection);
            client.batch_execute("CREATE DATABASE restauro").await.unwrap();
        });
        let url = format!("{}/restauro", admin.rsplit_once('/').unwrap().0);
        Some(OwnPostgres { dir, url })
    }

    /// The certificate authority that signed the server's certificate (for 127.0.0.1 and
    /// localhost), a PEM file.
    pub fn authority(&self) -> std::path::PathBuf {
        self.dir.join("tls/ca.crt")
    }

    /// The client certificate and key (PEM) with which the role `restauro_cert` logs in to
    /// its database `restauro_cert` — over TLS, by certificate alone (`cert` in
    /// `pg_hba.conf`).
    pub fn client_certificate(&self) -> (std::path::PathBuf, std::path::PathBuf) {
        (self.dir.join("tls/client.crt"), self.dir.join("tls/client.key"))
    }

    /// Restarts the server (fast: every session is cut).
    pub fn restart(&self) {
        postgres_script("restart", &self.dir, None);
    }
}

impl Drop for OwnPostgres {
    fn drop(&mut self) {
        postgres_script("stop", &self.dir, None);
    }
}

/// An S3-compatible server of a test's own (which it may fill up), SeaweedFS started by
/// `.ci/seaweedfs.sh` on five free ports in `dir`, its bucket `restauro`; stopped when dropped.
/// `None` (the test is skipped) without an S3-compatible server to test against, as
/// [`objects`] says.
pub struct OwnS3 {
    dir: std::path::PathBuf,
    /// Its S3 endpoint, for `AWS_ENDPOINT_URL`.
    pub endpoint: String,
}

impl OwnS3 {
    pub fn start(name: &str, dir: &std::path::Path) -> Option<OwnS3> {
        server("RESTAURO_TEST_S3", "s3://BUCKET (and AWS_*)", name)?;
        let dir = dir.join("s3");
        let port = free_ports(5);
        let endpoint = script("seaweedfs.sh", "start", &dir, Some(("RESTAURO_S3_PORT", port)));
        Some(OwnS3 { dir, endpoint })
    }

    /// Fills its bucket: over its quota, made read-only, it refuses every put (a 500), as a
    /// full store does, and still serves what it holds.
    pub fn fill(&self) {
        script("seaweedfs.sh", "fill", &self.dir, None);
    }

    /// Makes room: the bucket takes puts again.
    pub fn free(&self) {
        script("seaweedfs.sh", "free", &self.dir, None);
    }
}

impl Drop for OwnS3 {
    fn drop(&mut self) {
        script("seaweedfs.sh", "stop", &self.dir, None);
    }
}

/// The first of `n` consecutive ports free on loopback.
fn free_ports(n: u16) -> u16 {
    loop {
        let first =
            std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let all_free = (0..n).all(|i| {
            first
                .checked_add(i)
                .is_some_and(|p| std::net::TcpListener::bind(("127.0.0.1", p)).is_ok())
        });
        if all_free {
            return first;
        }
    }
}
