//! A headless Chromium driven over the Chrome DevTools Protocol, for the studio's browser tests.
//!
//! Why CDP over a WebSocket (tungstenite) rather than WebDriver or a Node driver: Debian's
//! `chromium` speaks CDP itself, so nothing else is installed (no chromedriver, no Node), and
//! the few commands the tests need (navigate, evaluate, type, click, screenshot) are plain JSON.
//! The browser runs with a fresh profile and is killed with the test.

use serde_json::{Value, json};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// How long one DevTools command may take before the test fails.
const CDP_PATIENCE: Duration = Duration::from_secs(120);

pub struct Browser {
    child: Child,
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    session: String,
    next_id: u64,
    _profile: tempfile::TempDir,
}

/// The browser, if this machine has one: `RESTAURO_CHROMIUM`, else `chromium` or
/// `chromium-browser` on the path.
pub fn chromium() -> Option<PathBuf> {
    if let Some(path) = std::env::var_os("RESTAURO_CHROMIUM") {
        return Some(PathBuf::from(path));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| ["chromium", "chromium-browser"].map(|name| dir.join(name)))
        .find(|candidate| candidate.is_file())
}

/// Whether a test that needs the browser should run: it fails when `RESTAURO_REQUIRE_BROWSER`
/// is set (CI installs Chromium and sets it) and there is none, and is skipped, saying so, on a
/// machine without a browser.
pub fn available(test: &str) -> bool {
    if chromium().is_some() {
        return true;
    }
    assert!(
        std::env::var_os("RESTAURO_REQUIRE_BROWSER").is_none(),
        "{test}: no Chromium found, and RESTAURO_REQUIRE_BROWSER is set; install it \
         (apt-get install chromium) or set RESTAURO_CHROMIUM to its path"
    );
    eprintln!("{test}: skipped: no Chromium on this machine (apt-get install chromium)");
    false
}

impl Browser {
    /// Starts headless Chromium with a `width × height` window and attaches to its page.
    pub fn launch(width: u32, height: u32) -> Browser {
        let exe = chromium().expect("a Chromium (see `available`)");
        let profile = tempfile::tempdir().unwrap();
        let child = Command::new(exe)
            .args([
                "--headless=new",
                "--no-sandbox",
                "--disable-gpu",
                // WebGL on the CPU (SwiftShader): the studio's 3D view, on a machine without GPU.
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--no-first-run",
                "--no-default-browser-check",
                // Nothing but the page under test: no update checks, sync or field trials, whose
                // connections a machine without a network refuses (and some wait on).
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-extensions",
                "--hide-scrollbars",
                "--remote-debugging-port=0",
                &format!("--window-size={width},{height}"),
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("starting Chromium");
        let (port, path) = devtools_address(profile.path());
        let (socket, _) =
            tungstenite::connect(format!("ws://127.0.0.1:{port}{path}")).expect("CDP socket");
        // A browser that stops answering fails the test instead of holding it for ever.
        if let MaybeTlsStream::Plain(stream) = socket.get_ref() {
            stream.set_read_timeout(Some(CDP_PATIENCE)).expect("a socket timeout");
        }
        let mut browser =
            Browser { child, socket, session: String::new(), next_id: 1, _profile: profile };
        let targets = browser.call("Target.getTargets", json!({}));
        let page = targets["targetInfos"]
            .as_array()
            .and_then(|t| t.iter().find(|t| t["type"] == "page"))
            .expect("a page target")["targetId"]
            .clone();
        let attached =
            browser.call("Target.attachToTarget", json!({ "targetId": page, "flatten": true }));
        browser.session = attached["sessionId"].as_str().unwrap().to_owned();
        browser.call("Page.enable", json!({}));
        browser.call("Runtime.enable", json!({}));
        browser
    }

    /// Sends a CDP command (to the page once attached) and waits for its answer, passing over
    /// the events that come between.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        self.socket.send(Message::text(message.to_string())).expect("sending to Chromium");
        loop {
            let reply = self.socket.read().unwrap_or_else(|e| {
                panic!("{method}: no answer from Chromium within {CDP_PATIENCE:?}: {e}")
            });
            let Message::Text(text) = reply else { continue };
            let value: Value = serde_json::from_str(&text).unwrap();
            if value["id"] == id {
                if let Some(error) = value.get("error") {
                    panic!("{method}: {error}");
                }
                return value["result"].clone();
            }
        }
    }

    pub fn goto(&mut self, url: &str) {
        self.call("Page.navigate", json!({ "url": url }));
        self.wait_for("the page to load", "document.readyState === 'complete'");
    }

    /// The value of a JavaScript expression in the page (promises awaited).
    pub fn eval(&mut self, expression: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }),
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("`{expression}` threw: {e}");
        }
        r["result"]["value"].clone()
    }

    /// Waits until `condition` (JavaScript) is true; fails naming `what` after 60 s.
    pub fn wait_for(&mut self, what: &str, condition: &str) {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            if self.eval(&format!("!!({condition})")) == json!(true) {
                return;
            }
            assert!(Instant::now() < deadline, "timed out waiting for {what} ({condition})");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Double-clicks the middle of the element `selector` with the mouse.
    pub fn double_click(&mut self, selector: &str) {
        let [x, y, w, h] = self.rect(selector);
        let (x, y) = (x + w / 2.0, y + h / 2.0);
        for count in [1, 2] {
            for kind in ["mousePressed", "mouseReleased"] {
                self.call(
                    "Input.dispatchMouseEvent",
                    json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": count }),
                );
            }
        }
    }

    /// Clicks the middle of the element `selector` with the mouse, as a person would.
    pub fn click(&mut self, selector: &str) {
        let quoted = serde_json::to_string(selector).unwrap();
        let at = self.eval(&format!(
            "(() => {{ const e = document.querySelector({quoted}); \
             e.scrollIntoView({{ block: 'center', inline: 'center' }}); \
             const r = e.getBoundingClientRect(); \
             return [r.x + r.width / 2, r.y + r.height / 2]; }})()"
        ));
        let (x, y) = (at[0].as_f64().unwrap(), at[1].as_f64().unwrap());
        for kind in ["mousePressed", "mouseReleased"] {
            self.call(
                "Input.dispatchMouseEvent",
                json!({ "type": kind, "x": x, "y": y, "button": "left", "clickCount": 1 }),
            );
        }
    }

    /// Types `text` into the focused element.
    pub fn type_text(&mut self, text: &str) {
        self.call("Input.insertText", json!({ "text": text }));
    }

    /// Chooses `file` in the file input `selector`, as a person picking it would (the page is
    /// sent its `change` event).
    pub fn choose_file(&mut self, selector: &str, file: &Path) {
        let root = self.call("DOM.getDocument", json!({}));
        let node = self.call(
            "DOM.querySelector",
            json!({ "nodeId": root["root"]["nodeId"], "selector": selector }),
        );
        self.call(
            "DOM.setFileInputFiles",
            json!({ "nodeId": node["nodeId"], "files": [file.to_str().unwrap()] }),
        );
    }

    /// Presses and releases a key (`"Enter"`, `"?"`, …).
    pub fn press(&mut self, key: &str) {
        let text = if key.chars().count() == 1 { key } else { "" };
        // The key's code, for what the browser itself does with a key (a dialog closes on
        // Escape's 27, a form is sent on Enter's 13).
        let code = match key {
            "Enter" => 13,
            "Escape" => 27,
            "Tab" => 9,
            _ => 0,
        };
        for kind in ["keyDown", "keyUp"] {
            let mut event = json!({ "type": kind, "key": key, "windowsVirtualKeyCode": code });
            if kind == "keyDown" && !text.is_empty() {
                event["text"] = json!(text);
            }
            if key == "Enter" && kind == "keyDown" {
                event["text"] = json!("\r");
            }
            self.call("Input.dispatchKeyEvent", event);
        }
    }

    /// Holds a key (`"ArrowUp"`, …) down for `time`, then lets it go.
    pub fn hold(&mut self, key: &str, time: Duration) {
        self.call("Input.dispatchKeyEvent", json!({ "type": "keyDown", "key": key, "code": key }));
        std::thread::sleep(time);
        self.call("Input.dispatchKeyEvent", json!({ "type": "keyUp", "key": key, "code": key }));
    }

    /// Holds a key down until what it drives has moved and stopped: until the JavaScript
    /// `expression`, once changed, gives the same value twice a second apart while the page
    /// drew at least 5 frames in between (`frames`, a JavaScript count of frames drawn: a
    /// loaded machine may draw none for a second), or `limit` has passed; then lets it go and
    /// returns that value. A walk is judged by where it ends, whatever the frame rate.
    pub fn hold_until_still(
        &mut self,
        key: &str,
        expression: &str,
        frames: &str,
        limit: Duration,
    ) -> Value {
        self.call("Input.dispatchKeyEvent", json!({ "type": "keyDown", "key": key, "code": key }));
        let deadline = Instant::now() + limit;
        let first = self.eval(expression);
        let count = |b: &mut Self| b.eval(frames).as_f64().unwrap_or(0.0);
        let (mut last, mut drawn) = (first.clone(), count(self));
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let (now, now_drawn) = (self.eval(expression), count(self));
            let still = now == last && now != first && now_drawn - drawn >= 5.0;
            if still || Instant::now() >= deadline {
                break;
            }
            (last, drawn) = (now, now_drawn);
        }
        self.call("Input.dispatchKeyEvent", json!({ "type": "keyUp", "key": key, "code": key }));
        self.eval(expression)
    }

    /// Writes what the page shows now to `path` as a PNG, and returns its bytes.
    pub fn screenshot(&mut self, path: &Path) -> Vec<u8> {
        use base64::Engine as _;
        let shot = self.call("Page.captureScreenshot", json!({ "format": "png" }));
        let data = base64::engine::general_purpose::STANDARD
            .decode(shot["data"].as_str().unwrap())
            .unwrap();
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, &data).unwrap();
        data
    }

    /// Makes the page's window exactly `width × height` CSS pixels (at one device pixel each)
    /// and waits until the page has taken the size.
    pub fn window_size(&mut self, width: u32, height: u32) {
        self.call(
            "Emulation.setDeviceMetricsOverride",
            json!({ "width": width, "height": height, "deviceScaleFactor": 1, "mobile": false }),
        );
        self.wait_for(
            "the window's size",
            &format!("innerWidth === {width} && innerHeight === {height}"),
        );
    }

    /// A picture for the README and the guides, at 1920 × 1080: written to the folder `shots`
    /// and, when `RESTAURO_UPDATE_DOCS` is set, to `docs/images/<name>` too, so the pictures
    /// are remade by the tests that check what they show. The window keeps the size.
    pub fn docs_picture(&mut self, shots: &Path, name: &str) -> Vec<u8> {
        self.window_size(1920, 1080);
        // Two frames, for the page to lay itself out and draw at the new size.
        self.eval(
            "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(true))))",
        );
        let shot = self.screenshot(&shots.join(name));
        if std::env::var_os("RESTAURO_UPDATE_DOCS").is_some() {
            let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/images").join(name);
            std::fs::write(&docs, &shot).unwrap_or_else(|e| panic!("{}: {e}", docs.display()));
        }
        shot
    }

    /// The error the page shows beside the row of controls (or the form) that `button` (a
    /// selector) is in, where the studio shows the refusal of an action taken there, once it
    /// shows.
    pub fn refusal_beside(&mut self, button: &str) -> String {
        let quoted = serde_json::to_string(button).unwrap();
        let shown = format!(
            "(() => {{ const host = document.querySelector({quoted}) \
               .closest('.actions, form, .fields, .choices, .overlay-head, .panel-body, dialog'); \
               const p = host && host.nextElementSibling; \
               return p && p.classList.contains('action-problem') && p.checkVisibility() ? p.textContent : ''; }})()"
        );
        self.wait_for("the refusal beside the button", &format!("{shown} !== ''"));
        self.eval(&shown).as_str().unwrap().to_owned()
    }

    /// The page-pixel rectangle (x, y, width, height) of the element `selector`.
    pub fn rect(&mut self, selector: &str) -> [f64; 4] {
        let quoted = serde_json::to_string(selector).unwrap();
        let r = self.eval(&format!(
            "(() => {{ const r = document.querySelector({quoted}).getBoundingClientRect(); \
             return [r.x, r.y, r.width, r.height]; }})()"
        ));
        std::array::from_fn(|k| r[k].as_f64().unwrap())
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The port and browser path Chromium writes into its profile once it listens.
fn devtools_address(profile: &Path) -> (u16, String) {
    let file = profile.join("DevToolsActivePort");
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Ok(text) = std::fs::read_to_string(&file) {
            let mut lines = text.lines();
            if let (Some(port), Some(path)) = (lines.next(), lines.next())
                && let Ok(port) = port.trim().parse()
            {
                return (port, path.trim().to_owned());
            }
        }
        assert!(Instant::now() < deadline, "Chromium did not open its DevTools port");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A PNG's pixels as RGB, row by row, and its width.
pub fn png_rgb(bytes: &[u8]) -> (Vec<[u8; 3]>, usize) {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut data = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut data).unwrap();
    let channels = info.color_type.samples();
    let pixels = (info.width * info.height) as usize;
    let rgb = data[..pixels * channels].chunks(channels).map(|p| [p[0], p[1], p[2]]).collect();
    (rgb, info.width as usize)
}

/// A PNG of `width` × `height` pixels all of the colour `rgb` (8-bit sRGB): a photograph to
/// attach to a note, whose colour a test can look for in the page.
pub fn solid_png(width: u32, height: u32, rgb: [u8; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&rgb.repeat((width * height) as usize)).unwrap();
    writer.finish().unwrap();
    out
}
