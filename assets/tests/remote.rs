//! Files named by URL, fetched from a real HTTP (and HTTPS, with a test certificate
//! authority) server on loopback: a pinned file is fetched once and cached; a wrong pin, a
//! 404, a redirect loop, a redirect to another scheme, a silent server and an oversize body
//! are refused with the URL named; a body broken off is resumed with a range request; the
//! cache keeps within its bound; and a scene whose files come from the web bundles to the same
//! identity as the same scene with the files in its folder.

use restauro_assets::AssetsError;
use restauro_assets::bundle_scene;
use restauro_assets::remote::cache::Cache;
use restauro_assets::remote::{Remote, RemoteConfig};
use restauro_scene::assets::{Assets, FolderAssets};
use restauro_scene::bundle::bundle_files;
use restauro_scene::load::{Limits, read_scene_file};
use restauro_scene::scene_file::Pin;
use std::collections::{BTreeMap, HashMap};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// What the test server does for one path.
#[derive(Clone)]
enum Route {
    /// Serves the bytes, honouring `Range: bytes=N-`.
    File(Vec<u8>),
    /// Like `File`, but the first answer announces the whole length and stops after `cut`
    /// bytes.
    BreakOnce(Vec<u8>, usize, Arc<AtomicBool>),
    Status(u16),
    Redirect(String),
    /// Reads the request and never answers.
    Silent,
    /// Announces a length and sends nothing.
    Announce(u64),
    /// Sends bytes without a length until the client hangs up.
    Endless,
    /// Announces 1000 bytes and sends one every 200 ms.
    Trickle,
    /// Answers with this status line and headers, and no body.
    Raw(&'static str),
}

/// Each request's path and `Range` header.
type RequestLog = Mutex<Vec<(String, Option<String>)>>;

struct Server {
    base: String,
    requests: Arc<RequestLog>,
}

fn serve<P: Into<String>>(
    routes: Vec<(P, Route)>,
    tls: Option<Arc<rustls::ServerConfig>>,
) -> Server {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let scheme = if tls.is_some() { "https" } else { "http" };
    let routes: Arc<HashMap<String, Route>> =
        Arc::new(routes.into_iter().map(|(p, r)| (p.into(), r)).collect());
    let requests = Arc::new(Mutex::new(Vec::new()));
    let log = requests.clone();
    std::thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(stream) = stream else { continue };
            let (routes, log, tls) = (routes.clone(), log.clone(), tls.clone());
            std::thread::spawn(move || match tls {
                Some(config) => {
                    let connection = rustls::ServerConnection::new(config).unwrap();
                    answer(rustls::StreamOwned::new(connection, stream), &routes, &log);
                }
                None => answer(stream, &routes, &log),
            });
        }
    });
    Server { base: format!("{scheme}://127.0.0.1:{port}"), requests }
}

fn answer<S: Read + Write>(mut stream: S, routes: &HashMap<String, Route>, log: &RequestLog) {
    let (path, range) = {
        let mut reader = BufReader::new(&mut stream);
        let mut line = String::new();
        if reader.read_line(&mut line).is_err() {
            return;
        }
        let path = line.split_whitespace().nth(1).unwrap_or("/").to_owned();
        let mut range = None;
        loop {
            let mut header = String::new();
            if reader.read_line(&mut header).unwrap_or(0) == 0 || header.trim().is_empty() {
                break;
            }
            if let Some((name, value)) = header.split_once(':')
                && name.eq_ignore_ascii_case("range")
            {
                range = Some(value.trim().to_owned());
            }
        }
        (path, range)
    };
    log.lock().unwrap().push((path.clone(), range.clone()));
    let from = range
        .as_deref()
        .and_then(|r| r.strip_prefix("bytes="))
        .and_then(|r| r.trim_end_matches('-').parse::<usize>().ok());
    let head = |status: &str, headers: String| {
        format!("HTTP/1.1 {status}\r\nConnection: close\r\n{headers}\r\n").into_bytes()
    };
    let send_file = |stream: &mut S, bytes: &[u8], cut: Option<usize>| {
        let (status, start) = match from {
            Some(start) if start <= bytes.len() => ("206 Partial Content", start),
            _ => ("200 OK", 0),
        };
        let mut headers = format!("Content-Length: {}\r\n", bytes.len() - start);
        if start > 0 || status.starts_with("206") {
            headers +=
                &format!("Content-Range: bytes {start}-{}/{}\r\n", bytes.len() - 1, bytes.len());
        }
        let _ = stream.write_all(&head(status, headers));
        let end = cut.map_or(bytes.len(), |c| c.min(bytes.len()));
        let _ = stream.write_all(&bytes[start..end]);
        let _ = stream.flush();
    };
    match routes.get(&path).cloned().unwrap_or(Route::Status(404)) {
        Route::File(bytes) => send_file(&mut stream, &bytes, None),
        Route::BreakOnce(bytes, cut, broken) => {
            let cut = (!broken.swap(true, Ordering::SeqCst)).then_some(cut);
            send_file(&mut stream, &bytes, cut);
        }
        Route::Status(code) => {
            let _ =
                stream.write_all(&head(&format!("{code} Status"), "Content-Length: 0\r\n".into()));
        }
        Route::Redirect(to) => {
            let headers = format!("Location: {to}\r\nContent-Length: 0\r\n");
            let _ = stream.write_all(&head("302 Found", headers));
        }
        Route::Silent => std::thread::sleep(Duration::from_secs(60)),
        Route::Announce(length) => {
            let _ = stream.write_all(&head("200 OK", format!("Content-Length: {length}\r\n")));
            let _ = stream.flush();
            std::thread::sleep(Duration::from_secs(5));
        }
        Route::Raw(raw) => {
            let (status, headers) = raw.split_once("\r\n").unwrap_or((raw, ""));
            let _ = stream.write_all(&head(status, headers.to_owned()));
        }
        Route::Trickle => {
            let _ = stream.write_all(&head("200 OK", "Content-Length: 1000\r\n".into()));
            while stream.write_all(b"x").and_then(|()| stream.flush()).is_ok() {
                std::thread::sleep(Duration::from_millis(200));
            }
        }
        Route::Endless => {
            let _ = stream.write_all(&head("200 OK", String::new()));
            let chunk = vec![b'x'; 64 * 1024];
            while stream.write_all(&chunk).is_ok() {}
        }
    }
}

/// A certificate authority, and a server certificate for 127.0.0.1 that it signed: the
/// server's TLS configuration and the authority's certificate (PEM) in `dir`.
fn test_authority(dir: &Path) -> (Arc<rustls::ServerConfig>, PathBuf) {
    use rcgen::{BasicConstraints, CertificateParams, IsCa, Issuer, KeyPair};
    let ca_key = KeyPair::generate().unwrap();
    let mut ca_params = CertificateParams::new(Vec::<String>::new()).unwrap();
    ca_params.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    let ca = ca_params.self_signed(&ca_key).unwrap();
    let issuer = Issuer::new(ca_params, ca_key);
    let key = KeyPair::generate().unwrap();
    let server = CertificateParams::new(vec!["127.0.0.1".to_owned()])
        .unwrap()
        .signed_by(&key, &issuer)
        .unwrap();
    let ca_file = dir.join("test-ca.pem");
    std::fs::write(&ca_file, ca.pem()).unwrap();
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .unwrap()
        .with_no_client_auth()
        .with_single_cert(
            vec![server.der().clone()],
            rustls::pki_types::PrivateKeyDer::Pkcs8(key.serialize_der().into()),
        )
        .unwrap();
    (Arc::new(config), ca_file)
}

/// SHA-256 by `sha256sum`, a program apart from the code under test.
fn sha256sum(bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("file");
    std::fs::write(&path, bytes).unwrap();
    let out = std::process::Command::new("sha256sum").arg(&path).output().unwrap();
    String::from_utf8(out.stdout).unwrap().split_whitespace().next().unwrap().to_owned()
}

fn config(dir: &Path, ca_file: Option<PathBuf>) -> RemoteConfig {
    RemoteConfig {
        cache: Cache { dir: dir.join("cache"), max_bytes: 1 << 30 },
        timeout: Duration::from_secs(1),
        deadline: Duration::from_secs(30),
        ca_file,
        public_only: false,
    }
}

/// The files of the folder of the scene file `scene`, within `max_bytes` each, those named by
/// URL fetched as `pins` say, with `config`.
fn folder(
    scene: &Path,
    max_bytes: u64,
    pins: &BTreeMap<String, Pin>,
    config: RemoteConfig,
) -> Result<FolderAssets, AssetsError> {
    let remote = Remote::new(scene, pins)?.with_config(config);
    Ok(FolderAssets::new(scene, max_bytes)?.with_fetch(Box::new(remote)))
}

/// The folder assets of an empty scene in `dir`, with `pins`.
fn assets(dir: &Path, pins: &[(&str, &[u8])], config: RemoteConfig) -> FolderAssets {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, "").unwrap();
    let pins: BTreeMap<String, Pin> = pins
        .iter()
        .map(|(url, bytes)| {
            ((*url).to_owned(), Pin { sha256: Some(sha256sum(bytes)), blake3: None })
        })
        .collect();
    folder(&scene, 1 << 20, &pins, config).unwrap()
}

fn cached(dir: &Path, bytes: &[u8]) -> bool {
    dir.join("cache/sha256").join(sha256sum(bytes)).is_file()
}

const WALL: &[u8] = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";

#[test]
fn a_pinned_file_is_fetched_once_checked_and_cached() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/wall.obj", Route::File(WALL.to_vec()))], None);
    let url = format!("{}/wall.obj", server.base);
    for _ in 0..2 {
        let assets = assets(dir.path(), &[(&url, WALL)], config(dir.path(), None));
        assert_eq!(assets.read(&url, "objects[0].mesh").unwrap(), WALL);
    }
    assert_eq!(server.requests.lock().unwrap().len(), 1, "the second read is the cache's");
    assert!(cached(dir.path(), WALL));
}

#[test]
fn https_is_fetched_with_the_authority_given_and_refused_without_it() {
    let dir = tempfile::tempdir().unwrap();
    let (tls, ca_file) = test_authority(dir.path());
    let server = serve(vec![("/wall.obj", Route::File(WALL.to_vec()))], Some(tls));
    let url = format!("{}/wall.obj", server.base);
    let untrusted = assets(dir.path(), &[(&url, WALL)], config(dir.path(), None));
    let e = untrusted.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("TLS") && e.contains("RESTAURO_CA_FILE"), "{e}");
    let trusted = assets(dir.path(), &[(&url, WALL)], config(dir.path(), Some(ca_file)));
    assert_eq!(trusted.read(&url, "objects[0].mesh").unwrap(), WALL);
}

#[test]
fn a_wrong_pin_is_refused_and_nothing_is_cached() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/wall.obj", Route::File(WALL.to_vec()))], None);
    let url = format!("{}/wall.obj", server.base);
    let other = b"another file";
    let assets = assets(dir.path(), &[(&url, other)], config(dir.path(), None));
    let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains("objects[0].mesh") && e.contains(&url), "{e}");
    assert!(e.contains(&sha256sum(WALL)) && e.contains(&sha256sum(other)), "{e}");
    assert!(e.contains("[pins]"), "{e}");
    assert!(!cached(dir.path(), WALL) && !cached(dir.path(), other));
    let partial = std::fs::read_dir(dir.path().join("cache/partial")).unwrap().count();
    assert_eq!(partial, 0, "the rejected download is not kept");
}

#[test]
fn a_broken_off_body_is_resumed_with_a_range_request() {
    let dir = tempfile::tempdir().unwrap();
    let body: Vec<u8> = (0..100_000u32).flat_map(|i| i.to_le_bytes()).collect();
    let route = Route::BreakOnce(body.clone(), 150_000, Arc::new(AtomicBool::new(false)));
    let server = serve(vec![("/scan.ply", route)], None);
    let url = format!("{}/scan.ply", server.base);
    let assets = assets(dir.path(), &[(&url, &body)], config(dir.path(), None));
    assert_eq!(assets.read(&url, "objects[0].mesh").unwrap(), body);
    let requests = server.requests.lock().unwrap().clone();
    assert_eq!(requests.len(), 2, "{requests:?}");
    assert_eq!(requests[0].1, None);
    assert_eq!(requests[1].1.as_deref(), Some("bytes=150000-"), "{requests:?}");
}

#[test]
fn a_missing_file_names_the_url_and_the_status() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(Vec::<(&str, Route)>::new(), None);
    let url = format!("{}/gone.obj", server.base);
    let assets = assets(dir.path(), &[(&url, WALL)], config(dir.path(), None));
    let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("404"), "{e}");
}

#[test]
fn redirects_are_followed_but_not_in_loops_nor_to_other_schemes() {
    let dir = tempfile::tempdir().unwrap();
    let (tls, ca_file) = test_authority(dir.path());
    let plain = serve(vec![("/wall.obj", Route::File(WALL.to_vec()))], None);
    let to_plain = format!("{}/wall.obj", plain.base);
    let server = serve(
        vec![
            ("/old.obj", Route::Redirect("/new/../wall.obj".into())),
            ("/wall.obj", Route::File(WALL.to_vec())),
            ("/a", Route::Redirect("/b".into())),
            ("/b", Route::Redirect("/a".into())),
            ("/ftp", Route::Redirect("ftp://127.0.0.1/wall.obj".into())),
            ("/down", Route::Redirect(to_plain)),
        ],
        Some(tls),
    );
    let url = |path: &str| format!("{}{path}", server.base);
    // The cache holds files by content: each refused URL gets a pin of its own, so that the
    // cache cannot answer for it.
    let pins: Vec<(String, &[u8])> = [
        ("/old.obj", WALL),
        ("/a", b"a loop".as_slice()),
        ("/ftp", b"ftp".as_slice()),
        ("/down", b"down".as_slice()),
    ]
    .iter()
    .map(|(p, bytes)| (url(p), *bytes))
    .collect();
    let pins: Vec<(&str, &[u8])> = pins.iter().map(|(u, b)| (u.as_str(), *b)).collect();
    let assets = assets(dir.path(), &pins, config(dir.path(), Some(ca_file)));
    assert_eq!(assets.read(&url("/old.obj"), "mesh").unwrap(), WALL);
    let e = assets.read(&url("/a"), "mesh").unwrap_err().to_string();
    assert!(e.contains(&url("/a")) && e.contains("redirect loop"), "{e}");
    let e = assets.read(&url("/ftp"), "mesh").unwrap_err().to_string();
    assert!(e.contains(&url("/ftp")) && e.contains("not ftp://"), "{e}");
    let e = assets.read(&url("/down"), "mesh").unwrap_err().to_string();
    assert!(e.contains(&url("/down")) && e.contains("from https to http"), "{e}");
    assert!(plain.requests.lock().unwrap().is_empty(), "nothing is fetched in the clear");
}

#[test]
fn a_silent_server_times_out() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/wall.obj", Route::Silent)], None);
    let url = format!("{}/wall.obj", server.base);
    let assets = assets(dir.path(), &[(&url, WALL)], config(dir.path(), None));
    let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("no answer within 1 s"), "{e}");
    assert!(e.contains("RESTAURO_DOWNLOAD_TIMEOUT_S"), "{e}");
}

#[test]
fn oversize_bodies_are_refused_announced_or_not() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(
        vec![("/huge.ply", Route::Announce(5 << 30)), ("/endless.ply", Route::Endless)],
        None,
    );
    for path in ["/huge.ply", "/endless.ply"] {
        let url = format!("{}{path}", server.base);
        let assets = assets(dir.path(), &[(&url, WALL)], config(dir.path(), None));
        let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
        assert!(e.contains(&url) && e.contains("over the limit of 1048576 bytes"), "{e}");
        assert!(e.contains("--max-file-mb"), "{e}");
    }
}

/// The message gives the pin of what the URL serves, so that the user can check and add it:
/// "abc" is FIPS 180-2's first example, whose SHA-256 the standard publishes.
#[test]
fn an_unpinned_url_is_refused_with_the_pin_of_what_it_serves() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/abc.csv", Route::File(b"abc".to_vec()))], None);
    let url = format!("{}/abc.csv", server.base);
    let assets = assets(dir.path(), &[], config(dir.path(), None));
    let e = assets.read(&url, "spectra.stone.file").unwrap_err().to_string();
    let fips = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
    assert!(e.contains("no pin in [pins]"), "{e}");
    assert!(e.contains(&format!("\"{url}\" = {{ sha256 = \"{fips}\" }}")), "{e}");
}

#[test]
fn the_cache_keeps_within_its_bound_dropping_the_least_recently_used() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (vec![b'a'; 600], vec![b'b'; 600]);
    let server =
        serve(vec![("/a.csv", Route::File(a.clone())), ("/b.csv", Route::File(b.clone()))], None);
    let (url_a, url_b) = (format!("{}/a.csv", server.base), format!("{}/b.csv", server.base));
    let mut small = config(dir.path(), None);
    small.cache.max_bytes = 1000;
    let assets = assets(dir.path(), &[(&url_a, &a), (&url_b, &b)], small);
    assets.read(&url_a, "a").unwrap();
    assert!(cached(dir.path(), &a));
    assets.read(&url_b, "b").unwrap();
    assert!(!cached(dir.path(), &a) && cached(dir.path(), &b), "a was dropped for b");
}

/// A glTF with its buffer and its photo beside it, and the scene's own photo, all on a web
/// server: the scene bundles to the same identity as with the files in its folder.
#[test]
fn a_scene_from_the_web_bundles_like_the_same_scene_from_its_folder() {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0];
    let uv: [f32; 6] = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0];
    let mut buffer: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    buffer.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    let gltf = br#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"material":0}]}],
        "materials":[{"name":"stone","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "textures":[{"source":0}],"images":[{"uri":"../photos/albedo.png"}],
        "buffers":[{"byteLength":60,"uri":"tri.bin"}],
        "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,-1],"max":[1,0,0]},
                     {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}]}"#;
    let mut png = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png, 1, 1);
        encoder.set_color(png::ColorType::Rgb);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[200, 180, 150]).unwrap();
    }
    let files: [(&str, &[u8]); 3] =
        [("models/tri.gltf", gltf), ("models/tri.bin", &buffer), ("photos/albedo.png", &png)];
    let server = serve(
        files
            .iter()
            .map(|(name, bytes)| (format!("/{name}"), Route::File(bytes.to_vec())))
            .collect(),
        None,
    );
    let scene = |mesh: &str, pins: &str| {
        format!(
            "format = 1\n[camera]\nposition = [0.5, 0.5, 3.0]\ntarget = [0.5, 0.5, 0.0]\nup = [0, 1, 0]\nwidth = 8\nheight = 8\n\
             [spectra]\nday = {{ illuminant = \"D65\" }}\ngrey = {{ constant = 0.5 }}\n\
             [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
             [[objects]]\nname = \"tri\"\nmesh = \"{mesh}\"\nmaterial = \"stone\"\n\
             [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n\
             {pins}"
        )
    };
    let local = tempfile::tempdir().unwrap();
    for (name, bytes) in &files {
        let path = local.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    std::fs::write(local.path().join("scene.toml"), scene("models/tri.gltf", "")).unwrap();
    let from_folder = bundle_scene(&local.path().join("scene.toml"), &Limits::default()).unwrap();

    let web = tempfile::tempdir().unwrap();
    let mut pins = String::from("[pins]\n");
    for (name, bytes) in &files {
        pins += &format!("\"{}/{name}\" = {{ sha256 = \"{}\" }}\n", server.base, sha256sum(bytes));
    }
    let toml = scene(&format!("{}/models/tri.gltf", server.base), &pins);
    let path = web.path().join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    let file = read_scene_file(&path, &Limits::default()).unwrap();
    let assets = folder(&path, 1 << 30, &file.pins, config(web.path(), None)).unwrap();
    let from_web = bundle_files(file, &assets, &Limits::default()).unwrap();
    assert_eq!(from_web.id(), from_folder.id(), "the same scene, the same identity");
    assert!(from_web.scene.pins.is_empty());
    let loaded = from_web.load(&Limits::default()).unwrap();
    assert_eq!(loaded.objects[0].mesh.positions.len(), 3);
    assert_eq!(server.requests.lock().unwrap().len(), 3, "each file fetched once");
}

/// A coordinator fetches for the studio's users, so only from public addresses: loopback here
/// stands for the farm's own network.
#[test]
fn a_process_that_fetches_from_public_addresses_only_refuses_loopback() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/wall.obj", Route::File(WALL.to_vec()))], None);
    let url = format!("{}/wall.obj", server.base);
    let mut public = config(dir.path(), None);
    public.public_only = true;
    let assets = assets(dir.path(), &[(&url, WALL)], public);
    let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("127.0.0.1, not a public address"), "{e}");
    assert!(e.contains("--fetch-private-urls"), "{e}");
    assert!(server.requests.lock().unwrap().is_empty());
}

/// A remote VRML97 world whose `Inline` names a file relative to it: the url resolves against
/// the world's (RFC 3986) and is fetched and pinned like the world; an inlined file without a
/// pin is refused with its pin.
#[test]
fn a_remote_worlds_inline_resolves_against_its_url_and_is_pinned_too() {
    let world =
        b"#VRML V2.0 utf8\nShape { geometry Box {} }\nInline { url \"../parts/column.wrl\" }\n";
    let column =
        b"#VRML V2.0 utf8\nTransform { translation 5 0 0 children Shape { geometry Box {} } }\n";
    let server = serve(
        vec![
            ("/site/world.wrl", Route::File(world.to_vec())),
            ("/parts/column.wrl", Route::File(column.to_vec())),
        ],
        None,
    );
    let (world_url, column_url) =
        (format!("{}/site/world.wrl", server.base), format!("{}/parts/column.wrl", server.base));
    let scene = |pins: &[(&str, &[u8])]| {
        let mut toml = format!(
            "format = 1\n[camera]\nposition = [0.0, -20.0, 2.0]\ntarget = [0.0, 0.0, 2.0]\nwidth = 8\nheight = 8\n\
             [spectra]\nday = {{ illuminant = \"D65\" }}\ngrey = {{ constant = 0.5 }}\n\
             [materials.stone]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
             [[objects]]\nname = \"world\"\nmesh = \"{world_url}\"\nmaterial = \"stone\"\n\
             [[lights]]\nkind = \"sun\"\nilluminance_lux = 1000.0\nazimuth_deg = 0.0\nelevation_deg = 60.0\nspectrum = \"day\"\n\
             [pins]\n"
        );
        for (url, bytes) in pins {
            toml += &format!("\"{url}\" = {{ sha256 = \"{}\" }}\n", sha256sum(bytes));
        }
        toml
    };
    let dir = tempfile::tempdir().unwrap();
    let bundle = |toml: String| {
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, toml).unwrap();
        let file = read_scene_file(&path, &Limits::default()).unwrap();
        let assets = folder(&path, 1 << 30, &file.pins, config(dir.path(), None)).unwrap();
        bundle_files(file, &assets, &Limits::default())
    };
    let e = bundle(scene(&[(&world_url, world)])).unwrap_err().to_string();
    assert!(e.contains(&column_url) && e.contains("no pin in [pins]"), "{e}");
    assert!(e.contains(&sha256sum(column)), "{e}");
    let done = bundle(scene(&[(&world_url, world), (&column_url, column)])).unwrap();
    assert_eq!(done.scene.included.len(), 1);
    let loaded = done.load(&Limits::default()).unwrap();
    assert_eq!(loaded.objects[0].mesh.triangles.len(), 24, "the world's box and the column's");
}

/// A server that sends a byte now and then, never silent for the timeout, is cut off at the
/// download's deadline, and what came is kept for the next run to resume.
#[test]
fn a_trickling_server_is_cut_off_at_the_deadline() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(vec![("/slow.obj", Route::Trickle)], None);
    let url = format!("{}/slow.obj", server.base);
    let mut short = config(dir.path(), None);
    short.deadline = Duration::from_secs(2);
    let assets = assets(dir.path(), &[(&url, WALL)], short);
    let e = assets.read(&url, "objects[0].mesh").unwrap_err().to_string();
    assert!(e.contains(&url) && e.contains("took longer than 2 s"), "{e}");
    let kept: u64 = std::fs::read_dir(dir.path().join("cache/partial"))
        .unwrap()
        .map(|f| f.unwrap().metadata().unwrap().len())
        .sum();
    assert!(kept > 0, "what came is kept");
}

/// Pins that cannot be checked are refused before anything is fetched, naming the pin and the
/// fix.
#[test]
fn pins_that_cannot_be_checked_are_refused_with_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, "").unwrap();
    let hex = "ab".repeat(32);
    for (url, pin, words) in [
        (
            "ftp://x.org/a.obj",
            Pin { sha256: Some(hex.clone()), blake3: None },
            "only https:// and http://",
        ),
        (
            "https://x.org/a.obj",
            Pin { sha256: Some(hex.clone()), blake3: Some(hex.clone()) },
            "give one hash",
        ),
        ("https://x.org/a.obj", Pin { sha256: None, blake3: None }, "give one hash"),
        (
            "https://x.org/a.obj",
            Pin { sha256: Some("abc".into()), blake3: None },
            "not 64 hexadecimal digits; copy it whole from `sha256sum`",
        ),
    ] {
        let pins = BTreeMap::from([(url.to_owned(), pin)]);
        let e = folder(&scene, 1 << 20, &pins, config(dir.path(), None))
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains(&format!("pins.\"{url}\"")) && e.contains(words), "{e}");
    }
}

/// Answers a download cannot go on from: a redirect without a Location, part of a file
/// without saying which part.
#[test]
fn answers_without_what_they_need_are_refused_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(
        vec![
            ("/moved", Route::Raw("302 Found\r\nContent-Length: 0\r\n")),
            ("/part", Route::Raw("206 Partial Content\r\nContent-Length: 0\r\n")),
        ],
        None,
    );
    let url = |path: &str| format!("{}{path}", server.base);
    let pins = [(url("/moved"), b"moved".as_slice()), (url("/part"), b"part".as_slice())];
    let pins: Vec<(&str, &[u8])> = pins.iter().map(|(u, b)| (u.as_str(), *b)).collect();
    let assets = assets(dir.path(), &pins, config(dir.path(), None));
    let e = assets.read(&url("/moved"), "mesh").unwrap_err().to_string();
    assert!(
        e.contains(&url("/moved")) && e.contains("redirected (302 Found) without a Location"),
        "{e}"
    );
    let e = assets.read(&url("/part"), "mesh").unwrap_err().to_string();
    assert!(e.contains(&url("/part")) && e.contains("without saying which part"), "{e}");
}
