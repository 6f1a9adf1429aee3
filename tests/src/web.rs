//! A scene's files on a web server: a plain HTTP/1.1 file server on loopback, and the scene
//! rewritten to name its files by URL, pinned.

use restauro_scene::bundle::Bundle;
use restauro_scene::load::{Limits, read_scene_file};
use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The paths a [`serve_folder`] server was asked for.
pub type Requests = Arc<Mutex<Vec<String>>>;

/// Serves the files under `root` over HTTP/1.1 on loopback: its base URL, and the paths asked.
pub fn serve_folder(root: PathBuf) -> (String, Requests) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let base = format!("http://{}", listener.local_addr().unwrap());
    let requests = Requests::default();
    let log = requests.clone();
    std::thread::spawn(move || {
        for mut stream in listener.incoming().flatten() {
            let mut line = String::new();
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            if reader.read_line(&mut line).is_err() {
                continue;
            }
            let mut header = String::new();
            while reader.read_line(&mut header).unwrap_or(0) > 2 {
                header.clear();
            }
            let path = line.split_whitespace().nth(1).unwrap_or("/").to_owned();
            log.lock().unwrap().push(path.clone());
            let answer = match std::fs::read(root.join(path.trim_start_matches('/'))) {
                Ok(body) => {
                    let mut a = format!("HTTP/1.1 200 OK\r\nContent-Length: {}\r\n", body.len());
                    a += "Connection: close\r\n\r\n";
                    [a.into_bytes(), body].concat()
                }
                Err(_) => b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\n\r\n".to_vec(),
            };
            let _ = stream.write_all(&answer);
        }
    });
    (base, requests)
}

/// Writes to `out` the scene file `scene` with each file it names replaced by its URL under
/// `base` (where [`serve_folder`] serves the scene's folder) and pinned by its BLAKE3; the
/// number of files.
pub fn scene_by_url(scene: &Path, base: &str, out: &Path) -> usize {
    let folder = scene.parent().unwrap();
    let mut text = std::fs::read_to_string(scene).unwrap();
    let mut file = read_scene_file(scene, &Limits::default()).unwrap();
    let mut files: Vec<String> =
        Bundle::references_mut(&mut file).into_iter().map(|r| r.clone()).collect();
    files.sort();
    files.dedup();
    let mut pins = String::from("\n[pins]\n");
    for name in &files {
        let url = format!("{base}/{name}");
        text = text.replace(&format!("\"{name}\""), &format!("\"{url}\""));
        let hash = blake3::hash(&std::fs::read(folder.join(name)).unwrap()).to_hex();
        pins += &format!("\"{url}\" = {{ blake3 = \"{hash}\" }}\n");
    }
    std::fs::write(out, text + &pins).unwrap();
    files.len()
}
