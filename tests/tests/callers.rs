//! What one caller can hold of a coordinator (issue 35), against a real coordinator process
//! with hand-written hostile callers: readers that never read, an upload that announces a
//! gigabyte and sends nothing, connections that never say a word.

use restauro_proto as pb;
use restauro_tests::raw::{Head, Raw, memory_kb, read_to_end};
use restauro_tests::{CLIENT_TOKEN, Coordinator, WORKER_TOKEN, wire};
use std::time::Duration;

/// `n` bytes that do not compress, and their asset reference.
fn asset(n: usize) -> (String, Vec<u8>) {
    let data: Vec<u8> =
        (0..n as u64).map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8).collect();
    (format!("blake3:{}.bin", blake3::hash(&data).to_hex()), data)
}

const FETCH_ASSET: &str = "/restauro.v1.Work/FetchAsset";
const UPLOAD_ASSET: &str = "/restauro.v1.Render/UploadAsset";
const RESOURCE_EXHAUSTED: i32 = 8;
const DEADLINE_EXCEEDED: i32 = 4;

/// Finding 1 (HIGH): readers that ask for a file and never open their window. Before, each such
/// stream pinned about 6.5 MiB and nothing limited their number (500 aborted the process).
/// Now 8 connections × 64 such requests for a 16 MiB asset: at most `--max-downloads` (32) are
/// sent, the rest refused at once naming the flag; the coordinator's memory grows by less than
/// 64 MiB; an honest client is served meanwhile; and after `--idle-timeout-s` the silent readers
/// lose their streams (ended with why, should they read again) and an honest worker fetches the
/// file.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn readers_that_never_read_hold_little_and_lose_their_streams() {
    let dir = tempfile::tempdir().unwrap();
    let coordinator = Coordinator::start(
        dir.path(),
        &dir.path().join("data"),
        "127.0.0.1:0",
        &["--idle-timeout-s", "4"],
    );
    let pid = coordinator.child.id();
    let mut client = wire::render_client(&coordinator.url).await;
    let (reference, data) = asset(16 << 20);
    wire::upload_bytes(&mut client, &reference, &data).await.unwrap();
    let mut work = wire::work_client(&coordinator.url).await;
    let session = wire::register(&mut work, "honest").await;
    let request =
        pb::FetchAssetRequest { session: Some(session.clone()), reference: reference.clone() };
    let (before, _) = memory_kb(pid);
    let (mut held, mut refused) = (Vec::new(), 0);
    for _ in 0..8 {
        let mut raw = Raw::connect(&coordinator.url).await;
        for _ in 0..64 {
            match raw.call(FETCH_ASSET, WORKER_TOKEN, &request, true).await.unwrap().0 {
                Head::Streaming(body) => held.push(body),
                Head::Refused(code, message) => {
                    assert_eq!(code, RESOURCE_EXHAUSTED, "{message}");
                    assert!(message.contains("--max-downloads"), "{message}");
                    refused += 1;
                }
            }
        }
        // The connection's streams stay open as long as the test holds `held`.
        std::mem::forget(raw);
    }
    tokio::time::sleep(Duration::from_millis(800)).await;
    let (during, _) = memory_kb(pid);
    let grown_mib = (during.saturating_sub(before)) as f64 / 1024.0;
    eprintln!(
        "{} streams sent, {refused} refused; the coordinator's memory {:.0} → {:.0} MiB (+{grown_mib:.1})",
        held.len(),
        before as f64 / 1024.0,
        during as f64 / 1024.0
    );
    assert_eq!(held.len(), 32, "--max-downloads's default");
    assert!(grown_mib < 64.0, "512 readers that never read cost {grown_mib:.0} MiB");
    // An honest client is answered meanwhile.
    client.list_jobs(pb::ListJobsRequest {}).await.unwrap();
    // After the idle timeout the silent readers' streams are cut and their places free: an
    // honest worker fetches the whole file.
    tokio::time::sleep(Duration::from_secs(6)).await;
    let mut stream = work.fetch_asset(request.clone()).await.unwrap().into_inner();
    let mut fetched = Vec::new();
    while let Some(chunk) = stream.message().await.unwrap() {
        fetched.extend_from_slice(&chunk.data);
    }
    assert!(fetched == data, "the honest fetch got {} bytes", fetched.len());
    // A reader that stops after its first bytes, on a connection of its own, and reads again
    // after the idle timeout: it gets what was sent before the cut and then why, not a file
    // that looks whole.
    let mut raw = Raw::connect(&coordinator.url).await;
    let Head::Streaming(mut body) =
        raw.call(FETCH_ASSET, WORKER_TOKEN, &request, true).await.unwrap().0
    else {
        panic!("the places were free")
    };
    let first = body.data().await.unwrap().unwrap();
    tokio::time::sleep(Duration::from_secs(6)).await;
    let _ = body.flow_control().release_capacity(first.len());
    let (bytes, status) = read_to_end(body).await;
    let (code, message) = status.expect("a status ends the stream");
    assert_eq!(code, DEADLINE_EXCEEDED, "{message}");
    assert!(
        message.contains("--idle-timeout-s") && first.len() + bytes < data.len(),
        "{} bytes: {message}",
        first.len() + bytes
    );
}

/// Finding 2 (MEDIUM): an upload that announces the whole upload budget and then sends
/// nothing. Before, it held the budget with no idle timeout, and every other upload waited for
/// its own deadline. Now it is cut after `--idle-timeout-s`, refused naming the flag, and an
/// honest upload that was waiting for room goes through.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_upload_that_stops_sending_gives_the_budget_back() {
    let dir = tempfile::tempdir().unwrap();
    let coordinator = Coordinator::start(
        dir.path(),
        &dir.path().join("data"),
        "127.0.0.1:0",
        &["--idle-timeout-s", "3", "--max-upload-mb", "64"],
    );
    let mut raw = Raw::connect(&coordinator.url).await;
    let (stalled_reference, _) = asset(1);
    let first = pb::Chunk { name: stalled_reference, total_bytes: 64 << 20, data: Vec::new() };
    // The first message, and then nothing: the request is never ended. A unary call's answer
    // comes when it ends: here, when the coordinator cuts it.
    let stalled = tokio::spawn(async move {
        let (head, stream) = raw.call(UPLOAD_ASSET, CLIENT_TOKEN, &first, false).await.unwrap();
        drop(stream);
        head
    });
    tokio::time::sleep(Duration::from_millis(300)).await;
    // Meanwhile an honest upload waits for room in the budget, and gets it.
    let mut client = wire::render_client(&coordinator.url).await;
    let (reference, data) = asset(4 << 20);
    let honest =
        tokio::spawn(async move { wire::upload_bytes(&mut client, &reference, &data).await });
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(!honest.is_finished(), "premise: the stalled upload holds the whole budget");
    match stalled.await.unwrap() {
        Head::Refused(code, message) => {
            assert_eq!(code, DEADLINE_EXCEEDED, "{message}");
            assert!(message.contains("--idle-timeout-s"), "{message}");
        }
        Head::Streaming(_) => panic!("the stalled upload was accepted"),
    }
    honest.await.unwrap().expect("the honest upload goes through once the budget is free");
}

/// Finding 5 (LOW): connections that never say a word. Before, 400 of them were never closed,
/// and no token was needed to hold them. Now each is closed at `--first-request-timeout-s`,
/// beyond `--max-connections` at once, and the coordinator serves an honest client throughout.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn connections_that_say_nothing_are_closed() {
    use tokio::io::AsyncReadExt;
    let dir = tempfile::tempdir().unwrap();
    let coordinator = Coordinator::start(
        dir.path(),
        &dir.path().join("data"),
        "127.0.0.1:0",
        &["--first-request-timeout-s", "2", "--max-connections", "300"],
    );
    let addr = coordinator.url.trim_start_matches("http://").to_owned();
    let mut client = wire::render_client(&coordinator.url).await;
    let mut silent = Vec::new();
    for _ in 0..400 {
        silent.push(tokio::net::TcpStream::connect(&addr).await.unwrap());
    }
    // Those beyond the limit are closed at once; those within it after 2 s.
    client.list_jobs(pb::ListJobsRequest {}).await.expect("an honest client is served");
    let mut all_closed = 0;
    for s in &mut silent {
        // The server speaks first (HTTP/2's SETTINGS); closed is the end of what it sends.
        let mut buf = [0u8; 256];
        let end = tokio::time::timeout(Duration::from_secs(5), async {
            loop {
                match s.read(&mut buf).await {
                    Ok(0) | Err(_) => return,
                    Ok(_) => {}
                }
            }
        });
        if end.await.is_ok() {
            all_closed += 1;
        }
    }
    assert_eq!(all_closed, 400, "connections left open");
    client.list_jobs(pb::ListJobsRequest {}).await.expect("and served still");
}

/// A limit of nothing is no limit anyone meant: each count flag refuses 0, naming itself.
#[test]
fn a_count_limit_of_zero_is_refused_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let (client, worker) = restauro_tests::token_files(dir.path());
    for flag in [
        "--max-connections",
        "--max-streams-per-connection",
        "--max-downloads",
        "--max-scene-loads",
    ] {
        let mut command =
            std::process::Command::new(restauro_tests::binary("restauro-coordinator"));
        command
            .args(["--listen", "127.0.0.1:0", "--data"])
            .arg(dir.path().join("data"))
            .arg("--client-token-file")
            .arg(&client)
            .arg("--worker-token-file")
            .arg(&worker)
            .args([flag, "0"]);
        let o = restauro_tests::output_within(&mut command, Duration::from_secs(60));
        assert!(!o.status.success(), "{flag} 0 was accepted");
        let said = restauro_tests::text(&o);
        assert!(said.contains(flag) && said.contains("must be at least 1"), "{flag}: {said}");
    }
}
