//! TLS between real processes: a coordinator serving a certificate signed by a site's own
//! authority, a worker and a client that trust that authority, and clients that do not.

use restauro_tests::{Coordinator, Worker, aosta_scene, restauro, text, token_files};
use std::path::Path;

/// A certificate authority and a server certificate for `localhost` signed by it, as PEM files
/// in `dir`: (ca.pem, server.pem, server.key).
fn certificates(dir: &Path) -> (String, String, String) {
    use rcgen::{BasicConstraints, CertificateParams, IsCa, Issuer, KeyPair};
    let ca_key = KeyPair::generate().unwrap();
    let mut ca_params = CertificateParams::new(Vec::<String>::new()).unwrap();
    ca_params.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    let ca = ca_params.self_signed(&ca_key).unwrap();
    let issuer = Issuer::new(ca_params, ca_key);
    let key = KeyPair::generate().unwrap();
    let server = CertificateParams::new(vec!["localhost".to_owned()])
        .unwrap()
        .signed_by(&key, &issuer)
        .unwrap();
    let write = |name: &str, pem: String| {
        let path = dir.join(name);
        std::fs::write(&path, pem).unwrap();
        path.to_str().unwrap().to_owned()
    };
    (
        write("ca.pem", ca.pem()),
        write("server.pem", server.pem()),
        write("server.key", key.serialize_pem()),
    )
}

#[test]
fn a_render_travels_over_tls_and_an_untrusting_or_plaintext_client_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ca, cert, key) = certificates(d);
    let scene = aosta_scene(d, 64, 36);
    let coordinator = Coordinator::start(
        d,
        &d.join("data"),
        "127.0.0.1:0",
        &["--tls-cert", &cert, "--tls-key", &key],
    );
    let port = coordinator.url.rsplit(':').next().unwrap().to_owned();
    let https = format!("https://localhost:{port}");
    let _worker = Worker::start(d, &https, "w1", &["--tls-ca", &ca]);
    let (client_token, _) = token_files(d);
    let token = client_token.to_str().unwrap();
    let out = d.join("out");
    let o = restauro(&[
        "submit",
        &scene,
        "--spp",
        "2",
        "--coordinator",
        &https,
        "--token-file",
        token,
        "--tls-ca",
        &ca,
        "--wait",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("aosta.exr").exists() && out.join("aosta.png").exists(), "{}", text(&o));

    // Without the site's authority the certificate is not trusted.
    let o = restauro(&["jobs", "--coordinator", &https, "--token-file", token]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).to_lowercase().contains("certificate"), "{}", text(&o));
    // Plaintext against the TLS port gets nowhere either.
    let o = restauro(&["jobs", "--coordinator", &coordinator.url, "--token-file", token]);
    assert!(!o.status.success(), "{}", text(&o));
    // A CA file for a plaintext URL is a mistake, said so.
    let o = restauro(&[
        "jobs",
        "--coordinator",
        &coordinator.url,
        "--token-file",
        token,
        "--tls-ca",
        &ca,
    ]);
    assert!(text(&o).contains("use https://"), "{}", text(&o));
}

/// The studio beside a TLS coordinator is served over TLS with its certificate: a client that
/// trusts the site's authority signs in and its session cookie is `Secure`; plain HTTP to that
/// port is answered by no studio.
#[test]
fn the_studio_is_served_over_tls_with_the_coordinators_certificate() {
    use restauro_tests::http::{request, request_tls};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ca, cert, key) = certificates(d);
    let tls = ["--tls-cert", &cert, "--tls-key", &key, "--studio-listen", "127.0.0.1:0"];
    let coordinator = Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &tls);
    let studio = coordinator.studio.clone().unwrap();
    let port = studio.rsplit(':').next().unwrap();
    let at = format!("localhost:{port}");
    let ca = Path::new(&ca);
    let token = format!("{{\"token\": \"{}\"}}", restauro_tests::CLIENT_TOKEN);
    let origin = format!("https://{at}");
    let headers = [("Origin", origin.as_str()), ("Content-Type", "application/json")];
    let r = request_tls(&at, ca, "POST", "/api/session", &headers, token.as_bytes());
    assert!(r.status < 300, "{} {}", r.status, r.text());
    let cookie = r.header("set-cookie").unwrap().to_owned();
    assert!(cookie.contains("; Secure") && cookie.contains("HttpOnly"), "{cookie}");
    let session = cookie.split(';').next().unwrap().to_owned();
    let me = request_tls(&at, ca, "GET", "/api/whoami", &[("Cookie", &session)], b"");
    assert_eq!(me.status, 200, "{}", me.text());
    assert_eq!(me.json()["role"], "client");
    let page = request_tls(&at, ca, "GET", "/", &[], b"");
    assert_eq!(page.status, 200);
    assert!(page.text().contains("restauro studio"));
    // Plain HTTP to the TLS port gets no page: the connection is closed or refused.
    let plain = std::panic::catch_unwind(|| request(&studio, "GET", "/", &[], b""));
    assert!(plain.map_or(true, |r| r.status != 200), "plain HTTP served the studio");
}

#[test]
fn files_that_are_not_pem_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (client_token, worker_token) = token_files(d);
    let junk = d.join("junk.pem");
    std::fs::write(&junk, "not a certificate").unwrap();
    let junk = junk.to_str().unwrap();
    // The coordinator checks its certificate before it listens.
    let mut coordinator =
        std::process::Command::new(restauro_tests::binary("restauro-coordinator"));
    coordinator
        .args(["--listen", "127.0.0.1:0", "--data", d.join("data").to_str().unwrap()])
        .args(["--client-token-file", client_token.to_str().unwrap()])
        .args(["--worker-token-file", worker_token.to_str().unwrap()])
        .args(["--tls-cert", junk, "--tls-key", junk]);
    let o = restauro_tests::output_within(&mut coordinator, restauro_tests::patience());
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains(&format!("the TLS certificate {junk} is not PEM")), "{}", text(&o));
    // A client given a CA file that is not a certificate says which file.
    let o = restauro(&[
        "jobs",
        "--coordinator",
        "https://localhost:1",
        "--token-file",
        client_token.to_str().unwrap(),
        "--tls-ca",
        junk,
    ]);
    assert!(!o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains(&format!("the CA certificate {junk}: not a PEM certificate")),
        "{}",
        text(&o)
    );
}
