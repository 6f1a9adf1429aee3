//! The studio's HTTP API against a real coordinator and worker (processes on loopback): every
//! route, every refusal, the session cookie, the live events and their resumption.

use restauro_tests::http::{Events, request};
use restauro_tests::{
    CLIENT_TOKEN, Coordinator, WORKER_TOKEN, Worker, aosta_scene, client, submit, text,
};

const BEARER: &str = "Bearer client-token-for-tests";

fn get(studio: &str, path: &str, auth: &[(&str, &str)]) -> restauro_tests::http::Response {
    request(studio, "GET", path, auth, b"")
}

fn error_of(r: &restauro_tests::http::Response) -> String {
    r.json()["error"].as_str().unwrap_or_else(|| panic!("no error in {}", r.text())).to_owned()
}

#[test]
fn every_route_needs_the_client_token_and_refuses_in_the_servers_words() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let c =
        Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &["--studio-listen", "127.0.0.1:0"]);
    let studio = c.studio.clone().unwrap();
    let s = studio.as_str();

    // The page itself is public, with a policy that runs only its own scripts.
    let page = get(s, "/", &[]);
    assert_eq!(page.status, 200);
    assert!(page.text().contains("<title>restauro studio</title>"));
    assert!(page.header("content-security-policy").unwrap().contains("script-src 'self'"));
    let js = get(s, "/static/studio.js", &[]);
    assert_eq!(
        (js.status, js.header("content-type")),
        (200, Some("text/javascript; charset=utf-8"))
    );
    let missing = get(s, "/static/nothing.js", &[]);
    assert_eq!(missing.status, 404);
    assert!(error_of(&missing).contains("/static/nothing.js"));
    assert_eq!(get(s, "/nowhere", &[]).status, 404);

    // Every API route: 401 without a token, 403 with the worker's, 401 with a guess.
    let id = "6f0a4f7e-1111-4a2b-9c3d-0123456789ab";
    let routes = [
        ("GET", "/api/whoami".to_owned()),
        ("GET", "/api/jobs".to_owned()),
        ("GET", format!("/api/jobs/{id}")),
        ("POST", format!("/api/jobs/{id}/cancel")),
        ("GET", format!("/api/jobs/{id}/results/a.png")),
        ("GET", "/api/workers".to_owned()),
        ("GET", "/api/events".to_owned()),
        ("GET", "/api/scenes".to_owned()),
        ("POST", "/api/scenes?name=x".to_owned()),
        ("GET", format!("/api/scenes/{}", "0".repeat(64))),
        ("GET", format!("/api/scenes/{}/preview.glb", "0".repeat(64))),
        ("POST", format!("/api/scenes/{}/snapshots", "0".repeat(64))),
        ("POST", format!("/api/scenes/{}/edits", "0".repeat(64))),
        ("POST", format!("/api/scenes/{}/revert", "0".repeat(64))),
        ("GET", format!("/api/scenes/{}/revisions", "0".repeat(64))),
        ("GET", format!("/api/scenes/{}/scene.json", "0".repeat(64))),
        ("GET", format!("/api/scenes/{}/download", "0".repeat(64))),
        ("GET", "/api/spectra".to_owned()),
        ("GET", "/api/sun-path".to_owned()),
        ("POST", format!("/api/scenes/{}/photometry?name=a.ies", "0".repeat(64))),
        ("POST", format!("/api/scenes/{}/spectrum?name=a.csv", "0".repeat(64))),
        ("POST", format!("/api/scenes/{}/images?name=a.png", "0".repeat(64))),
        ("GET", format!("/api/images/blake3:{}.png", "0".repeat(64))),
        ("GET", format!("/api/jobs/{id}/painting.png")),
        ("GET", format!("/api/jobs/{id}/display.png")),
        ("GET", format!("/api/jobs/{id}/luminance")),
        ("GET", format!("/api/jobs/{id}/luminance.png")),
        ("GET", format!("/api/compare?a={id}&b={id}")),
        ("GET", format!("/api/compare/delta-e.png?a={id}&b={id}")),
        ("POST", format!("/api/scenes/{}/sequences", "0".repeat(64))),
        ("GET", format!("/api/jobs/{id}/frames")),
    ];
    let worker = format!("Bearer {WORKER_TOKEN}");
    for (method, path) in &routes {
        let r = request(s, method, path, &[], b"");
        assert_eq!(r.status, 401, "{method} {path}");
        assert!(error_of(&r).contains("not signed in"), "{method} {path}");
        let r = request(s, method, path, &[("Authorization", &worker)], b"");
        assert_eq!(r.status, 403, "{method} {path}");
        assert!(error_of(&r).contains("this is a worker token"), "{}", error_of(&r));
        let r = request(s, method, path, &[("Authorization", "Bearer guess")], b"");
        assert_eq!(r.status, 401, "{method} {path}");
        assert!(error_of(&r).contains("not valid"), "{}", error_of(&r));
    }

    // With the client token: what the domain says, as the gRPC door says it.
    let auth = [("Authorization", BEARER)];
    assert_eq!(get(s, "/api/whoami", &auth).json()["role"], "client");
    assert_eq!(get(s, "/api/jobs", &auth).json(), serde_json::json!([]));
    let r = get(s, "/api/jobs/not-a-job", &auth);
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("`not-a-job` is not a job id"), "{}", error_of(&r));
    let r = get(s, &format!("/api/jobs/{id}"), &auth);
    assert_eq!((r.status, error_of(&r)), (404, format!("no job {id}")));
    let r = request(s, "POST", &format!("/api/jobs/{id}/cancel"), &auth, b"");
    assert_eq!(r.status, 404);
    assert_eq!(get(s, &format!("/api/jobs/{id}/results/a.png"), &auth).status, 404);
    let r = get(s, &format!("/api/jobs/{id}/painting.png"), &auth);
    assert_eq!((r.status, error_of(&r)), (404, format!("no job {id}")));
    assert_eq!(request(s, "DELETE", "/api/jobs", &auth, b"").status, 405);
    assert_eq!(get(s, "/api/scenes", &auth).json(), serde_json::json!([]));
    let r = get(s, "/api/scenes/../../etc", &auth);
    assert_eq!(r.status, 404, "{}", r.text());
    let r = get(s, "/api/scenes/not-a-scene", &auth);
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("is not a scene id"), "{}", error_of(&r));
    let r = get(s, &format!("/api/scenes/{}", "0".repeat(64)), &auth);
    assert_eq!(r.status, 404);
    assert!(error_of(&r).contains("the coordinator holds the scenes of its jobs"));
}

#[test]
fn the_session_cookie_is_made_from_the_client_token_only_and_guards_changes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let c =
        Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &["--studio-listen", "127.0.0.1:0"]);
    let s = c.studio.clone().unwrap();
    let origin = format!("http://{s}");
    let sign_in = |token: &str, origin: &str| {
        let body = serde_json::json!({ "token": token }).to_string();
        request(&s, "POST", "/api/session", &[("Origin", origin)], body.as_bytes())
    };
    let r = sign_in(WORKER_TOKEN, &origin);
    assert_eq!(r.status, 403, "the worker token opens nothing here");
    assert_eq!(sign_in("guess", &origin).status, 401);
    let r = sign_in(CLIENT_TOKEN, "http://evil.example");
    assert_eq!(r.status, 403);
    assert!(error_of(&r).contains("http://evil.example"), "{}", error_of(&r));
    let r = request(&s, "POST", "/api/session", &[("Origin", &origin)], b"{\"tokn\": 1}");
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("{\"token\": \"<client token>\"}"), "{}", error_of(&r));

    let r = sign_in(CLIENT_TOKEN, &origin);
    assert_eq!(r.status, 204);
    let set = r.header("set-cookie").unwrap().to_owned();
    for attribute in ["HttpOnly", "SameSite=Strict", "Path=/"] {
        assert!(set.contains(attribute), "{set}");
    }
    let cookie = set.split(';').next().unwrap().to_owned();
    assert_eq!(get(&s, "/api/whoami", &[("Cookie", &cookie)]).status, 200);
    // A change by cookie needs the studio's own Origin; reading does not.
    let job = "6f0a4f7e-1111-4a2b-9c3d-0123456789ab";
    let cancel = format!("/api/jobs/{job}/cancel");
    let r = request(&s, "POST", &cancel, &[("Cookie", &cookie)], b"");
    assert_eq!(r.status, 403, "{}", r.text());
    let r = request(
        &s,
        "POST",
        &cancel,
        &[("Cookie", &cookie), ("Origin", "http://evil.example")],
        b"",
    );
    assert_eq!(r.status, 403);
    let r = request(&s, "POST", &cancel, &[("Cookie", &cookie), ("Origin", &origin)], b"");
    assert_eq!(r.status, 404, "past the gate, to the domain: {}", r.text());
    // A tampered cookie is no session; signing out clears it.
    // (Its last hex digit changed: to 1 where it was 0, else to 0.)
    let last = if cookie.ends_with('0') { '1' } else { '0' };
    let forged = format!("{}{last}", &cookie[..cookie.len() - 1]);
    assert_eq!(get(&s, "/api/whoami", &[("Cookie", &forged)]).status, 401);
    let out = request(&s, "DELETE", "/api/session", &[], b"");
    assert!(out.header("set-cookie").unwrap().contains("Max-Age=0"));
}

#[test]
fn events_follow_a_job_to_its_end_and_resume_after_the_last_event_seen() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let c =
        Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &["--studio-listen", "127.0.0.1:0"]);
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let mut events = Events::open(&s, "/api/events", &auth);
    assert_eq!(events.status, 200);
    let first = events.next_event();
    assert_eq!(first.kind, "snapshot");
    assert_eq!(first.json()["jobs"], serde_json::json!([]));

    let _worker = Worker::start(d, &c.url, "w1", &[]);
    let w = events.next_event();
    assert_eq!(w.kind, "worker");
    assert_eq!(w.json()["name"], "w1");

    let scene = aosta_scene(d, 64, 36);
    let token = d.join("client.token");
    let id = submit(&scene, &["--spp", "1", "--tile", "16"], &c.url, &token);
    let (last, seen) = follow_the_job_to_its_end(&mut events, &id);
    results_are_the_files_the_cli_fetches(&c, d, &token, &id, &last);
    let (scene_id, view) = the_scene_is_viewed_as_restauro_colours_it(&s);
    snapshots_are_checked_as_a_submission_is(&s, &scene_id, &view);
    reconnecting_resumes_after_the_event_seen(&s, &seen, &id);

    // Cancelling: a job too large to finish first.
    let long = submit(&scene, &["--spp", "4096", "--tile", "8"], &c.url, &token);
    let r = request(&s, "POST", &format!("/api/jobs/{long}/cancel"), &auth, b"");
    assert_eq!((r.status, r.json()["state"].as_str()), (200, Some("cancelled")));
    let r = get(&s, &format!("/api/jobs/{long}/results/aosta.png"), &auth);
    assert_eq!(r.status, 409, "{}", r.text());
    assert!(error_of(&r).contains("is cancelled, not done"), "{}", error_of(&r));
}

/// Job events until job `id` is done; the tiles done never go back. The last job event's JSON,
/// and every event seen.
fn follow_the_job_to_its_end(
    events: &mut Events,
    id: &str,
) -> (serde_json::Value, Vec<restauro_tests::http::Event>) {
    let (mut done_seen, mut seen) = (0, Vec::new());
    let last = loop {
        let e = events.next_event();
        seen.push(e.clone());
        if e.kind != "job" {
            continue;
        }
        let j = e.json();
        assert_eq!(j["id"], id);
        let done = j["tiles_done"].as_u64().unwrap();
        assert!(done >= done_seen, "tiles done went from {done_seen} to {done}");
        done_seen = done;
        if j["state"] == "done" {
            break j;
        }
    };
    assert_eq!(last["tiles_total"], 12, "64 × 36 px in 16-px tiles");
    assert!(seen.iter().filter(|e| e.kind == "job").count() >= 2, "{seen:?}");
    (last, seen)
}

/// The result of job `id` as the studio gives it is the file the CLI fetches; a result the job
/// has not is refused.
fn results_are_the_files_the_cli_fetches(
    c: &Coordinator,
    d: &std::path::Path,
    token: &std::path::Path,
    id: &str,
    last: &serde_json::Value,
) {
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let png = last["results"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n.as_str().unwrap().ends_with("aosta.png"))
        .unwrap()
        .as_str()
        .unwrap()
        .to_owned();
    let r = get(&s, &format!("/api/jobs/{id}/results/{png}"), &auth);
    assert_eq!((r.status, r.header("content-type")), (200, Some("image/png")));
    let out = d.join("fetched");
    let o = client(&["fetch", id, "--out", out.to_str().unwrap()], &c.url, token);
    assert!(o.status.success(), "{}", text(&o));
    assert!(r.body == std::fs::read(out.join(&png)).unwrap(), "the studio's PNG differs");
    let exr = get(&s, &format!("/api/jobs/{id}/results/aosta.exr"), &auth);
    assert!(exr.header("content-disposition").unwrap().contains("attachment"));
    let r = get(&s, &format!("/api/jobs/{id}/results/secret.txt"), &auth);
    assert_eq!(r.status, 404);
    assert!(error_of(&r).contains("has no result `secret.txt`"));
    assert_eq!(get(&s, &format!("/api/jobs/{id}"), &auth).json()["state"], "done");
}

/// The job's scene, for the real-time view: its camera, its materials coloured from their
/// spectra as `restauro color` computes them, and its geometry as GLB. The scene's id and view.
fn the_scene_is_viewed_as_restauro_colours_it(s: &str) -> (String, serde_json::Value) {
    let auth = [("Authorization", BEARER)];
    let scenes = get(s, "/api/scenes", &auth).json();
    assert_eq!(scenes.as_array().unwrap().len(), 1, "{scenes}");
    assert_eq!((scenes[0]["name"].as_str(), scenes[0]["jobs"].as_u64()), (Some("aosta"), Some(1)));
    let scene_id = scenes[0]["id"].as_str().unwrap().to_owned();
    let view = get(s, &format!("/api/scenes/{scene_id}"), &auth).json();
    assert!(view["triangles"].as_u64().unwrap() > 1000, "{}", view["triangles"]);
    assert_eq!(view["camera"]["width"], 64);
    let travertine =
        view["materials"].as_array().unwrap().iter().find(|m| m["name"] == "travertine").unwrap();
    let o = restauro_tests::restauro(&["color", "travertine_tufa_solid__eco_ward73", "--json"]);
    let color: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in 0..3 {
        let (got, want) = (
            travertine["colour_linear_srgb"][k].as_f64().unwrap(),
            color["sample"]["rgb_linear"][k].as_f64().unwrap(),
        );
        assert!((got - want).abs() < 1e-4, "channel {k}: {got} vs {want}");
    }
    let glb = get(s, &format!("/api/scenes/{scene_id}/preview.glb"), &auth);
    assert_eq!((glb.status, glb.header("content-type")), (200, Some("model/gltf-binary")));
    assert_eq!(&glb.body[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(glb.body[8..12].try_into().unwrap()) as usize, glb.body.len());
    (scene_id, view)
}

/// Snapshots: checked as a submission is, refused in the same words; one accepted is a second
/// job of the same scene.
fn snapshots_are_checked_as_a_submission_is(s: &str, scene_id: &str, view: &serde_json::Value) {
    let auth = [("Authorization", BEARER)];
    let snapshot = |patch: serde_json::Value| {
        let mut body = serde_json::json!({
            "camera": {
                "position": view["camera"]["position"], "target": view["camera"]["target"],
                "up": view["camera"]["up"], "vertical_fov_deg": view["camera"]["vertical_fov_deg"]
            },
            "render": {
                "width": 32, "height": 18,
                "samples_per_pixel": 1, "integrator": "whitted", "variant": "cleaned"
            }
        });
        for (k, v) in patch.as_object().unwrap() {
            match k.strip_prefix("render.") {
                Some(option) => body["render"][option] = v.clone(),
                None => body[k] = v.clone(),
            }
        }
        body["render"].as_object_mut().unwrap().retain(|_, v| !v.is_null());
        let path = format!("/api/scenes/{scene_id}/snapshots");
        request(s, "POST", &path, &auth, body.to_string().as_bytes())
    };
    for (patch, words) in [
        (
            serde_json::json!({ "render.integrator": "raymarch" }),
            "render.integrator: unknown variant `raymarch`, expected `whitted` or `path`",
        ),
        (serde_json::json!({ "render.variant": "restored" }), "restored"),
        (
            serde_json::json!({ "render.samples_per_pixel": 0 }),
            "render.samples_per_pixel: 0; use at least 1",
        ),
        (serde_json::json!({ "colour": "red" }), "unknown field `colour`"),
        (serde_json::json!({ "render.colour": "red" }), "render.colour: unknown field `colour`"),
        (serde_json::json!({ "render.width": -3 }), "render.width"),
        (
            serde_json::json!({ "render.noise_target": 0.9 }),
            "render.noise_target: 0.9 is not a noise target",
        ),
    ] {
        let r = snapshot(patch.clone());
        assert_eq!(r.status, 400, "{patch}: {}", r.text());
        assert!(error_of(&r).contains(words), "{patch}: {}", error_of(&r));
    }
    let r = snapshot(serde_json::json!({}));
    assert_eq!(r.status, 200, "{}", r.text());
    let job = r.json();
    assert_eq!((job["name"].as_str(), job["width"].as_u64()), (Some("aosta-cleaned"), Some(32)));
    // The snapshot's scene differs only by its camera: still one scene, with two jobs.
    let scenes = get(s, "/api/scenes", &auth).json();
    assert_eq!((scenes[0]["id"].as_str(), scenes[0]["jobs"].as_u64()), (Some(scene_id), Some(2)));
}

/// Reconnecting after an event: what came after it, not a snapshot. With an id of another
/// coordinator's run (or none): a snapshot, with job `id` done.
fn reconnecting_resumes_after_the_event_seen(
    s: &str,
    seen: &[restauro_tests::http::Event],
    id: &str,
) {
    let auth = [("Authorization", BEARER)];
    let middle = &seen[0];
    let mut resumed = Events::open(s, "/api/events", &[auth[0], ("Last-Event-ID", &middle.id)]);
    let next = resumed.next_event();
    assert_eq!(
        (next.kind.as_str(), next.id.as_str()),
        (seen[1].kind.as_str(), seen[1].id.as_str())
    );
    let mut fresh = Events::open(s, "/api/events", &[auth[0], ("Last-Event-ID", "0123456789ab-3")]);
    let snap = fresh.next_event();
    assert_eq!(snap.kind, "snapshot");
    let jobs = snap.json()["jobs"].clone();
    let first = jobs.as_array().unwrap().iter().find(|j| j["id"] == id).unwrap();
    assert_eq!(first["state"], "done", "{jobs}");
}

/// `restauro studio` starts an embedded cluster whose coordinator serves the studio, and prints
/// an address whose fragment carries a token that opens it.
#[test]
fn restauro_studio_prints_an_address_that_signs_in() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let scene = aosta_scene(dir.path(), 64, 36);
    let mut child = std::process::Command::new(restauro_tests::binary("restauro"))
        .args(["studio", &scene, "--listen", "127.0.0.1:0", "--exit-with-stdin"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let url = line.trim().strip_prefix("studio on http://").unwrap_or_else(|| panic!("{line}"));
    let (addr, token) = url.split_once("/#token=").unwrap();
    let mut rest = String::new();
    out.read_line(&mut rest).unwrap();
    out.read_line(&mut rest).unwrap();
    assert!(rest.contains("restauro submit --coordinator http://127.0.0.1:"), "{rest}");
    out.read_line(&mut rest).unwrap();
    out.read_line(&mut rest).unwrap();
    assert!(rest.contains(&format!("opened {scene} (its preview render is job ")), "{rest}");
    assert_eq!(get(addr, "/", &[]).status, 200);
    let bearer = format!("Bearer {token}");
    restauro_tests::wait_for("both workers", std::time::Duration::from_secs(30), || {
        get(addr, "/api/workers", &[("Authorization", &bearer)]).json().as_array().map(Vec::len)
            == Some(2)
    });
    // The scene it was given is the studio's.
    let scenes = get(addr, "/api/scenes", &[("Authorization", &bearer)]).json();
    assert_eq!(scenes[0]["name"], "aosta", "{scenes}");
    drop(child.stdin.take());
    let status = child.wait().unwrap();
    assert!(status.success(), "{status}");
}

/// The linear-sRGB colour `restauro color` computes for a shipped spectrum under D65.
fn colour_of(spectrum: &str) -> [f64; 3] {
    let o = restauro_tests::restauro(&["color", spectrum, "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let color: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    std::array::from_fn(|k| color["sample"]["rgb_linear"][k].as_f64().unwrap())
}

fn material<'a>(view: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    view["materials"].as_array().unwrap().iter().find(|m| m["name"] == name).unwrap()
}

/// Sends `body` as an edit of scene `id` to the studio at `s`.
fn edit_scene(s: &str, id: &str, body: &serde_json::Value) -> restauro_tests::http::Response {
    let auth = [("Authorization", BEARER)];
    request(s, "POST", &format!("/api/scenes/{id}/edits"), &auth, body.to_string().as_bytes())
}

/// Edits from the page make revisions of the scene: each checked as a scene file is (the same
/// messages), refused edits leave no revision, earlier revisions stay readable and can be made
/// the latest again, and every revision survives a restart of the coordinator.
#[test]
fn edits_make_revisions_checked_as_scene_files_and_kept_across_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = d.join("data");
    let c = Coordinator::start(d, &data, "127.0.0.1:0", &["--studio-listen", "127.0.0.1:0"]);
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let scene = aosta_scene(d, 64, 36);
    let token = d.join("client.token");
    submit(&scene, &["--spp", "1", "--tile", "32"], &c.url, &token);
    let id = get(&s, "/api/scenes", &auth).json()[0]["id"].as_str().unwrap().to_owned();
    let first = get(&s, &format!("/api/scenes/{id}"), &auth).json();
    assert_eq!(first["revision"], 0);

    let other = "travertine_particulate_fine__eco_travertine1";
    let old = another_travertine_is_coloured_as_restauro_colours_it(&s, &id, &first, other);
    refused_edits_make_no_revision(&s, &id);
    let v2 = the_sun_after_sunset_is_on_its_days_path(&s, &id);
    a_saved_view_is_kept_in_the_worlds_frame(&s, &id, &v2);
    earlier_revisions_stay_and_one_is_made_the_latest(&s, &id, &old, other);
    a_snapshot_of_revision_1_belongs_to_the_same_scene(&s, &id, &first);

    // Restarted on the same store: every revision is there.
    let addr = c.url.strip_prefix("http://").unwrap().to_owned();
    drop(c);
    let c = Coordinator::start(d, &data, &addr, &["--studio-listen", "127.0.0.1:0"]);
    let s = c.studio.clone().unwrap();
    let list = get(&s, &format!("/api/scenes/{id}/revisions"), &auth).json();
    assert_eq!(list.as_array().unwrap().len(), 5, "{list}");
    let v1 = get(&s, &format!("/api/scenes/{id}?revision=1"), &auth).json();
    assert_eq!(material(&v1, "travertine")["states"][0]["spectrum"], other);
    a_note_is_kept_in_the_worlds_frame_its_links_checked(&s, &id);
    revisions_download_as_scene_folders(&s, &id, other);
}

/// Another shipped travertine (`other`) for the stone: its colour is restauro's own for that
/// spectrum, and no longer that of revision 0 (`first`). The colour the stone had.
fn another_travertine_is_coloured_as_restauro_colours_it(
    s: &str,
    id: &str,
    first: &serde_json::Value,
    other: &str,
) -> serde_json::Value {
    let r = edit_scene(
        s,
        id,
        &serde_json::json!({"edit": "material", "material": "travertine", "spectrum": other}),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let v1 = r.json();
    assert_eq!(v1["revision"], 1);
    let stone = material(&v1, "travertine");
    assert_eq!(stone["states"][0]["spectrum"], other, "{stone}");
    // `restauro color` integrates the measurement at its own resolution, the preview the
    // 5-nm grid the renderer uses: they agree to a few parts in 10⁴.
    let want = colour_of(other);
    for (k, want) in want.iter().enumerate() {
        let got = stone["colour_linear_srgb"][k].as_f64().unwrap();
        assert!((got - want).abs() < 1e-3, "channel {k}: {got} vs {want}");
    }
    let old = material(first, "travertine")["colour_linear_srgb"].clone();
    assert_ne!(stone["colour_linear_srgb"], old, "the preview's colour changed");
    old
}

/// Refusals, in the words `scene check` uses; none makes a revision.
fn refused_edits_make_no_revision(s: &str, id: &str) {
    let auth = [("Authorization", BEARER)];
    for (body, status, words) in [
        (
            serde_json::json!({"edit": "material", "material": "travertin", "roughness": 0.2}),
            400,
            "did you mean `travertine`",
        ),
        (
            serde_json::json!({"edit": "material", "material": "travertine", "spectrum": "travertine_tufa"}),
            400,
            "travertine_tufa_solid__eco_ward73",
        ),
        (
            serde_json::json!({"edit": "material", "material": "travertine", "model": "cook-torrance", "roughness": 7.0}),
            400,
            "roughness",
        ),
        (
            serde_json::json!({"edit": "sun", "latitude_deg": 45.7, "longitude_deg": 7.3, "datetime": "21/12/2026 17:00"}),
            400,
            "RFC 3339",
        ),
        (
            serde_json::json!({"edit": "paint", "colour": "red"}),
            400,
            "unknown kind `paint`; use material, sun, save-view, delete-view, save-annotation, delete-annotation, save-variant, rename-variant, delete-variant, save-light, delete-light",
        ),
        (serde_json::json!({"edit": "delete-view", "name": "portal"}), 400, "view"),
        (serde_json::json!({"edit": "sun", "latitude_deg": "north"}), 400, "latitude_deg"),
    ] {
        let r = edit_scene(s, id, &body);
        assert_eq!(r.status, status, "{body}: {}", r.text());
        assert!(error_of(&r).contains(words), "{body}: {}", error_of(&r));
    }
    let r = request(s, "POST", &format!("/api/scenes/{}/edits", "0".repeat(64)), &auth, b"{}");
    assert_eq!(r.status, 400, "{}", r.text());
    let r = request(
        s,
        "POST",
        &format!("/api/scenes/{}/edits", "0".repeat(64)),
        &auth,
        br#"{"edit": "delete-view", "name": "x"}"#,
    );
    assert_eq!(r.status, 404, "{}", r.text());
    assert_eq!(
        get(s, &format!("/api/scenes/{id}/revisions"), &auth).json().as_array().unwrap().len(),
        2
    );
}

/// The sun at 17:00 on 21 December at the theatre: after sunset. Its path that day peaks
/// at the solstice's noon altitude, 90° − 45.74° − 23.44° = 20.8° (plus refraction). The view
/// of revision 2.
fn the_sun_after_sunset_is_on_its_days_path(s: &str, id: &str) -> serde_json::Value {
    let auth = [("Authorization", BEARER)];
    let r = edit_scene(
        s,
        id,
        &serde_json::json!({"edit": "sun", "latitude_deg": 45.7371, "longitude_deg": 7.3228,
        "datetime": "2026-12-21T17:00:00+01:00"}),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let v2 = r.json();
    let sun = &v2["sun"];
    assert_eq!(sun["site"]["datetime"], "2026-12-21T17:00:00+01:00");
    let path = get(
        s,
        "/api/sun-path?latitude_deg=45.7371&longitude_deg=7.3228&date=2026-12-21&utc_offset=%2B01:00",
        &auth,
    );
    assert_eq!(path.status, 200, "{}", path.text());
    let path = path.json();
    let points = path.as_array().unwrap();
    assert_eq!(points.len(), 96);
    let at_five = points.iter().find(|p| p["time"] == "17:00").unwrap();
    assert!(
        (at_five["elevation_deg"].as_f64().unwrap() - sun["elevation_deg"].as_f64().unwrap()).abs()
            < 1e-9
    );
    assert!(sun["elevation_deg"].as_f64().unwrap() < 0.0, "{sun}");
    let highest =
        points.iter().map(|p| p["elevation_deg"].as_f64().unwrap()).fold(f64::MIN, f64::max);
    assert!((highest - 20.8).abs() < 0.3, "noon altitude {highest}");
    let r = get(
        s,
        "/api/sun-path?latitude_deg=100&longitude_deg=7&date=2026-12-21&utc_offset=%2B01:00",
        &auth,
    );
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("latitude_deg"), "{}", error_of(&r));
    v2
}

/// A view saved in the preview's frame (Y up, offset removed; `v2` gives the offset) is kept
/// in the world's.
fn a_saved_view_is_kept_in_the_worlds_frame(s: &str, id: &str, v2: &serde_json::Value) {
    let auth = [("Authorization", BEARER)];
    let offset: Vec<f64> = serde_json::from_value(v2["offset_m"].clone()).unwrap();
    let r = edit_scene(
        s,
        id,
        &serde_json::json!({"edit": "save-view", "view": {"name": "portal",
        "position": [1.0, 1.6, 8.0], "target": [1.0, 3.0, 0.0], "up": [0.0, 1.0, 0.0]}}),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let shown = r.json()["views"][0]["position"].clone();
    for (k, want) in [1.0, 1.6, 8.0].iter().enumerate() {
        assert!((shown[k].as_f64().unwrap() - want).abs() < 1e-9, "{shown}");
    }
    let manifest = get(s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    let kept = &manifest["views"][0];
    let want = [1.0 + offset[0], -8.0 + offset[1], 1.6 + offset[2]];
    for (k, want) in want.iter().enumerate() {
        assert!((kept["position"][k].as_f64().unwrap() - want).abs() < 1e-9, "{kept}");
    }
    assert_eq!(kept["up"], serde_json::json!([0.0, 0.0, 1.0]));
}

/// Earlier revisions stay as they were (revision 0's stone coloured `old`); one is made the
/// latest again as a new revision, and the summaries say so (the first naming `other`).
fn earlier_revisions_stay_and_one_is_made_the_latest(
    s: &str,
    id: &str,
    old: &serde_json::Value,
    other: &str,
) {
    let auth = [("Authorization", BEARER)];
    let zero = get(s, &format!("/api/scenes/{id}?revision=0"), &auth).json();
    assert_eq!(&material(&zero, "travertine")["colour_linear_srgb"], old);
    let r = get(s, &format!("/api/scenes/{id}?revision=9"), &auth);
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("has no revision 9; its latest is 3"), "{}", error_of(&r));
    let r = get(s, &format!("/api/scenes/{id}?revision=last"), &auth);
    assert!(error_of(&r).contains("`last` is not a revision number"), "{}", error_of(&r));
    let r = request(s, "POST", &format!("/api/scenes/{id}/revert"), &auth, br#"{"revision": 0}"#);
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["revision"], 4);
    let at = |n: u32| get(s, &format!("/api/scenes/{id}/scene.json?revision={n}"), &auth).text();
    assert_eq!(at(4), at(0), "revision 4 is revision 0 again");
    let summaries: Vec<String> = get(s, &format!("/api/scenes/{id}/revisions"), &auth)
        .json()
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["summary"].as_str().unwrap().to_owned())
        .collect();
    assert_eq!(summaries.len(), 5, "{summaries:?}");
    assert!(
        summaries[1].contains(other) && summaries[4].contains("back to revision 0"),
        "{summaries:?}"
    );
}

/// A snapshot of revision 1, from revision 0's (`first`) camera, belongs to the same scene.
fn a_snapshot_of_revision_1_belongs_to_the_same_scene(
    s: &str,
    id: &str,
    first: &serde_json::Value,
) {
    let auth = [("Authorization", BEARER)];
    let camera = &first["camera"];
    let body = serde_json::json!({
        "camera": {"position": camera["position"], "target": camera["target"], "up": camera["up"],
            "vertical_fov_deg": camera["vertical_fov_deg"]},
        "render": {"width": 16, "height": 9, "samples_per_pixel": 1, "integrator": "whitted"},
        "revision": 1
    });
    let r = request(
        s,
        "POST",
        &format!("/api/scenes/{id}/snapshots"),
        &auth,
        body.to_string().as_bytes(),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let scenes = get(s, "/api/scenes", &auth).json();
    assert_eq!(scenes.as_array().unwrap().len(), 1, "{scenes}");
    assert_eq!((scenes[0]["jobs"].as_u64(), scenes[0]["revision"].as_u64()), (Some(2), Some(4)));
}

/// A note pinned in the preview's frame is kept in the world's, its links checked; a note
/// deleted by a title misspelt is refused with the title meant.
fn a_note_is_kept_in_the_worlds_frame_its_links_checked(s: &str, id: &str) {
    let auth = [("Authorization", BEARER)];
    let note = |links: serde_json::Value| {
        let body = serde_json::json!({"edit": "save-annotation", "annotation": {
            "title": "crack", "text": "2 mm", "position": [1.0, 2.0, 3.0], "part": "facade/travertine",
            "links": links, "pose": {"position": [1.0, 1.6, 9.0], "target": [1.0, 2.0, 3.0], "up": [0.0, 1.0, 0.0]}}});
        edit_scene(s, id, &body)
    };
    let r = note(serde_json::json!(["javascript:alert(1)"]));
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(error_of(&r).contains("annotations[0].links[0]"), "{}", error_of(&r));
    let r = note(serde_json::json!(["https://example.org/a.pdf"]));
    assert_eq!((r.status, r.json()["revision"].as_u64()), (200, Some(5)), "{}", r.text());
    let manifest = get(s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    let kept = &manifest["annotations"][0];
    let offset: Vec<f64> = serde_json::from_value(r.json()["offset_m"].clone()).unwrap();
    let want = [1.0 + offset[0], -3.0 + offset[1], 2.0 + offset[2]];
    for (k, want) in want.iter().enumerate() {
        assert!((kept["position"][k].as_f64().unwrap() - want).abs() < 1e-9, "{kept}");
    }
    assert_eq!(kept["pose"]["up"], serde_json::json!([0.0, 0.0, 1.0]));
    let r = request(
        s,
        "POST",
        &format!("/api/scenes/{id}/edits"),
        &auth,
        br#"{"edit": "delete-annotation", "title": "crak"}"#,
    );
    assert!(error_of(&r).contains("did you mean `crack`"), "{}", error_of(&r));
}

/// Any revision downloads as a scene folder; one that does not exist is refused. The shipped
/// spectrum `other` is in the studio's library.
fn revisions_download_as_scene_folders(s: &str, id: &str, other: &str) {
    let auth = [("Authorization", BEARER)];
    let r = get(s, &format!("/api/scenes/{id}/download?revision=2"), &auth);
    assert_eq!((r.status, r.header("content-type")), (200, Some("application/x-tar")));
    let mut archive = tar::Archive::new(std::io::Cursor::new(r.body));
    let names: Vec<String> = archive
        .entries()
        .unwrap()
        .map(|e| e.unwrap().path().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names[0], "aosta-revision-2/scene.toml", "{names:?}");
    assert!(names.iter().any(|n| n.starts_with("aosta-revision-2/files/") && n.ends_with(".obj")));
    let r = get(s, &format!("/api/scenes/{id}/download?revision=9"), &auth);
    assert_eq!(r.status, 400);
    let library = get(s, "/api/spectra", &auth).json();
    let shipped = library.as_array().unwrap().iter().find(|x| x["name"] == other).unwrap();
    assert_eq!(shipped["reflectance"].as_array().unwrap().len(), 81);
    assert!(shipped["material"].as_str().unwrap().contains("travertine"), "{shipped}");
}

/// A coordinator serving the studio, holding the Aosta scene (64 × 36 px, rendered once): the
/// coordinator, the studio's address and the scene's id.
fn studio_with_scene(d: &std::path::Path) -> (Coordinator, String, String) {
    let (c, _) = Coordinator::with_studio(d);
    let s = c.studio.clone().unwrap();
    let scene = aosta_scene(d, 64, 36);
    submit(&scene, &["--spp", "1", "--tile", "32"], &c.url, &d.join("client.token"));
    let auth = [("Authorization", BEARER)];
    let id = get(&s, "/api/scenes", &auth).json()[0]["id"].as_str().unwrap().to_owned();
    (c, s, id)
}

/// Hypotheses from the page: saved, renamed and deleted as edits, checked as the scene file's
/// `[variants]` are (an unknown part or state refused in `scene check`'s words), and each sent
/// back with the state it gives every part of the model.
#[test]
fn hypotheses_are_edits_checked_as_the_scene_file_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_c, s, id) = studio_with_scene(d);
    let auth = [("Authorization", BEARER)];
    let edit = |body: serde_json::Value| {
        request(&s, "POST", &format!("/api/scenes/{id}/edits"), &auth, body.to_string().as_bytes())
    };
    let first = get(&s, &format!("/api/scenes/{id}"), &auth).json();
    let found = first["variants"].as_array().unwrap().iter().find(|v| v["name"] == "as-found");
    let found = found.unwrap();
    assert_eq!(found["parts"]["facade/travertine"], "degraded", "{found}");

    let r = edit(serde_json::json!({"edit": "save-variant", "name": "portal first",
        "state": "degraded", "states": {"facade/travertine": "cleaned", "facade/paving": "base"}}));
    assert_eq!(r.status, 200, "{}", r.text());
    let v = r.json();
    let saved = v["variants"].as_array().unwrap().iter().find(|v| v["name"] == "portal first");
    let parts = &saved.unwrap()["parts"];
    assert_eq!(
        (&parts["facade/travertine"], &parts["facade/paving"], &parts["facade/mortar"]),
        (&serde_json::json!("cleaned"), &serde_json::json!("base"), &serde_json::json!("degraded")),
        "{parts}"
    );
    let manifest = get(&s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    assert_eq!(manifest["variants"]["portal first"]["states"]["facade/travertine"], "cleaned");

    for (body, words) in [
        (
            serde_json::json!({"edit": "save-variant", "name": "x", "states": {"facade/travertin": "cleaned"}}),
            "travertin",
        ),
        (
            serde_json::json!({"edit": "save-variant", "name": "x", "state": "polished"}),
            "unknown state `polished`; use base, degraded or cleaned",
        ),
        (serde_json::json!({"edit": "save-variant", "name": " "}), "a hypothesis needs a name"),
        (serde_json::json!({"edit": "save-variant", "name": "x", "colour": 1}), "colour"),
        (
            serde_json::json!({"edit": "rename-variant", "name": "portal first", "to": "as-found"}),
            "a hypothesis named `as-found` exists",
        ),
        (
            serde_json::json!({"edit": "rename-variant", "name": "portal frist", "to": "y"}),
            "did you mean `portal first`",
        ),
        (serde_json::json!({"edit": "delete-variant", "name": "clean"}), "did you mean `cleaned`"),
    ] {
        let r = edit(body.clone());
        assert_eq!(r.status, 400, "{body}: {}", r.text());
        assert!(error_of(&r).contains(words), "{body}: {}", error_of(&r));
    }
    let r = edit(
        serde_json::json!({"edit": "rename-variant", "name": "portal first", "to": "campaign 1"}),
    );
    assert_eq!((r.status, r.json()["revision"].as_u64()), (200, Some(2)), "{}", r.text());
    let r = edit(serde_json::json!({"edit": "delete-variant", "name": "campaign 1"}));
    assert_eq!((r.status, r.json()["revision"].as_u64()), (200, Some(3)), "{}", r.text());
    let names: Vec<String> = r.json()["variants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["name"].as_str().unwrap().to_owned())
        .collect();
    assert_eq!(names, ["as-found", "cleaned"]);
    let summaries = get(&s, &format!("/api/scenes/{id}/revisions"), &auth).json();
    let summaries: Vec<&str> =
        summaries.as_array().unwrap().iter().map(|r| r["summary"].as_str().unwrap()).collect();
    assert!(summaries[2].contains("renamed `campaign 1`"), "{summaries:?}");
}

/// Light from the page: a photometric file read and kept (refused, naming it, when it is not
/// one), a luminaire saved with it (its figures and solid in the scene's view), a CIE
/// illuminant added by name, and every refusal of a light edit in the scene file's words.
#[test]
fn lights_and_photometric_files_are_checked_as_the_scene_file_is() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_c, s, id) = studio_with_scene(d);
    let auth = [("Authorization", BEARER)];
    let (file, reference) = upload_the_photometric_file(&s, &id);

    let edit = |body: serde_json::Value| {
        request(&s, "POST", &format!("/api/scenes/{id}/edits"), &auth, body.to_string().as_bytes())
    };
    let lamp = serde_json::json!({"kind": "point", "position": [0.0, -8.0, 0.3],
        "aim": [0.0, 0.0, 6.0], "ies": reference, "spectrum": "cie:A"});
    let r = edit(serde_json::json!({"edit": "save-light", "light": lamp}));
    assert_eq!(r.status, 200, "{}", r.text());
    let view = r.json();
    let shown = view["lights"].as_array().unwrap().iter().find(|l| l["index"] == 2).unwrap();
    assert_eq!(shown["light"]["spectrum"], "cie_A");
    let near = |a: &serde_json::Value, b: &serde_json::Value| {
        (a.as_f64().unwrap() / b.as_f64().unwrap() - 1.0).abs() < 1e-9
    };
    assert!(near(&shown["flux_lm"], &file["flux_lm"]), "{shown} {file}");
    assert!(near(&shown["intensity_cd"], &file["peak_cd"]), "{shown} {file}");
    assert_eq!(shown["solid"].as_array().unwrap().len(), 37 * 36);
    let manifest = get(&s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    assert_eq!(manifest["spectra"]["cie_A"]["illuminant"], "A");

    for (body, words) in [
        (
            serde_json::json!({"edit": "save-light", "index": 9, "light": lamp}),
            "the scene has 3 lights (0 to 2); no light 9",
        ),
        (serde_json::json!({"edit": "delete-light", "index": 3}), "no light 3"),
        (
            serde_json::json!({"edit": "save-light", "light": {"kind": "point", "position": [0.0, 0.0, 1.0], "spectrum": "cie:Q"}}),
            "cie_Q",
        ),
        (
            serde_json::json!({"edit": "save-light", "light": {"kind": "spot", "position": [0.0, 0.0, 1.0], "aim": [0.0, 0.0, 1.0], "cone_deg": 10.0, "intensity_cd": 100.0, "spectrum": "cie:A"}}),
            "aim",
        ),
        (
            serde_json::json!({"edit": "save-light", "light": {"kind": "point", "position": [0.0, 0.0, 1.0], "ies": format!("blake3:{}.ies", "0".repeat(64)), "spectrum": "cie:A"}}),
            "blake3:",
        ),
        (
            serde_json::json!({"edit": "save-light", "light": {"kind": "sky", "illuminance_lux": -5.0, "spectrum": "skylight"}}),
            "illuminance_lux",
        ),
        (serde_json::json!({"edit": "save-light", "light": {"kind": "lamp"}}), "lamp"),
    ] {
        let r = edit(body.clone());
        assert!([400, 404, 409].contains(&r.status), "{body}: {}", r.text());
        assert!(error_of(&r).contains(words), "{body}: {}", error_of(&r));
    }
    // A second sky is refused; the one there is changed in place, and a light deleted.
    let sky = serde_json::json!({"kind": "sky", "illuminance_lux": 20000.0, "model": "uniform", "spectrum": "skylight"});
    let r = edit(serde_json::json!({"edit": "save-light", "light": sky}));
    assert_eq!(r.status, 400, "{}", r.text());
    let r = edit(serde_json::json!({"edit": "save-light", "index": 1, "light": sky}));
    assert_eq!(r.status, 200, "{}", r.text());
    let v = r.json();
    assert_eq!(
        (v["lights"][1]["illuminance_lux"].as_f64(), v["lights"][1]["model"].as_str()),
        (Some(20000.0), Some("uniform sky"))
    );
    let r = edit(serde_json::json!({"edit": "delete-light", "index": 2}));
    assert_eq!(
        (r.status, r.json()["lights"].as_array().map(Vec::len)),
        (200, Some(2)),
        "{}",
        r.text()
    );

    // Lit by a tungsten lamp alone (CIE A), the preview colours under the lamp's light: its
    // white the one CIE 15:2004 Table T.3's chromaticity of A, (0.44757, 0.40745), gives in
    // linear sRGB, the brightest channel at 1.
    let lamp = serde_json::json!({"kind": "point", "position": [0.0, -5.0, 3.0], "intensity_cd": 500.0, "spectrum": "cie:A"});
    assert_eq!(edit(serde_json::json!({"edit": "save-light", "light": lamp})).status, 200);
    edit(serde_json::json!({"edit": "delete-light", "index": 1}));
    let r = edit(serde_json::json!({"edit": "delete-light", "index": 0}));
    assert_eq!(r.status, 200, "{}", r.text());
    let lights = r.json()["preview_lights"].clone();
    assert_eq!(lights[0]["key"], "scene", "{lights}");
    assert!(lights[0]["label"].as_str().unwrap().contains("luminaires (cie_A)"), "{lights}");
    let a = published_white(0.44757, 0.40745);
    for k in 0..3 {
        let got = lights[0]["white_linear_srgb"][k].as_f64().unwrap();
        assert!((got - a[k]).abs() < 5e-3, "{lights}");
    }
}

/// A photometric file read and kept: refused, naming it, when it is not one (or is too large,
/// or is sent to a scene that does not exist). The file's figures as the studio reads them,
/// and the reference it is kept by.
fn upload_the_photometric_file(s: &str, id: &str) -> (serde_json::Value, String) {
    let auth = [("Authorization", BEARER)];
    let upload = |name: &str, bytes: &[u8]| {
        let path = format!("/api/scenes/{id}/photometry?name={name}");
        request(s, "POST", &path, &auth, bytes)
    };
    let ldt = std::fs::read(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scene/tests/data/photometric/ldt_isym1_absolute.ldt"),
    )
    .unwrap();
    for (name, bytes, words) in [
        ("lamp.txt", &ldt[..], "ending in .ies or .ldt"),
        ("../lamp.ldt", &ldt[..], "ending in .ies"),
        ("lamp.ies", b"not a photometric file".as_slice(), "lamp.ies"),
        ("lamp.ldt", &vec![b'1'; (1 << 20) + 1][..], "at most 1048576"),
    ] {
        let r = upload(name, bytes);
        assert_eq!(r.status, 400, "{name}: {}", r.text());
        assert!(error_of(&r).contains(words), "{name}: {}", error_of(&r));
    }
    let r = request(
        s,
        "POST",
        &format!("/api/scenes/{}/photometry?name=a.ldt", "0".repeat(64)),
        &auth,
        &ldt,
    );
    assert_eq!(r.status, 404, "{}", r.text());
    let r = upload("wallwasher.ldt", &ldt);
    assert_eq!(r.status, 200, "{}", r.text());
    let file = r.json();
    let reference = file["reference"].as_str().unwrap().to_owned();
    assert!(reference.starts_with("blake3:") && reference.ends_with(".ldt"), "{file}");
    (file, reference)
}

/// A measured reflectance sent as CSV: read as `[spectra]` files are (refusals name the file and
/// the line), kept, and assigned to a material by the reference the studio answers.
#[test]
fn measured_spectra_sent_as_csv_are_read_as_scene_files_read_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_c, s, id) = studio_with_scene(d);
    let auth = [("Authorization", BEARER)];
    let send = |name: &str, body: &[u8]| {
        request(&s, "POST", &format!("/api/scenes/{id}/spectrum?name={name}"), &auth, body)
    };
    let rows: String = (400..=700).step_by(10).map(|nm| format!("{nm},0.25\n")).collect();
    for (name, body, words) in [
        ("a.png", rows.clone().into_bytes(), "ending in .csv or .txt"),
        ("a.csv", vec![0xff, 0xfe, 0x00], "a.csv: not UTF-8"),
        ("a.csv", vec![b'1'; (1 << 20) + 1], "at most 1048576"),
        ("short.csv", rows.clone().into_bytes(), "short.csv"),
    ] {
        let r = send(name, &body);
        assert_eq!(r.status, 400, "{name}: {}", r.text());
        assert!(error_of(&r).contains(words), "{name}: {}", error_of(&r));
    }
    // Measured from 400 to 700 nm only: held at its ends when asked, and said so.
    let r = send("short.csv&extrapolate=true", rows.as_bytes());
    assert_eq!(r.status, 200, "{}", r.text());
    let info = r.json();
    assert_eq!(info["reflectance"].as_array().unwrap().len(), 81);
    assert!(!info["notes"].as_array().unwrap().is_empty(), "{info}");
    let r = send(
        "flat.csv",
        (380..=780).step_by(5).map(|nm| format!("{nm},0.25\n")).collect::<String>().as_bytes(),
    );
    let reference = r.json()["reference"].as_str().unwrap().to_owned();
    let edit = |body: serde_json::Value| {
        request(&s, "POST", &format!("/api/scenes/{id}/edits"), &auth, body.to_string().as_bytes())
    };
    for (body, words) in [
        (
            serde_json::json!({"edit": "material", "material": "travertine", "file": reference, "spectrum": "marble_white_solid__eco_ward95"}),
            "not both",
        ),
        (
            serde_json::json!({"edit": "material", "material": "travertine", "file": "flat.csv"}),
            "send the spectrum to the studio first",
        ),
        (
            serde_json::json!({"edit": "material", "material": "travertine", "file": format!("blake3:{}.csv", "0".repeat(64))}),
            "has not been uploaded",
        ),
    ] {
        let r = edit(body.clone());
        assert!([400, 409].contains(&r.status), "{body}: {}", r.text());
        assert!(error_of(&r).contains(words), "{body}: {}", error_of(&r));
    }
    let r = edit(
        serde_json::json!({"edit": "material", "material": "travertine", "file": reference, "file_name": "flat.csv"}),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let stone = material(&r.json(), "travertine").clone();
    assert_eq!(stone["states"][0]["spectrum"], "flat", "{stone}");
    let l = stone["states"][0]["lab"][0].as_f64().unwrap();
    // CIE 1976: L* = 116 · 0.25^(1/3) − 16.
    assert!((l - (116.0 * 0.25f64.cbrt() - 16.0)).abs() < 1e-3, "L* {l}");
}

/// The white of a light of chromaticity (x, y) in linear sRGB (IEC 61966-2-1's matrix), scaled
/// so that its brightest channel is 1, as the studio shows whites.
fn published_white(x: f64, y: f64) -> [f64; 3] {
    let xyz = [x / y, 1.0, (1.0 - x - y) / y];
    let m = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]];
    let rgb: [f64; 3] = std::array::from_fn(|r| (0..3).map(|k| m[r][k] * xyz[k]).sum());
    let top = rgb.iter().copied().fold(0.0, f64::max);
    rgb.map(|v| v / top)
}

/// The preview colours each spectrum under the scene's own light, each of its light spectra
/// alone, or D65: the whites are the published chromaticities' in sRGB, and the scene's
/// daylight is its sun and sky in proportion to what each gives the ground.
#[test]
fn the_preview_colours_each_spectrum_under_the_scenes_own_light() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_c, s, id) = studio_with_scene(d);
    let auth = [("Authorization", BEARER)];
    let view = get(&s, &format!("/api/scenes/{id}"), &auth).json();
    let lights = view["preview_lights"].as_array().unwrap();
    let keys: Vec<&str> = lights.iter().map(|l| l["key"].as_str().unwrap()).collect();
    assert_eq!(keys, ["scene", "spectrum:sunlight", "spectrum:skylight", "cie:D65"], "{lights:?}");
    let white = |key: &str| -> Vec<f64> {
        let l = lights.iter().find(|l| l["key"] == key).unwrap();
        serde_json::from_value(l["white_linear_srgb"].clone()).unwrap()
    };
    // sRGB's white is D65's (IEC 61966-2-1). The sun here is D55, whose chromaticity CIE
    // 15:2004 Table T.3 gives as (0.33242, 0.34743): its white in linear sRGB, the brightest
    // channel at 1.
    let d55 = published_white(0.33242, 0.34743);
    for (key, want) in [("cie:D65", vec![1.0; 3]), ("spectrum:sunlight", d55.to_vec())] {
        let got = white(key);
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 5e-3, "{key}: {got:?}, want {want:?}");
        }
    }
    // The ground's daylight: the sun's illuminance on the horizontal (normal illuminance by the
    // sine of its elevation) and the sky's, so each state's XYZ under it is the two lights'
    // XYZs (each relative to its own white) weighted by those illuminances.
    let sun = &view["sun"];
    let e_sun = sun["illuminance_lux"].as_f64().unwrap()
        * sun["elevation_deg"].as_f64().unwrap().to_radians().sin();
    let sky =
        view["lights"].as_array().unwrap().iter().find(|l| l["light"]["kind"] == "sky").unwrap();
    let e_sky = sky["illuminance_lux"].as_f64().unwrap();
    assert!(e_sun > 1000.0 && e_sky > 1000.0, "{e_sun} {e_sky}");
    let mut states = 0;
    for m in view["materials"].as_array().unwrap() {
        for st in m["states"].as_array().unwrap() {
            let xyz = |key: &str| -> Vec<f64> {
                serde_json::from_value(st["under"][key]["xyz"].clone()).unwrap()
            };
            let (mix, a, b) = (xyz("scene"), xyz("spectrum:sunlight"), xyz("spectrum:skylight"));
            for k in 0..3 {
                let want = (e_sun * a[k] + e_sky * b[k]) / (e_sun + e_sky);
                assert!(
                    (mix[k] - want).abs() < 1e-3 * want.max(1.0),
                    "{}: {mix:?} vs {want}",
                    m["name"]
                );
            }
            // Under D65 the state looks as its own colour and L*a*b* say.
            assert_eq!(st["under"]["cie:D65"]["lab"], st["lab"], "{}", m["name"]);
            states += 1;
        }
    }
    assert!(states >= 4, "{states} states");
}

/// Images sent for a note are checked to be the PNG or JPEG their names say, kept, named in the
/// note, served back under their own media type (and nothing else the coordinator holds is),
/// and travel with the scene's download, which reads back as the same scene.
#[test]
fn images_kept_with_notes_are_checked_served_and_downloaded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_c, s, id) = studio_with_scene(d);
    let auth = [("Authorization", BEARER)];
    let send = |name: &str, body: &[u8]| {
        request(&s, "POST", &format!("/api/scenes/{id}/images?name={name}"), &auth, body)
    };
    let photo = restauro_tests::browser::solid_png(8, 6, [200, 40, 30]);
    for (name, body, words) in [
        ("a.gif", photo.clone(), "ending in .png or .jpg or .jpeg"),
        ("a.jpg", photo.clone(), "a.jpg: not a JPEG file"),
        ("a.png", b"<svg onload=alert(1)>".to_vec(), "a.png: not a PNG file"),
        ("big.png", vec![0; (16 << 20) + 1], "at most 16777216 bytes"),
    ] {
        let r = send(name, &body);
        assert_eq!(r.status, 400, "{name}: {}", r.text());
        assert!(error_of(&r).contains(words), "{name}: {}", error_of(&r));
    }
    let r = send("crack%202024.png", &photo);
    assert_eq!(r.status, 200, "{}", r.text());
    let reference = r.json()["reference"].as_str().unwrap().to_owned();
    assert_eq!(reference, format!("blake3:{}.png", blake3_hex(&photo)));
    let r = get(&s, &format!("/api/images/{reference}"), &auth);
    assert_eq!((r.status, r.header("content-type")), (200, Some("image/png")));
    assert_eq!(r.header("x-content-type-options"), Some("nosniff"));
    assert!(r.header("content-security-policy").unwrap().contains("sandbox"));
    assert_eq!(r.body, photo);

    // Only images: the scene's mesh asked for as a `.png` is not served, nor a hash not held.
    let manifest = get(&s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    let mesh = manifest["objects"][0]["mesh"].as_str().unwrap().to_owned();
    let disguised = mesh.replace(".obj", ".png");
    for path in [
        format!("/api/images/{mesh}"),
        format!("/api/images/{disguised}"),
        format!("/api/images/blake3:{}.png", "0".repeat(64)),
    ] {
        let r = get(&s, &path, &auth);
        assert_eq!(r.status, 404, "{path}: {}", r.text());
        assert!(error_of(&r).contains("no image"), "{path}: {}", error_of(&r));
    }

    let note = |images: serde_json::Value| {
        let body = serde_json::json!({"edit": "save-annotation", "annotation": {
            "title": "crack", "position": [0.0, 1.0, 0.0], "images": images}});
        request(&s, "POST", &format!("/api/scenes/{id}/edits"), &auth, body.to_string().as_bytes())
    };
    for (images, words) in [
        (serde_json::json!(["photos/crack.png"]), "send the image to the studio first"),
        (serde_json::json!([disguised]), "annotations[0].images[0]: not a PNG file"),
        (serde_json::json!([mesh]), "a note's image is a .png, .jpg or .jpeg file"),
        (serde_json::json!([format!("blake3:{}.png", "0".repeat(64))]), "has not been uploaded"),
    ] {
        let r = note(images.clone());
        assert!([400, 409].contains(&r.status), "{images}: {}", r.text());
        assert!(error_of(&r).contains(words), "{images}: {}", error_of(&r));
    }
    let r = note(serde_json::json!([reference]));
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["annotations"][0]["images"], serde_json::json!([reference]));

    // The download holds the image, and reads back as the very scene the studio holds.
    let r = get(&s, &format!("/api/scenes/{id}/download"), &auth);
    assert_eq!(r.status, 200);
    let mut archive = tar::Archive::new(std::io::Cursor::new(&r.body));
    let image_entry = archive
        .entries()
        .unwrap()
        .map(|e| e.unwrap().path().unwrap().to_string_lossy().into_owned())
        .find(|n| n.ends_with(".png"));
    assert!(image_entry.is_some_and(|n| n.contains("/files/")), "no image in the download");
    let limits = restauro_scene::load::Limits::default();
    let bundle = restauro_assets::folder::bundle_folder_archive(&r.body, None, &limits).unwrap();
    let latest = get(&s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    let read_back: serde_json::Value = serde_json::from_str(&bundle.canonical_json()).unwrap();
    assert_eq!(read_back, latest);
}

fn blake3_hex(bytes: &[u8]) -> String {
    blake3::hash(bytes).to_hex().to_string()
}

/// A zip of the folder `dir` (its files under `top/`, deflated).
fn folder_zip(dir: &std::path::Path, top: &str) -> Vec<u8> {
    use std::io::Write;
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let mut pending = vec![dir.to_owned()];
    while let Some(at) = pending.pop() {
        for entry in std::fs::read_dir(&at).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                pending.push(path);
                continue;
            }
            let relative = path.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            w.start_file(format!("{top}/{relative}"), options).unwrap();
            w.write_all(&std::fs::read(&path).unwrap()).unwrap();
        }
    }
    w.finish().unwrap().into_inner()
}

/// A tar of the folder `dir` (its entries under `top/`).
fn folder_tar(dir: &std::path::Path, top: &str) -> Vec<u8> {
    let mut b = tar::Builder::new(Vec::new());
    b.append_dir_all(top, dir).unwrap();
    b.into_inner().unwrap()
}

/// A tar of the `(path, bytes)` entries, written as given (the tar crate's writer refuses
/// `..` in a path, so the header's name is set by hand).
fn raw_tar(entries: &[(&str, &[u8])]) -> Vec<u8> {
    let mut b = tar::Builder::new(Vec::new());
    for (path, bytes) in entries {
        let mut h = tar::Header::new_ustar();
        h.as_ustar_mut().unwrap().name[..path.len()].copy_from_slice(path.as_bytes());
        h.set_size(bytes.len() as u64);
        h.set_mode(0o644);
        h.set_entry_type(tar::EntryType::Regular);
        h.set_cksum();
        b.append(&h, *bytes).unwrap();
    }
    b.into_inner().unwrap()
}

/// A scene folder sent as a tar becomes one of the studio's scenes (bundled as `restauro
/// scene bundle` bundles it, the same identity), with a preview job; a bundle archive too; and
/// what is not a scene folder is refused in words that name the problem.
#[test]
fn a_scene_folder_sent_as_a_tar_or_a_zip_opens_as_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, _) = Coordinator::with_studio(d);
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let scene = aosta_scene(d, 64, 36);
    let folder = std::path::Path::new(&scene).parent().unwrap().to_owned();
    let send = |name: &str, body: &[u8]| {
        request(&s, "POST", &format!("/api/scenes?name={name}"), &auth, body)
    };
    // The generator writes four scenes into the folder (four lights): one is chosen.
    let r = send("aosta-sent", &folder_tar(&folder, "aosta"));
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(error_of(&r).contains("4 scene files at the same level"), "{}", error_of(&r));
    let r = send("aosta-sent&scene=aosta/nothing.toml", &folder_tar(&folder, "aosta"));
    assert!(error_of(&r).contains("no scene file `aosta/nothing.toml`"), "{}", error_of(&r));
    let r = send("aosta-sent&scene=aosta/aosta.toml", &folder_tar(&folder, "aosta"));
    assert_eq!(r.status, 200, "{}", r.text());
    let opened = r.json();
    assert_eq!(opened["job"]["name"], "aosta-sent", "{opened}");
    let id = opened["scene"].as_str().unwrap().to_owned();
    let scenes = get(&s, "/api/scenes", &auth).json();
    assert!(scenes.as_array().unwrap().iter().any(|x| x["id"] == id.as_str()), "{scenes}");
    // `restauro scene bundle` gives the scene the same identity, and its archive opens as the
    // same scene.
    let archive = d.join("aosta.tar");
    let o =
        restauro_tests::restauro(&["scene", "bundle", &scene, "--out", archive.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let r = send("aosta-archive", &std::fs::read(&archive).unwrap());
    assert_eq!((r.status, r.json()["scene"].as_str()), (200, Some(id.as_str())), "{}", r.text());
    // Zipped, as a file manager packs a folder: the same scene.
    let zipped = folder_zip(&folder, "aosta");
    let r = send("aosta-zip&scene=aosta/aosta.toml", &zipped);
    assert_eq!((r.status, r.json()["scene"].as_str()), (200, Some(id.as_str())), "{}", r.text());
    let r = send("aosta-zip", &zipped[..zipped.len() / 2]);
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(error_of(&r).contains("not a readable zip archive"), "{}", error_of(&r));

    let toml = std::fs::read(&scene).unwrap();
    for (name, body, words) in [
        (
            "x",
            b"not a tar at all, but long enough to be read as one? no".repeat(20),
            "the folder sent",
        ),
        ("x", raw_tar(&[("../scene.toml", &toml)]), "is not a path inside the folder"),
        ("x", raw_tar(&[("a/readme.txt", b"hello")]), "it has no scene file"),
        ("x", raw_tar(&[("a.toml", &toml), ("b.toml", &toml)]), "2 scene files at the same level"),
        ("x", raw_tar(&[("aosta/scene.toml", &toml)]), "meshes/facade.obj"),
        ("bad%0Aname&scene=aosta/aosta.toml", folder_tar(&folder, "aosta"), "name"),
    ] {
        let r = send(name, &body);
        assert_eq!(r.status, 400, "{words}: {}", r.text());
        assert!(error_of(&r).contains(words), "{words}: {}", error_of(&r));
    }
}

/// The studio's comparison of two snapshots is `restauro compare`'s: the same ΔE00 statistics
/// for the same two rendered images, and a map of their size; snapshots of two sizes, or one
/// not finished, are refused.
#[test]
fn the_studios_comparison_is_restauro_compares() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, _) = Coordinator::with_studio(d);
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let _worker = Worker::start(d, &c.url, "w", &[]);
    let scene = aosta_scene(d, 64, 36);
    let token = d.join("client.token");
    let render = |variant: &str, width: &str| {
        let id =
            submit(&scene, &["--spp", "1", "--variant", variant, "--width", width], &c.url, &token);
        let o = client(&["watch", &id], &c.url, &token);
        assert!(o.status.success(), "{}", text(&o));
        let out = d.join(format!("{variant}-{width}"));
        let o = client(&["fetch", &id, "--out", out.to_str().unwrap()], &c.url, &token);
        assert!(o.status.success(), "{}", text(&o));
        let exr = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                p.extension().is_some_and(|x| x == "exr")
                    && !p.to_string_lossy().contains("retinex")
            })
            .expect("the rendered EXR");
        (id, exr)
    };
    let (a, a_exr) = render("as-found", "64");
    let (b, b_exr) = render("cleaned", "64");
    let r = get(&s, &format!("/api/compare?a={a}&b={b}"), &auth);
    assert_eq!(r.status, 200, "{}", r.text());
    let studio = r.json();
    let out = d.join("compared");
    let o = restauro_tests::restauro(&[
        "compare",
        a_exr.to_str().unwrap(),
        b_exr.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let cli: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("compare.json")).unwrap()).unwrap();
    assert_eq!(studio["delta_e00"], cli["delta_e00"], "studio {studio}, restauro compare {cli}");
    assert_eq!(studio["white_luminance"], cli["white_luminance"]);
    assert!(studio["delta_e00"]["mean"].as_f64().unwrap() > 1.0, "the hypotheses differ: {studio}");
    let map = get(&s, &format!("/api/compare/delta-e.png?a={a}&b={b}"), &auth);
    assert_eq!((map.status, map.header("content-type")), (200, Some("image/png")));
    let (pixels, width) = restauro_tests::browser::png_rgb(&map.body);
    assert_eq!((width, pixels.len()), (64, 64 * 36));

    let (small, _) = render("cleaned", "32");
    let r = get(&s, &format!("/api/compare?a={a}&b={small}"), &auth);
    assert_eq!(r.status, 400);
    assert!(error_of(&r).contains("compare snapshots of one size"), "{}", error_of(&r));
    let r = get(&s, &format!("/api/compare?a={a}"), &auth);
    assert!(error_of(&r).contains("b: give the job to compare"), "{}", error_of(&r));
    let long = submit(&scene, &["--spp", "4096", "--tile", "8"], &c.url, &token);
    let r = get(&s, &format!("/api/compare?a={a}&b={long}"), &auth);
    assert_eq!(r.status, 409, "{}", r.text());
    assert!(error_of(&r).contains("not done"), "{}", error_of(&r));
}

/// A snapshot at another exposure is what `restauro display --exposure` makes of its EXR, and in
/// false colour each pixel's luminance sits on the logarithmic scale asked for.
#[test]
fn exposure_and_false_colour_are_restauro_displays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let farm = Coordinator::studio_farm(d, 64, 36);
    let (c, s) = (&farm.coordinator, farm.coordinator.studio.clone().unwrap());
    let auth = [("Authorization", BEARER)];
    let id = submit(&farm.scene, &["--spp", "1"], &c.url, &farm.token);
    let o = client(&["watch", &id], &c.url, &farm.token);
    assert!(o.status.success(), "{}", text(&o));
    let out = d.join("fetched");
    let o = client(&["fetch", &id, "--out", out.to_str().unwrap()], &c.url, &farm.token);
    assert!(o.status.success(), "{}", text(&o));
    let exr = out.join("aosta.exr");

    let l = get(&s, &format!("/api/jobs/{id}/luminance"), &auth).json();
    let white = l["auto_white_cd_m2"].as_f64().unwrap() / 2.0;
    let (lo, hi) = (l["scale_min_cd_m2"].as_f64().unwrap(), l["scale_max_cd_m2"].as_f64().unwrap());
    assert!(lo <= l["p1_cd_m2"].as_f64().unwrap() && l["p99_cd_m2"].as_f64().unwrap() <= hi, "{l}");
    let r = get(&s, &format!("/api/jobs/{id}/display.png?exposure=absolute:{white}"), &auth);
    assert_eq!((r.status, r.header("content-type")), (200, Some("image/png")), "{}", r.text());
    let cli = d.join("display.png");
    let o = restauro_tests::restauro(&[
        "display",
        exr.to_str().unwrap(),
        "--exposure",
        &format!("absolute:{white}"),
        "--out",
        cli.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let png = restauro_tests::browser::png_rgb;
    assert!(
        png(&r.body).0 == png(&std::fs::read(&cli).unwrap()).0,
        "the studio's pixels differ from restauro display's"
    );
    let r = get(&s, &format!("/api/jobs/{id}/display.png?exposure=bright"), &auth);
    assert_eq!(r.status, 400);
    assert!(
        error_of(&r).contains("use auto, auto:<key>, absolute:<cd/m²> or relative"),
        "{}",
        error_of(&r)
    );

    // False colour: the pixel of median luminance is at the middle of a scale centred on it.
    let image = restauro_image::image_files::read_exr(&exr, 1 << 24).unwrap();
    let (k, p) = image.pixels.iter().enumerate().find(|(_, p)| p[1] > 0.0).unwrap();
    let y = f64::from(p[1]);
    let r = get(
        &s,
        &format!("/api/jobs/{id}/luminance.png?min_cd_m2={}&max_cd_m2={}", y / 10.0, y * 10.0),
        &auth,
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let (pixels, _) = png(&r.body);
    assert_eq!(
        pixels[k],
        restauro_image::delta_e::viridis(0.5),
        "luminance {y} cd/m² at the scale's middle"
    );
    for bad in ["min_cd_m2=0&max_cd_m2=10", "min_cd_m2=10&max_cd_m2=1", "max_cd_m2=10"] {
        let r = get(&s, &format!("/api/jobs/{id}/luminance.png?{bad}"), &auth);
        assert_eq!(r.status, 400, "{bad}: {}", r.text());
        assert!(error_of(&r).contains("min_cd_m2"), "{bad}: {}", error_of(&r));
    }
}

/// A scene in survey coordinates (5 000 000 m east): the page works near zero, and what it
/// saves goes back into the file in the survey's coordinates, the scene's `origin` included.
#[test]
fn a_georeferenced_scene_is_shown_near_zero_and_edited_in_survey_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (c, _) = Coordinator::with_studio(d);
    let s = c.studio.clone().unwrap();
    let auth = [("Authorization", BEARER)];
    let (e, n) = (5_000_000.25, 4_000_000.5);
    let folder = d.join("survey");
    std::fs::create_dir_all(&folder).unwrap();
    let corners = [[e, n, 0.0], [e + 10.0, n, 0.0], [e + 10.0, n + 10.0, 0.0], [e, n + 10.0, 0.0]];
    let obj: String = corners.iter().map(|[x, y, z]| format!("v {x} {y} {z}\n")).collect();
    std::fs::write(folder.join("ground.obj"), obj + "f 1 2 3 4\n").unwrap();
    let scene = format!(
        "format = 1\norigin = [5000000.0, 4000000.0, 0.0]\n\
         [camera]\nposition = [{}, {}, 1.6]\ntarget = [{}, {}, 0.0]\nwidth = 32\nheight = 18\n\
         [spectra]\ngrey = {{ constant = 0.5 }}\nlamp = {{ illuminant = \"A\" }}\n\
         [materials.grey]\nmodel = \"lambert\"\nreflectance = \"grey\"\n\
         [[objects]]\nname = \"ground\"\nmesh = \"ground.obj\"\nmaterial = \"grey\"\n\
         [[lights]]\nkind = \"point\"\nposition = [{}, {}, 3.0]\nintensity_cd = 1000.0\nspectrum = \"lamp\"\n",
        e + 5.0,
        n - 5.0,
        e + 5.0,
        n + 5.0,
        e + 5.0,
        n + 5.0
    );
    let path = folder.join("survey.toml");
    std::fs::write(&path, scene).unwrap();
    submit(path.to_str().unwrap(), &["--spp", "1"], &c.url, &d.join("client.token"));
    let id = get(&s, "/api/scenes", &auth).json()[0]["id"].as_str().unwrap().to_owned();
    let view = get(&s, &format!("/api/scenes/{id}"), &auth).json();
    let offset: Vec<f64> = serde_json::from_value(view["offset_m"].clone()).unwrap();
    assert!(
        (offset[0] - 5_000_000.0).abs() < 100.0,
        "the page's zero is in the survey: {offset:?}"
    );
    let camera = &view["camera"]["position"];
    let near = (0..3).all(|k| camera[k].as_f64().unwrap().abs() < 100.0);
    assert!(near, "the page's camera is near its zero: {camera}");
    // The luminaires' table shows the file's own coordinates.
    assert_eq!(view["lights"][0]["light"]["position"], serde_json::json!([e + 5.0, n + 5.0, 3.0]));

    let r = request(
        &s,
        "POST",
        &format!("/api/scenes/{id}/edits"),
        &auth,
        serde_json::json!({"edit": "save-view", "view": {"name": "corner",
            "position": [1.0, 1.6, 8.0], "target": [1.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0]}})
        .to_string()
        .as_bytes(),
    );
    assert_eq!(r.status, 200, "{}", r.text());
    let manifest = get(&s, &format!("/api/scenes/{id}/scene.json"), &auth).json();
    assert_eq!(manifest["origin"], serde_json::json!([5_000_000.0, 4_000_000.0, 0.0]));
    let kept = &manifest["views"][0]["position"];
    let want = [1.0 + offset[0], -8.0 + offset[1], 1.6 + offset[2]];
    for (k, want) in want.iter().enumerate() {
        assert!((kept[k].as_f64().unwrap() - want).abs() < 1e-6, "{kept} against {want:?}");
    }
}

/// A scene folder sent to the studio whose scene names its files by URL: the coordinator
/// fetches them for the user, but by default only from public servers (loopback stands for the
/// farm's own network here), and with `--fetch-private-urls` from any; the scene then has the
/// identity of the same folder with the files in it, and the files are in the coordinator's
/// data folder.
#[test]
fn a_scene_sent_with_files_by_url_is_fetched_only_from_where_the_operator_allows() {
    use restauro_tests::web::{scene_by_url, serve_folder};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = std::path::PathBuf::from(aosta_scene(d, 64, 36));
    let folder = scene.parent().unwrap().to_owned();
    let (base, requests) = serve_folder(folder.clone());
    let web = d.join("web");
    std::fs::create_dir_all(web.join("aosta")).unwrap();
    let files = scene_by_url(&scene, &base, &web.join("aosta/aosta.toml"));
    let auth = [("Authorization", BEARER)];
    let send = |studio: &str, name: &str, body: &[u8]| {
        let path = format!("/api/scenes?name={name}&scene=aosta/aosta.toml");
        request(studio, "POST", &path, &auth, body)
    };

    let (c, _) = Coordinator::with_studio(d);
    let r = send(c.studio.as_deref().unwrap(), "by-url", &folder_tar(&web.join("aosta"), "aosta"));
    assert_eq!(r.status, 400, "{}", r.text());
    assert!(error_of(&r).contains("not a public address"), "{}", error_of(&r));
    assert!(error_of(&r).contains("--fetch-private-urls"), "{}", error_of(&r));
    assert!(requests.lock().unwrap().is_empty(), "nothing fetched");
    drop(c);

    let data = d.join("data-intranet");
    let args = ["--studio-listen", "127.0.0.1:0", "--fetch-private-urls"];
    let c = Coordinator::start(d, &data, "127.0.0.1:0", &args);
    let studio = c.studio.as_deref().unwrap();
    let from_folder = send(studio, "in-folder", &folder_tar(&folder, "aosta"));
    let from_web = send(studio, "by-url", &folder_tar(&web.join("aosta"), "aosta"));
    assert_eq!(from_web.status, 200, "{}", from_web.text());
    assert_eq!(from_web.json()["scene"], from_folder.json()["scene"], "one scene");
    assert_eq!(requests.lock().unwrap().len(), files);
    assert!(data.join("downloads/blake3").read_dir().unwrap().count() >= files);
}
