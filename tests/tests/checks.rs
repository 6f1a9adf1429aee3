//! Tiles checked (issue 40): the coordinator renders a sample of each worker's tiles a second
//! time on another worker and compares bytes; a mismatch is settled by a third; the worker found
//! wrong is quarantined and its unchecked tiles rendered again. Real processes on loopback: a
//! coordinator, honest workers and one that lies (the worker's hidden fault injection alters
//! one pixel of a tile by the least bit of its X).

use restauro_tests::{
    Coordinator, Standby, Worker, aosta_scene, assert_identical, client, exr_pixels as pixels,
    free_loopback_addr, http_get, restauro, sample, text, token_files, wait_for,
};
use std::path::Path;
use std::time::Duration;

/// 96 × 54 pixels in 8-pixel tiles: 84 tiles, each a few milliseconds at 2 samples.
const OPTIONS: [&str; 4] = ["--spp", "2", "--tile", "8"];

/// The scene rendered in one process, as the reference.
fn reference(d: &Path, scene: &str) -> Vec<[f32; 3]> {
    let out = d.join("alone");
    let mut args = vec!["render", scene, "--in-process", "--out", out.to_str().unwrap()];
    args.extend(OPTIONS);
    let o = restauro(&args);
    assert!(o.status.success(), "{}", text(&o));
    pixels(&out.join("aosta.exr"))
}

/// Submits `scene` and waits for its results in `out`.
fn render_on_the_farm(c: &Coordinator, d: &Path, scene: &str, out: &Path) {
    let (token, _) = token_files(d);
    let mut args = vec!["submit", scene, "--wait", "--out", out.to_str().unwrap()];
    args.extend(OPTIONS);
    let o = client(&args, &c.url, &token);
    assert!(o.status.success(), "{}", text(&o));
}

fn metric(c: &Coordinator, name: &str) -> f64 {
    let (status, body) = http_get(c.metrics.as_deref().unwrap(), "/metrics");
    assert_eq!(status, 200, "{body}");
    sample(&body, name)
}

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |s| s.lines().count())
}

/// A farm of a liar (started first, so that it is in from the first tile) and `honest` honest
/// workers, on a coordinator with `checks` as its check options.
fn farm(
    d: &Path,
    checks: &[&str],
    lie: &[&str],
    honest: usize,
) -> (Coordinator, Worker, Vec<Worker>) {
    let mut extra = vec!["--metrics-listen", "127.0.0.1:0"];
    extra.extend(checks);
    let c = Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &extra);
    let log = d.join("liar-tiles.log");
    let mut liar_args = vec!["--tile-log", log.to_str().unwrap()];
    liar_args.extend(lie);
    let liar = Worker::start(d, &c.url, "liar", &liar_args);
    let (token, _) = token_files(d);
    wait_for("the liar to register", Duration::from_secs(30), || {
        text(&client(&["workers"], &c.url, &token)).contains("liar")
    });
    let workers =
        (1..=honest).map(|i| Worker::start(d, &c.url, &format!("honest-{i}"), &[])).collect();
    // All in before the job: a dispute with no third worker registered is left undecided.
    wait_for("the honest workers to register", Duration::from_secs(30), || {
        text(&client(&["workers"], &c.url, &token)).matches("honest-").count() == honest
    });
    (c, liar, workers)
}

/// What the farm says of the liar once the job is done: it was quarantined, told so, and left.
fn the_liar_was_quarantined(c: &Coordinator, d: &Path, mut liar: Worker) {
    assert_eq!(metric(c, "restauro_workers_quarantined_total"), 1.0);
    assert!(metric(c, "restauro_tile_checks_disputed_total") >= 1.0);
    assert!(metric(c, "restauro_tile_checks_agreed_total") >= 1.0);
    let (token, _) = token_files(d);
    let listed = text(&client(&["workers"], &c.url, &token));
    let line = listed
        .lines()
        .find(|l| l.starts_with("quarantined"))
        .unwrap_or_else(|| panic!("`restauro workers` lists no quarantined worker:\n{listed}"));
    assert!(line.contains("liar") && line.contains("differed from the same tile"), "{line}");
    assert!(
        !listed.lines().any(|l| !l.starts_with("quarantined") && l.contains(" liar ")),
        "{listed}"
    );
    // Refused when it registers again, it stops, saying why.
    let status = {
        let mut waited = 0;
        loop {
            if let Some(status) = liar.0.try_wait().unwrap() {
                break status;
            }
            assert!(waited < 600, "the quarantined worker is still running");
            std::thread::sleep(Duration::from_millis(50));
            waited += 1;
        }
    };
    assert!(!status.success());
    let said = std::fs::read_to_string(d.join("liar.log")).unwrap();
    assert!(said.contains("is quarantined"), "{said}");
}

/// A coordinator with `store` (its store's arguments), three honest workers and one lying in
/// one pixel of one tile render the scene: the image is the one process renders, and the liar
/// is quarantined. The coordinator, with its honest workers.
fn one_pixel_liar_is_found(d: &Path, store: &[&str]) -> (Coordinator, Vec<Worker>) {
    let scene = aosta_scene(d, 96, 54);
    let alone = reference(d, &scene);
    // Every result of a worker not yet trusted is checked, and none is trusted: the one altered
    // tile is checked, wherever it falls.
    let checks = [store, &["--check-rate-new", "1", "--trust-after", "1000000"]].concat();
    // Its first tile, whatever it is: a tile of its own or a check of another worker's.
    let lie = ["--fault-lie-from", "1", "--fault-lie-count", "1"];
    let (c, liar, honest) = farm(d, &checks, &lie, 3);
    let out = d.join("farm");
    render_on_the_farm(&c, d, &scene, &out);
    assert!(lines(&d.join("liar-tiles.log")) >= 1, "the liar rendered no tile");
    assert_identical(&pixels(&out.join("aosta.exr")), &alone);
    the_liar_was_quarantined(&c, d, liar);
    (c, honest)
}

#[test]
fn a_worker_lying_in_one_pixel_of_one_tile_is_found_and_the_image_is_right() {
    let dir = tempfile::tempdir().unwrap();
    one_pixel_liar_is_found(dir.path(), &[]);
}

#[test]
fn a_worker_lying_in_every_tile_is_found_at_the_default_rates_and_its_tiles_redone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 96, 54);
    let alone = reference(d, &scene);
    // The coordinator's defaults: half of a new worker's results are checked until four are
    // confirmed. A liar's never are; the chance that none of its first k results is checked is
    // 2^-k, and it renders a third of the job's 84 tiles or so.
    let (c, liar, _honest) = farm(d, &[], &["--fault-lie-from", "1"], 2);
    let out = d.join("farm");
    render_on_the_farm(&c, d, &scene, &out);
    let rendered = lines(&d.join("liar-tiles.log"));
    assert!(rendered >= 1, "the liar rendered no tile: the test proves nothing");
    // Every tile it rendered was a lie, and none is in the image: those found by a check were
    // replaced, and those no check had reached when it was found were rendered again.
    assert_identical(&pixels(&out.join("aosta.exr")), &alone);
    the_liar_was_quarantined(&c, d, liar);
    let log = std::fs::read_to_string(d.join("coordinator.log")).unwrap();
    let redone = log.lines().find(|l| l.contains("worker quarantined")).unwrap_or_default();
    eprintln!("the liar rendered {rendered} tiles; {redone}");
}

/// The liar among honest workers on the fleet's store (issue 40, item 6): PostgreSQL keeps the
/// tiles, the disputed renderings and the quarantine, so the image is right, and the
/// coordinator that takes the lead when the leader is killed knows the liar for what it is
/// (the refusal of a quarantined identity that registers again is `farm`'s unit test's).
#[test]
fn on_postgresql_a_liar_is_found_and_the_next_leader_knows_it() {
    let Some(url) = restauro_tests::fleet::database("liar") else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fleet = ["--store", &url, "--lead-ttl-s", "3"];
    let (c, _honest) = one_pixel_liar_is_found(d, &fleet);
    // A standby with a folder of its own takes the lead from the killed leader: what it knows
    // of the liar it read from the database.
    let standby = Standby::start(d, &d.join("data-standby"), &free_loopback_addr(), &fleet);
    drop(c);
    let (next, _) = standby.wait_to_lead();
    let (token, _) = token_files(d);
    let listed = text(&client(&["workers"], &next.url, &token));
    assert!(
        listed.lines().any(|l| l.starts_with("quarantined") && l.contains("liar")),
        "the new leader does not list the quarantined liar:\n{listed}"
    );
}

#[test]
fn honest_workers_check_each_other_and_agree() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 96, 54);
    let alone = reference(d, &scene);
    let c = Coordinator::start(
        d,
        &d.join("data"),
        "127.0.0.1:0",
        &["--metrics-listen", "127.0.0.1:0", "--check-rate", "0.5"],
    );
    let _workers: Vec<Worker> =
        (1..=2).map(|i| Worker::start(d, &c.url, &format!("w{i}"), &[])).collect();
    let out = d.join("farm");
    render_on_the_farm(&c, d, &scene, &out);
    assert_identical(&pixels(&out.join("aosta.exr")), &alone);
    assert!(metric(&c, "restauro_tile_checks_agreed_total") >= 1.0);
    assert_eq!(metric(&c, "restauro_tile_checks_disputed_total"), 0.0);
    assert_eq!(metric(&c, "restauro_workers_quarantined_total"), 0.0);
    let (token, _) = token_files(d);
    let listed = text(&client(&["workers"], &c.url, &token));
    let confirmed: u64 = listed
        .lines()
        .filter_map(|l| l.split("confirmed").nth(1))
        .filter_map(|rest| rest.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    assert!(confirmed >= 2, "no worker's results were confirmed:\n{listed}");
}

#[test]
fn with_two_workers_a_dispute_is_told_and_the_job_still_ends() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = aosta_scene(d, 96, 54);
    let checks = ["--check-rate-new", "1", "--trust-after", "1000000"];
    let lie = ["--fault-lie-from", "1", "--fault-lie-count", "1"];
    let (c, _liar, _honest) = farm(d, &checks, &lie, 1);
    render_on_the_farm(&c, d, &scene, &d.join("farm"));
    // No third worker to say which of the two is wrong: nobody is quarantined, the operator is
    // told, and the job is not held up waiting for a worker that may never come.
    assert!(metric(&c, "restauro_tile_checks_undecided_total") >= 1.0);
    assert_eq!(metric(&c, "restauro_workers_quarantined_total"), 0.0);
    let log = std::fs::read_to_string(d.join("coordinator.log")).unwrap();
    assert!(log.contains("no third worker is registered to settle it"), "{log}");
}

/// What a coordinator given `flag=value` says as it refuses to start.
fn refusal(d: &Path, flag: &str, value: &str) -> String {
    let (client_token, worker_token) = token_files(d);
    let o = std::process::Command::new(restauro_tests::binary("restauro-coordinator"))
        .args(["--listen", "127.0.0.1:0", "--data"])
        .arg(d.join("data"))
        .arg("--client-token-file")
        .arg(&client_token)
        .arg("--worker-token-file")
        .arg(&worker_token)
        .arg(format!("{flag}={value}"))
        .output()
        .unwrap();
    assert!(!o.status.success(), "{flag}={value} was taken");
    text(&o)
}

#[test]
fn a_check_rate_that_is_not_a_share_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, value) in [("--check-rate", "1.5"), ("--check-rate-new", "-0.1")] {
        let said = refusal(dir.path(), flag, value);
        let words =
            format!("{flag} {value}: use a share between 0 (no check) and 1 (every result)");
        assert!(said.contains(&words), "{said}");
    }
}

/// The lead's time to live (issue 40): under a second it would be renewed faster than a busy
/// database answers; over an hour the farm would wait that long for a standby.
#[test]
fn a_lead_time_to_live_out_of_range_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    for value in ["0.2", "7200", "NaN"] {
        let said = refusal(dir.path(), "--lead-ttl-s", value);
        assert!(
            said.contains(&format!("--lead-ttl-s {value}: give seconds from 1 to 3600")),
            "{said}"
        );
    }
}
