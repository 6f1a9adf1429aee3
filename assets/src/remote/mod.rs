//! Files a scene names by URL. Any file reference (a mesh, a spectrum's `file`, a photometric
//! file, a photo, a degradation map's image, a glTF's buffers and images) may be an
//! `https://` or `http://` URL; the scene's `[pins]` table gives the content hash each URL
//! must serve, so that a render made from remote files can be made again:
//!
//! ```toml
//! mesh = "https://survey.example.org/aosta/facade.glb"
//!
//! [pins]
//! "https://survey.example.org/aosta/facade.glb" = { sha256 = "9f86d081…" }
//! ```
//!
//! The process that reads the scene folder — the client, or the coordinator for a scene sent
//! to the studio — fetches each file once into a user cache folder (by hash, under a size
//! bound), resumes a download broken off, checks the hash and refuses a file that does not
//! match. A bundle names the file by its BLAKE3 hash like any other file, so workers never
//! fetch: they get every file from the coordinator.
//!
//! The environment sets the cache and the network's bounds:
//!
//! | variable | default |
//! |---|---|
//! | `RESTAURO_CACHE_DIR` | `$XDG_CACHE_HOME/restauro/downloads`, else `~/.cache/restauro/downloads` |
//! | `RESTAURO_CACHE_MB` | 4096 |
//! | `RESTAURO_DOWNLOAD_TIMEOUT_S` (connecting, waiting for an answer, any stretch without data; one download may take 120 times as long in all) | 30 |
//! | `RESTAURO_CA_FILE` (PEM certificates trusted besides the system's) | none |
//!
//! The system's certificates are those `rustls-native-certs` finds (`SSL_CERT_FILE` and
//! `SSL_CERT_DIR` are honoured).

pub mod cache;
mod http;

use crate::error::{AssetsError, Result};
pub use http::{DEADLINE_TIMEOUTS, is_public};
use restauro_scene::assets::Fetch;
pub use restauro_scene::pins::{Algorithm, ContentHash};
use restauro_scene::scene_file::Pin;
pub use restauro_scene::web_url::{WebUrl, is_url};
use std::collections::BTreeMap;

/// Why a file named by URL cannot be had, worded for the user; it becomes the `problem` of an
/// [`AssetsError::Fetch`] naming where the scene names the URL. Clone, so that the TLS
/// client's setup, made once, can refuse every URL alike.
#[derive(Clone, Debug, thiserror::Error)]
enum FetchProblem {
    /// The environment's download settings.
    #[error("{0}")]
    Setting(String),
    #[error("RESTAURO_CA_FILE {}: {message}", path.display())]
    CaFile { path: PathBuf, message: String },
    #[error("RESTAURO_CA_FILE {}: no PEM certificate", path.display())]
    NoCertificate { path: PathBuf },
    #[error("{0}")]
    Tls(String),
    #[error("the download cache {}: {message}", dir.display())]
    Cache { dir: PathBuf, message: String },
    /// The download itself (the server, the network, a bound), as [`http::download`] words it.
    #[error("{0}")]
    Download(String),
    #[error(
        "it serves a file whose {algorithm} is {actual}, but the scene pins {pinned}: the file \
         changed where it is kept, or the pin is wrong; check the file, then correct [pins]"
    )]
    Mismatch { algorithm: &'static str, actual: String, pinned: String },
    /// A URL without a pin, refused with what it serves now (or why it cannot be fetched).
    #[error("the URL has no pin in [pins], so a render from it could not be made again; {0}")]
    Unpinned(String),
}
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

/// What to do when a server's certificate is not trusted.
const TLS_FIX: &str = "if the server uses a private certificate authority, give its certificate \
                       (PEM) in RESTAURO_CA_FILE";

/// The hash of `bytes` by `algorithm`, in lower-case hexadecimal.
pub fn digest_hex(algorithm: Algorithm, bytes: &[u8]) -> String {
    match algorithm {
        Algorithm::Sha256 => ring::digest::digest(&ring::digest::SHA256, bytes)
            .as_ref()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
        Algorithm::Blake3 => blake3::hash(bytes).to_hex().to_string(),
    }
}

/// Whether `bytes` are what `hash` pins.
pub fn matches(hash: &ContentHash, bytes: &[u8]) -> bool {
    digest_hex(hash.algorithm, bytes) == hash.hex
}

/// What a process lets files by URL reach, set once when it starts. The coordinator fetches
/// for the studio's users: unless its operator allows more, only from public addresses (a user
/// must not reach the farm's own network, or a cloud's metadata service, through it), into its
/// data folder.
#[derive(Clone, Debug, Default)]
pub struct Policy {
    pub public_only: bool,
    pub cache_dir: Option<PathBuf>,
}

static POLICY: OnceLock<Policy> = OnceLock::new();

/// Sets this process's policy; false if it was set already.
pub fn set_policy(policy: Policy) -> bool {
    POLICY.set(policy).is_ok()
}

/// Where downloads are cached and how long the network may take.
#[derive(Clone, Debug)]
pub struct RemoteConfig {
    pub cache: cache::Cache,
    pub timeout: Duration,
    /// The longest one download may take in all ([`DEADLINE_TIMEOUTS`] timeouts from the
    /// environment), however a server trickles its bytes.
    pub deadline: Duration,
    /// Certificates (PEM) trusted besides the system's.
    pub ca_file: Option<PathBuf>,
    /// Refuse hosts at loopback, private, link-local and other non-public addresses.
    pub public_only: bool,
}

impl RemoteConfig {
    /// The configuration the environment gives (see the module's table).
    pub fn from_env() -> Result<RemoteConfig> {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        let number = |name: &str, default: u64| -> Result<u64> {
            var(name).map_or(Ok(default), |v| {
                v.trim()
                    .parse()
                    .map_err(|_| AssetsError::Setting { name: name.to_owned(), value: v.clone() })
            })
        };
        let policy = POLICY.get().cloned().unwrap_or_default();
        let dir = policy.cache_dir.or_else(|| var("RESTAURO_CACHE_DIR").map(PathBuf::from));
        let dir = dir.unwrap_or_else(|| {
            let base = var("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| var("HOME").map(|h| Path::new(&h).join(".cache")))
                .unwrap_or_else(std::env::temp_dir);
            base.join("restauro").join("downloads")
        });
        let timeout = Duration::from_secs(number("RESTAURO_DOWNLOAD_TIMEOUT_S", 30)?.max(1));
        Ok(RemoteConfig {
            cache: cache::Cache { dir, max_bytes: number("RESTAURO_CACHE_MB", 4096)? << 20 },
            timeout,
            deadline: timeout * DEADLINE_TIMEOUTS,
            ca_file: var("RESTAURO_CA_FILE").map(PathBuf::from),
            public_only: policy.public_only,
        })
    }

    /// The TLS client: the system's certificates and those of `ca_file`.
    fn tls(&self) -> std::result::Result<Arc<rustls::ClientConfig>, FetchProblem> {
        use rustls::pki_types::CertificateDer;
        use rustls::pki_types::pem::PemObject;
        let mut roots = rustls::RootCertStore::empty();
        let native = rustls_native_certs::load_native_certs();
        for cert in native.certs {
            let _ = roots.add(cert);
        }
        if let Some(path) = &self.ca_file {
            let certs: Vec<_> = CertificateDer::pem_file_iter(path)
                .and_then(|certs| certs.collect::<Result<Vec<_>, _>>())
                .map_err(|e| ca_file(path, e))?;
            if certs.is_empty() {
                return Err(FetchProblem::NoCertificate { path: path.clone() });
            }
            for cert in certs {
                roots.add(cert).map_err(|e| ca_file(path, e))?;
            }
        }
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let config = rustls::ClientConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .map_err(|e| FetchProblem::Tls(e.to_string()))?
            .with_root_certificates(roots)
            .with_no_client_auth();
        Ok(Arc::new(config))
    }
}

/// The files a scene names by URL: its pins, and (made when the first URL is met) the
/// configuration and TLS client.
pub struct Remote {
    scene_file: PathBuf,
    pins: BTreeMap<String, ContentHash>,
    config: Option<RemoteConfig>,
    ready: OnceLock<std::result::Result<(RemoteConfig, Arc<rustls::ClientConfig>), FetchProblem>>,
}

impl Remote {
    /// Checks the scene's `[pins]`: each key a web URL, each value one well-formed hash.
    pub fn new(scene_file: &Path, pins: &BTreeMap<String, Pin>) -> Result<Remote> {
        Ok(Remote {
            scene_file: scene_file.to_owned(),
            pins: restauro_scene::pins::check_pins(scene_file, pins)?,
            config: None,
            ready: OnceLock::new(),
        })
    }

    /// Uses `config` rather than the environment's.
    pub fn with_config(mut self, config: RemoteConfig) -> Remote {
        self.config = Some(config);
        self
    }

    /// The bytes of the file at `url`, from the cache or the network, checked against its pin.
    /// `place` says where the scene names it, for messages.
    pub fn read(&self, url: &str, place: &str, max_bytes: u64) -> Result<Vec<u8>> {
        let invalid = |problem: String| AssetsError::Fetch {
            scene_file: self.scene_file.clone(),
            place: place.to_owned(),
            problem,
        };
        let parsed = WebUrl::parse(url).map_err(|e| invalid(e.to_string()))?;
        let (config, tls) = self.ready().map_err(|e| invalid(format!("{url}: {e}")))?;
        let bounds = http::Bounds {
            max_bytes,
            timeout: config.timeout,
            deadline: config.deadline,
            tls: tls.clone(),
            public_only: config.public_only,
        };
        let fetched = match self.pins.get(&parsed.to_string()) {
            Some(hash) => fetch_pinned(&parsed, hash, &config.cache, &bounds),
            None => Err(unpinned(&parsed, &config.cache, &bounds)),
        };
        fetched.map_err(|problem| invalid(format!("{parsed}: {problem}")))
    }

    fn ready(
        &self,
    ) -> std::result::Result<&(RemoteConfig, Arc<rustls::ClientConfig>), FetchProblem> {
        self.ready
            .get_or_init(|| {
                let config = match &self.config {
                    Some(c) => c.clone(),
                    None => RemoteConfig::from_env()
                        .map_err(|e| FetchProblem::Setting(e.to_string()))?,
                };
                let tls = config.tls()?;
                Ok((config, tls))
            })
            .as_ref()
            .map_err(Clone::clone)
    }
}

impl Fetch for Remote {
    /// A failure crosses into the scene's loader as the scene model's error, worded the same.
    fn fetch(&self, url: &str, place: &str, max_bytes: u64) -> restauro_scene::Result<Vec<u8>> {
        self.read(url, place, max_bytes).map_err(AssetsError::into_scene_error)
    }
}

/// The file pinned by `hash`: from the cache, or downloaded, checked and cached.
fn fetch_pinned(
    url: &WebUrl,
    hash: &ContentHash,
    cache: &cache::Cache,
    bounds: &http::Bounds,
) -> std::result::Result<Vec<u8>, FetchProblem> {
    if let Some(bytes) = cache.get(hash) {
        return Ok(bytes);
    }
    let cache_problem = |e: std::io::Error| cache_problem(cache, e);
    let mut partial =
        cache.partial(&format!("{}-{}", hash.algorithm.name(), hash.hex)).map_err(cache_problem)?;
    // Another process may have finished it while this one waited for the lock.
    if let Some(bytes) = cache.get(hash) {
        return Ok(bytes);
    }
    tracing::info!(%url, "downloading");
    http::download(url, &mut partial.file, bounds)
        .map_err(|f| FetchProblem::Download(f.problem))?;
    let bytes = std::fs::read(&partial.path).map_err(cache_problem)?;
    let actual = digest_hex(hash.algorithm, &bytes);
    if actual != hash.hex {
        let _ = std::fs::remove_file(&partial.path);
        return Err(FetchProblem::Mismatch {
            algorithm: hash.algorithm.name(),
            actual,
            pinned: hash.hex.clone(),
        });
    }
    cache.store(partial, hash).map_err(cache_problem)?;
    Ok(bytes)
}

/// The refusal of a URL without a pin. The file is fetched all the same (and cached), so that
/// the message can give the pin of what the URL serves now, for the user to check and add.
fn unpinned(url: &WebUrl, cache: &cache::Cache, bounds: &http::Bounds) -> FetchProblem {
    let name = format!("url-{}", &blake3::hash(url.to_string().as_bytes()).to_hex()[..32]);
    let cache_problem = |e: std::io::Error| cache_problem(cache, e);
    let outcome = cache.partial(&name).map_err(cache_problem).and_then(|mut partial| {
        partial.file.set_len(0).map_err(cache_problem)?;
        http::download(url, &mut partial.file, bounds)
            .map_err(|f| FetchProblem::Download(f.problem))?;
        let bytes = std::fs::read(&partial.path).map_err(cache_problem)?;
        let hash = ContentHash {
            algorithm: Algorithm::Sha256,
            hex: digest_hex(Algorithm::Sha256, &bytes),
        };
        cache.store(partial, &hash).map_err(cache_problem)?;
        Ok(hash)
    });
    FetchProblem::Unpinned(match outcome {
        Ok(hash) => format!(
            "it serves a file with {hash}: check that file, then add under [pins] the line \
             \"{url}\" = {{ {hash} }}"
        ),
        Err(problem) => format!("and it cannot be fetched either: {}", unpinned_cause(&problem)),
    })
}

/// What stopped the fetch of an unpinned URL, in the words the refusal used before it was typed:
/// an I/O error of the cache as the system words it, a download's problem as it is.
fn unpinned_cause(problem: &FetchProblem) -> String {
    match problem {
        FetchProblem::Cache { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// A PEM file of `RESTAURO_CA_FILE` that cannot be read or holds a bad certificate.
fn ca_file(path: &Path, e: impl std::fmt::Display) -> FetchProblem {
    FetchProblem::CaFile { path: path.to_owned(), message: e.to_string() }
}

/// The download cache's trouble (a lock, a partial file, storing).
fn cache_problem(cache: &cache::Cache, e: std::io::Error) -> FetchProblem {
    FetchProblem::Cache { dir: cache.dir.clone(), message: e.to_string() }
}
