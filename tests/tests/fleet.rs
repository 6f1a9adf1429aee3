//! The farm's store on PostgreSQL (issue 40) against a real server: it keeps what the file store
//! keeps, call for call, and its schema is migrated once however many coordinators open it.
//! Skipped, saying so, without `RESTAURO_TEST_POSTGRES` (see `restauro_tests::fleet`).

use restauro_farm::store::Store;

type Seen = Vec<String>;

/// The same calls on `store`, and what each answered, in words.
fn exercise(store: &Store) -> Seen {
    let mut seen = Vec::new();
    let mut say = |what: &str, value: String| seen.push(format!("{what}: {value}"));
    let (secret, first) = store.begin_run([7; 32]).unwrap();
    let (again, second) = store.begin_run([9; 32]).unwrap();
    say("epochs", format!("{first} {second}, secret kept {}", secret == again));
    store.put_job("b", b"record b").unwrap();
    store.put_job("a", b"record a").unwrap();
    store.put_job("a", b"record a, later").unwrap();
    say("jobs", format!("{:?}", store.jobs().unwrap()));
    store.put_revision("scene", 2, b"two").unwrap();
    store.put_revision("scene", 1, b"one").unwrap();
    say("revisions", format!("{:?}", store.revisions().unwrap()));
    // A batch with a tile twice: its last bytes stand.
    let tiles: Vec<(&str, u32, &[u8])> =
        vec![("a", 5, b"x"), ("a", 1, b"y"), ("b", 0, b"z"), ("a", 5, b"x2"), ("a", 9, b"w")];
    store.put_tiles(&tiles).unwrap();
    say("finished a", format!("{:?}", store.finished_tiles("a").unwrap()));
    say("tile a 5", format!("{:?}", store.tile("a", 5).unwrap()));
    say("tile a 2", format!("{:?}", store.tile("a", 2).unwrap()));
    store.put_disputed("a", 1, b"other").unwrap();
    say("disputed", format!("{:?}", store.disputed("a", 1).unwrap()));
    store.remove_tile_list("a", &[1]).unwrap();
    say(
        "after list",
        format!("{:?} {:?}", store.finished_tiles("a").unwrap(), store.disputed("a", 1).unwrap()),
    );
    store.remove_tile_range("a", 5..9).unwrap();
    say("after range", format!("{:?}", store.finished_tiles("a").unwrap()));
    store.put_disputed("b", 0, b"d").unwrap();
    store.remove_tiles("b").unwrap();
    say(
        "after removal",
        format!("{:?} {:?}", store.finished_tiles("b").unwrap(), store.disputed("b", 0).unwrap()),
    );
    store.put_quarantine("00000000000000ff", b"{}").unwrap();
    say("quarantine", format!("{:?}", store.quarantine().unwrap()));
    say("problem", format!("{:?}", store.problem()));
    seen
}

#[test]
fn the_postgres_store_keeps_what_the_file_store_keeps() {
    let Some(url) = restauro_tests::fleet::database("store") else { return };
    let dir = tempfile::tempdir().unwrap();
    let file = exercise(&Store::open(&dir.path().join("store.redb")).unwrap());
    let postgres = exercise(&Store::connect(&url).unwrap());
    assert_eq!(postgres, file);
    // Opened again (a second coordinator, a restart): the schema is not migrated twice, and
    // what was kept is there.
    let reopened = Store::connect(&url).unwrap();
    assert_eq!(reopened.jobs().unwrap().len(), 2);
    assert_eq!(reopened.begin_run([0; 32]).unwrap().1, 3);
}

#[test]
fn a_database_that_is_not_there_is_refused_naming_it_without_the_password() {
    let Some(url) = restauro_tests::fleet::database("absent") else { return };
    let (server, _) = url.rsplit_once('/').unwrap();
    let absent = format!("{server}/no_such_database");
    let Err(e) = Store::connect(&absent) else { panic!("a database that is not there opened") };
    let e = e.to_string();
    assert!(e.contains("no_such_database") && e.contains("does not exist"), "{e}");
    assert!(!e.contains(":restauro@"), "the password is shown: {e}");
}

/// The one-process render of `scene` with `options`, in `d/alone`.
fn render_alone(d: &std::path::Path, scene: &str, options: &[&str]) -> std::path::PathBuf {
    let alone = d.join("alone");
    let mut args = vec!["render", scene, "--in-process", "--out", alone.to_str().unwrap()];
    args.extend(options);
    let o = restauro_tests::restauro(&args);
    assert!(o.status.success(), "{}", restauro_tests::text(&o));
    alone
}

/// The id of a job of `scene` with `options`, submitted to the coordinator at `url`.
fn submitted(scene: &str, options: &[&str], url: &str, token: &std::path::Path) -> String {
    let mut submit = vec!["submit", scene];
    submit.extend(options);
    let o = restauro_tests::client(&submit, url, token);
    assert!(o.status.success(), "{}", restauro_tests::text(&o));
    String::from_utf8_lossy(&o.stdout).trim().to_owned()
}

/// The results of job `id`, fetched from the coordinator at `url`, are the one-process
/// render's in `alone`, bit for bit.
fn fetched_is_alone(
    d: &std::path::Path,
    id: &str,
    url: &str,
    token: &std::path::Path,
    alone: &std::path::Path,
) {
    let out = d.join("farm");
    let o = restauro_tests::client(&["fetch", id, "--out", out.to_str().unwrap()], url, token);
    assert!(o.status.success(), "{}", restauro_tests::text(&o));
    restauro_tests::assert_identical(
        &restauro_tests::exr_pixels(&out.join("aosta.exr")),
        &restauro_tests::exr_pixels(&alone.join("aosta.exr")),
    );
}

/// Terminates every session of database `db` but the caller's, as an operator's
/// `pg_terminate_backend` or a pooler's restart does; how many it ended.
fn terminate_sessions(admin: &str, db: &str) -> u64 {
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    runtime.block_on(async {
        let (client, connection) =
            tokio_postgres::connect(admin, tokio_postgres::NoTls).await.unwrap();
        tokio::spawn(connection);
        let sql = "SELECT count(pg_terminate_backend(pid)) FROM pg_stat_activity
                   WHERE datname = $1 AND pid <> pg_backend_pid()";
        client.query_one(sql, &[&db]).await.unwrap().get::<_, i64>(0) as u64
    })
}

/// The coordinator's database sessions terminated again and again while a job runs, until it
/// has ended: a call that finds its connection gone connects again and runs once more, a write
/// that still fails is retried by its worker, assembly waits for the store, and the image is
/// the one process renders.
#[test]
fn terminated_database_sessions_lose_no_tile() {
    let Some(url) = restauro_tests::fleet::database("terminated") else { return };
    let admin = std::env::var("RESTAURO_TEST_POSTGRES").unwrap();
    let db = url.rsplit('/').next().unwrap().split('?').next().unwrap().to_owned();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = restauro_tests::aosta_scene(d, 192, 108);
    let options = ["--spp", "16", "--tile", "16"];
    let alone = render_alone(d, &scene, &options);
    let c =
        restauro_tests::Coordinator::start(d, &d.join("data"), "127.0.0.1:0", &["--store", &url]);
    let _workers: Vec<restauro_tests::Worker> =
        (1..=2).map(|i| restauro_tests::Worker::start(d, &c.url, &format!("w{i}"), &[])).collect();
    let (token, _) = restauro_tests::token_files(d);
    let id = submitted(&scene, &options, &c.url, &token);
    // Sessions are terminated every 30 ms until the job has ended, its assembly included.
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let terminator = {
        let (done, admin, db) = (done.clone(), admin.clone(), db.clone());
        std::thread::spawn(move || {
            let mut ended = 0;
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                ended += terminate_sessions(&admin, &db);
                std::thread::sleep(std::time::Duration::from_millis(30));
            }
            ended
        })
    };
    let o = restauro_tests::client(&["watch", &id], &c.url, &token);
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    let ended = terminator.join().unwrap();
    assert!(restauro_tests::text(&o).contains("done"), "{}", restauro_tests::text(&o));
    assert!(ended >= 1, "no session of the coordinator's was ever open to terminate");
    fetched_is_alone(d, &id, &c.url, &token, &alone);
    let log = std::fs::read_to_string(d.join("coordinator.log")).unwrap();
    eprintln!(
        "{ended} sessions terminated; the coordinator logged {} store errors",
        log.matches("cannot be written").count() + log.matches("could not store").count()
    );
}

/// Two coordinators on one database (issue 40, item 2): while one leads, the other cannot take
/// the lead, and is told who holds it and for how long; once the lead lapses (by the database's
/// clock) the other takes it under a greater epoch, which is also its run's epoch; from then on
/// a write of the one that lost it is refused, naming both epochs, and its renewal fails, while
/// the new leader's writes land.
#[test]
fn a_write_under_a_lapsed_lead_is_refused() {
    use restauro_farm::store::{LeadAttempt, StoreError};
    let Some(url) = restauro_tests::fleet::database("fencing") else { return };
    let (a, b) = (Store::connect(&url).unwrap(), Store::connect(&url).unwrap());
    let ttl = std::time::Duration::from_millis(1500);
    let LeadAttempt::Led { epoch: first } = a.try_lead("a", ttl).unwrap() else {
        panic!("the free lead was not taken")
    };
    assert_eq!(a.begin_run([1; 32]).unwrap().1, first, "the run's epoch is the lead's");
    a.put_job("j", b"by a").unwrap();
    match b.try_lead("b", ttl).unwrap() {
        LeadAttempt::HeldBy { holder, for_ms } => {
            assert_eq!(holder, "a");
            assert!(for_ms > 0 && for_ms <= 1500, "{for_ms} ms left of a 1500 ms lead");
        }
        led => panic!("a held lead was taken: {led:?}"),
    }
    assert!(a.renew_lead("a", first, ttl).unwrap(), "the leader could not renew");
    std::thread::sleep(ttl + std::time::Duration::from_millis(200));
    let LeadAttempt::Led { epoch: second } = b.try_lead("b", ttl).unwrap() else {
        panic!("a lapsed lead was not taken")
    };
    assert!(second > first, "epoch {second} after {first}");
    let refused = a.put_job("j", b"stale").unwrap_err();
    assert!(
        matches!(refused, StoreError::Fenced { ours, current, .. } if ours == first && current == second),
        "{refused:?}"
    );
    let message = refused.to_string();
    assert!(
        message.contains(&format!("epoch {first}")) && message.contains(&format!("epoch {second}")),
        "{message}"
    );
    assert!(a.put_tiles(&[("j", 0, b"stale")]).is_err(), "a stale tile was written");
    assert!(a.begin_run([1; 32]).is_err(), "a stale run began");
    assert!(!a.renew_lead("a", first, ttl).unwrap(), "a lost lead was renewed");
    b.put_job("j", b"by b").unwrap();
    assert_eq!(b.jobs().unwrap(), vec![("j".to_owned(), b"by b".to_vec())]);
    assert!(b.finished_tiles("j").unwrap().is_empty());
    assert_eq!(b.begin_run([2; 32]).unwrap().1, second);
    // Given up, the lead is free at once.
    b.release_lead("b", second).unwrap();
    assert!(matches!(a.try_lead("a", ttl).unwrap(), LeadAttempt::Led { epoch } if epoch > second));
}

/// The object store on a real S3-compatible server (issue 40, item 3): a file put is fetched
/// back whole — a small one in one request, one of 40 MiB in parts — and an object never put is
/// reported missing, leaving no file behind.
#[test]
fn files_put_in_the_object_store_are_fetched_back_whole() {
    use restauro_farm::objects::Objects;
    let Some(url) = restauro_tests::fleet::objects("objects") else { return };
    let dir = tempfile::tempdir().unwrap();
    let objects = Objects::open(Some(&url)).unwrap();
    assert!(objects.is_shared());
    let small: Vec<u8> = (0..100_000u32).flat_map(|i| i.to_le_bytes()).collect();
    let large: Vec<u8> = (0..10_000_000u32).flat_map(|i| (i ^ 0x5a5a).to_le_bytes()).collect();
    for (name, bytes) in [("small", &small), ("large", &large)] {
        let sent = dir.path().join(format!("{name}.sent"));
        std::fs::write(&sent, bytes).unwrap();
        objects.put_file(&format!("test/{name}"), &sent).unwrap();
        let back = dir.path().join("back").join(name);
        assert!(objects.fetch(&format!("test/{name}"), &back).unwrap(), "{name} not found");
        assert!(std::fs::read(&back).unwrap() == *bytes, "{name} came back different");
    }
    let never = dir.path().join("never");
    assert!(!objects.fetch("test/never-put", &never).unwrap());
    assert!(!never.exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path().join("back")).unwrap().collect();
    assert_eq!(leftovers.len(), 2, "{leftovers:?}");
}

/// A bucket that does not exist, or credentials the server refuses, stop the coordinator at
/// its start with a message naming the URL and what to check.
#[test]
fn an_object_store_that_cannot_be_reached_is_refused_at_the_start() {
    use restauro_farm::objects::Objects;
    let Some(url) = restauro_tests::fleet::objects("unreachable") else { return };
    let bucket = url.strip_prefix("s3://").unwrap().split('/').next().unwrap();
    let wrong = url.replacen(bucket, "no-such-bucket-for-restauro", 1);
    let Err(e) = Objects::open(Some(&wrong)) else { panic!("a missing bucket was taken") };
    let message = e.to_string();
    assert!(message.contains(&wrong) && message.contains("the bucket exists"), "{message}");
    let Err(e) = Objects::open(Some("s3:/nothing")) else { panic!("a malformed URL was taken") };
    assert!(e.to_string().contains("s3://BUCKET[/PREFIX]"), "{e}");
}

/// The coordinator's database restarted in the middle of a job (issue 40, item 6): every
/// session is cut and the server refuses connections for a moment. The coordinator keeps its
/// lead (the restart is shorter than its step-down), its writes fail and are retried, workers
/// keep their results until acknowledged; the job ends, each tile rendered once, and the image
/// is the one process renders.
#[test]
fn a_restarted_database_loses_no_tile_and_renders_none_twice() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let Some(postgres) = restauro_tests::fleet::OwnPostgres::start("pgrestart", d) else { return };
    let scene = restauro_tests::aosta_scene(d, 192, 108);
    let options = ["--spp", "64", "--tile", "16"];
    let alone = render_alone(d, &scene, &options);
    let no_checks = ["--check-rate", "0", "--check-rate-new", "0"];
    let mut c = restauro_tests::Coordinator::start(
        d,
        &d.join("data"),
        "127.0.0.1:0",
        &[&["--store", &postgres.url][..], &no_checks].concat(),
    );
    let logs: Vec<_> = (1..=2).map(|i| d.join(format!("tiles-{i}.log"))).collect();
    let _workers: Vec<restauro_tests::Worker> = logs
        .iter()
        .enumerate()
        .map(|(i, log)| {
            let name = format!("w{}", i + 1);
            restauro_tests::Worker::start(d, &c.url, &name, &["--tile-log", log.to_str().unwrap()])
        })
        .collect();
    let (token, _) = restauro_tests::token_files(d);
    let id = submitted(&scene, &options, &c.url, &token);
    let rendered = || restauro_tests::tiles_rendered(&logs, &id);
    let deadline = std::time::Instant::now() + restauro_tests::patience();
    while rendered().len() < 12 {
        assert!(std::time::Instant::now() < deadline, "no progress: {}", restauro_tests::logs(d));
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let total = 12 * 7;
    assert!(rendered().len() < total as usize, "the job ended before the restart");
    postgres.restart();
    let o = restauro_tests::client(&["watch", &id], &c.url, &token);
    assert!(restauro_tests::text(&o).contains("done"), "{}", restauro_tests::text(&o));
    assert!(c.child.try_wait().unwrap().is_none(), "the coordinator stopped");
    let mut tiles = rendered();
    tiles.sort_unstable();
    assert_eq!(tiles, (0..total).collect::<Vec<u32>>(), "each tile rendered once");
    fetched_is_alone(d, &id, &c.url, &token, &alone);
}

/// Whether each session of database `db` is encrypted, by its `application_name`, as the
/// server sees it (`pg_stat_ssl`).
fn encrypted_sessions(admin: &str, db: &str) -> std::collections::BTreeMap<String, bool> {
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    runtime.block_on(async {
        let (client, connection) =
            tokio_postgres::connect(admin, tokio_postgres::NoTls).await.unwrap();
        tokio::spawn(connection);
        let sql = "SELECT a.application_name, s.ssl FROM pg_stat_ssl s
                   JOIN pg_stat_activity a USING (pid) WHERE a.datname = $1";
        let rows = client.query(sql, &[&db]).await.unwrap();
        rows.iter().map(|r| (r.get(0), r.get(1))).collect()
    })
}

/// TLS to PostgreSQL as libpq's `sslmode` says (issue 40), against a server whose certificate
/// an authority of the test's own signed: `verify-full` with that authority connects,
/// encrypted; against the system's authorities, or for a host name the certificate does not
/// name, it is refused, saying what to give; `verify-ca` takes any name; `require` and the
/// default encrypt without checking; `disable` does not encrypt; a client certificate
/// (`sslcert`, `sslkey`) logs in a role the server authenticates by certificate.
#[test]
fn the_store_speaks_tls_as_sslmode_says_and_checks_the_certificate_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let Some(postgres) = restauro_tests::fleet::OwnPostgres::start("tls", dir.path()) else {
        return;
    };
    let ca = postgres.authority();
    let ca = ca.to_str().unwrap();
    let port = restauro_tests::fleet::server_addr(&postgres.url).port();
    let url = |host: &str, params: &str| {
        format!("postgres://restauro:restauro@{host}:{port}/restauro?{params}")
    };
    let mut open = Vec::new();
    for (name, host, params) in [
        ("full", "localhost", format!("sslmode=verify-full&sslrootcert={ca}")),
        ("full-ip", "127.0.0.1", format!("sslmode=verify-full&sslrootcert={ca}")),
        ("ca", "wrong.invalid", format!("hostaddr=127.0.0.1&sslmode=verify-ca&sslrootcert={ca}")),
        ("require", "127.0.0.1", "sslmode=require".to_owned()),
        ("default", "127.0.0.1", String::new()),
        ("disable", "127.0.0.1", "sslmode=disable".to_owned()),
    ] {
        let url = url(host, &format!("application_name={name}&{params}"));
        let store = Store::connect(&url).unwrap_or_else(|e| panic!("{url}: {e}"));
        store.put_job(name, b"kept").unwrap();
        open.push(store);
    }
    let admin = postgres.url.replace("/restauro", "/postgres");
    let seen = encrypted_sessions(&admin, "restauro");
    let expected: std::collections::BTreeMap<String, bool> = [
        ("full", true),
        ("full-ip", true),
        ("ca", true),
        ("require", true),
        ("default", true),
        ("disable", false),
    ]
    .into_iter()
    .map(|(name, tls)| (name.to_owned(), tls))
    .collect();
    assert_eq!(seen, expected);
    assert_eq!(open[0].jobs().unwrap().len(), 6);
    for (why, url, said) in [
        (
            "an authority the system does not trust",
            url("localhost", "sslmode=verify-full"),
            ["UnknownIssuer", "sslrootcert=PATH"],
        ),
        (
            "a name the certificate does not give",
            url(
                "wrong.invalid",
                &format!("hostaddr=127.0.0.1&sslmode=verify-full&sslrootcert={ca}"),
            ),
            ["not valid for name \"wrong.invalid\"", "sslmode=verify-ca"],
        ),
    ] {
        let Err(e) = Store::connect(&url) else { panic!("{why} was taken") };
        let e = e.to_string();
        assert!(said.iter().all(|s| e.contains(s)), "{why}: {e}");
        assert!(!e.contains("restauro:restauro@"), "the password is shown: {e}");
    }
    // A role the server authenticates by client certificate alone: in with it, refused
    // without it.
    let (cert, key) = postgres.client_certificate();
    let by_cert = format!(
        "postgres://restauro_cert@localhost:{port}/restauro_cert?sslmode=verify-full&sslrootcert={ca}"
    );
    let with_cert = format!("{by_cert}&sslcert={}&sslkey={}", cert.display(), key.display());
    let store = Store::connect(&with_cert).unwrap_or_else(|e| panic!("{with_cert}: {e}"));
    store.put_job("c", b"by certificate").unwrap();
    assert_eq!(store.jobs().unwrap().len(), 1);
    let Err(e) = Store::connect(&by_cert) else {
        panic!("a login without its certificate was taken")
    };
    assert!(e.to_string().contains("requires a valid client certificate"), "{e}");
}

/// The object store filled up in the middle of a job (issue 40, item 6): its bucket, over its
/// quota, refuses every put as a full store does. An upload meanwhile is refused, naming the
/// object store, and nothing of it is kept; the job, its tiles all in, waits in assembly with
/// the problem shown (`restauro jobs`, `/readyz`, the metric) rather than fail; once there is
/// room it ends by itself, each tile rendered once, the image the one process renders.
#[test]
fn a_full_object_store_holds_the_job_until_it_has_room_and_loses_nothing() {
    use restauro_tests::{client, http_get, patience, sample, text, wait_for, wire};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let Some(s3) = restauro_tests::fleet::OwnS3::start("full", d) else { return };
    let scene = restauro_tests::aosta_scene(d, 96, 54);
    let options = ["--spp", "2", "--tile", "16"];
    let alone = render_alone(d, &scene, &options);
    let endpoint = format!("AWS_ENDPOINT_URL={}", s3.endpoint);
    let c = restauro_tests::Coordinator::start_under(
        &["env", &endpoint],
        d,
        &d.join("data"),
        "127.0.0.1:0",
        &["--objects", "s3://restauro/farm", "--metrics-listen", "127.0.0.1:0"],
    );
    let metrics = c.metrics.clone().unwrap();
    let (token, _) = restauro_tests::token_files(d);
    // Its files in the bucket, the job waits for a worker while the bucket fills.
    let id = submitted(&scene, &options, &c.url, &token);
    s3.fill();
    let log = d.join("tiles.log");
    let _worker =
        restauro_tests::Worker::start(d, &c.url, "w", &["--tile-log", log.to_str().unwrap()]);
    wait_for("the object store's problem to be shown", patience(), || {
        sample(&http_get(&metrics, "/metrics").1, "restauro_objects_failing") == 1.0
    });
    let (status, body) = http_get(&metrics, "/readyz");
    assert!(
        status == 503 && body.contains("the object store s3://restauro/farm cannot be written"),
        "{status} {body}"
    );
    let listed = text(&client(&["jobs"], &c.url, &token));
    assert!(listed.contains("cannot be written"), "{listed}");
    let line = listed.lines().find(|l| l.contains(&id)).unwrap_or_else(|| panic!("{listed}"));
    assert!(!line.contains("failed") && !line.contains("done"), "{line}");
    // A new file is refused while the bucket is full, and is not kept.
    let data = vec![7u8; 1000];
    let reference = format!("blake3:{}.bin", blake3::hash(&data).to_hex());
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let refused = runtime.block_on(async {
        let mut render = wire::render_client(&c.url).await;
        wire::upload_bytes(&mut render, &reference, &data).await
    });
    let refused = refused.expect_err("an upload to a full bucket was acknowledged");
    assert_eq!(refused.code(), tonic::Code::Unavailable, "{refused:?}");
    assert!(refused.message().contains("the object store s3://restauro/farm"), "{refused:?}");
    let hash = blake3::hash(&data).to_hex().to_string();
    let kept: Vec<String> = std::fs::read_dir(d.join("data/assets"))
        .unwrap()
        .flatten()
        .map(|f| f.file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains(&hash))
        .collect();
    assert!(kept.is_empty(), "the refused upload left {kept:?}");
    // Room made: the same job ends by itself.
    s3.free();
    let o = client(&["watch", &id], &c.url, &token);
    assert!(text(&o).contains("done"), "{}", text(&o));
    let mut tiles = restauro_tests::tiles_rendered(&[log], &id);
    tiles.sort_unstable();
    assert_eq!(tiles, (0..24).collect::<Vec<u32>>(), "each tile rendered once");
    fetched_is_alone(d, &id, &c.url, &token, &alone);
}
