//! A scene whose files are on a web server, through the real `restauro` binary: the client
//! fetches each file once into the cache the environment names, the bundle has the identity of
//! the same scene with its files in its folder, and the embedded cluster renders it without a
//! worker fetching anything.

use restauro_tests::web::{scene_by_url, serve_folder};
use restauro_tests::{aosta_scene, binary, output_within, patience, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn restauro_with_cache(cache: &Path, args: &[&str]) -> Output {
    let mut command = Command::new(binary("restauro"));
    command.args(args).env_remove("RESTAURO_COORDINATOR").env("RESTAURO_CACHE_DIR", cache);
    output_within(&mut command, patience())
}

/// The identity `scene bundle` prints (its last line).
fn identity(o: &Output) -> String {
    assert!(o.status.success(), "{}", text(o));
    String::from_utf8_lossy(&o.stdout).lines().last().unwrap_or_default().to_owned()
}

#[test]
fn a_scene_from_a_web_server_is_fetched_once_and_rendered_by_the_cluster() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let local = PathBuf::from(aosta_scene(d, 16, 8));
    let folder = local.parent().unwrap().to_owned();
    let (base, requests) = serve_folder(folder);
    let web = d.join("web");
    std::fs::create_dir_all(&web).unwrap();
    let remote = web.join("aosta.toml");
    let files = scene_by_url(&local, &base, &remote);
    assert!(files > 0, "the Aosta scene names its mesh");

    let cache = d.join("cache");
    let from_folder =
        identity(&restauro_with_cache(&cache, &["scene", "bundle", local.to_str().unwrap()]));
    let from_web =
        identity(&restauro_with_cache(&cache, &["scene", "bundle", remote.to_str().unwrap()]));
    assert_eq!(from_web, from_folder, "the same scene, the same identity");
    assert_eq!(requests.lock().unwrap().len(), files, "each file fetched once");
    assert!(cache.join("blake3").read_dir().unwrap().count() >= files);

    let out = d.join("render");
    let o = restauro_with_cache(
        &cache,
        &["render", remote.to_str().unwrap(), "--spp", "1", "--out", out.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read_dir(&out).unwrap().count() > 0, "the images are written");
    // The client found every file in its cache; the workers got them from the coordinator.
    assert_eq!(requests.lock().unwrap().len(), files, "nothing fetched again");
}

/// The environment's settings for fetching, when they cannot be used, are refused naming the
/// variable, before anything is fetched.
#[test]
fn unusable_download_settings_are_refused_naming_the_variable() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let local = PathBuf::from(aosta_scene(d, 16, 8));
    // A port nobody listens on: the refusals come before any connection.
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let remote = d.join("remote.toml");
    scene_by_url(&local, &format!("http://127.0.0.1:{port}"), &remote);
    let not_pem = d.join("not.pem");
    std::fs::write(&not_pem, "not a certificate").unwrap();
    for (variable, value, words) in [
        ("RESTAURO_CACHE_MB", "lots", "RESTAURO_CACHE_MB: `lots` is not a whole number"),
        ("RESTAURO_CA_FILE", not_pem.to_str().unwrap(), "no PEM certificate"),
    ] {
        let mut command = Command::new(binary("restauro"));
        command
            .args(["scene", "check", remote.to_str().unwrap()])
            .env("RESTAURO_CACHE_DIR", d.join("cache"))
            .env(variable, value);
        let o = output_within(&mut command, patience());
        assert!(!o.status.success(), "{}", text(&o));
        assert!(text(&o).contains(words), "{}", text(&o));
    }
}
