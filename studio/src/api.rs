//! The studio's JSON API under `/api/`: the same domain calls the gRPC `Render` service makes
//! ([`Farm`]), and the same refusals, with HTTP statuses (`StudioError::http_status`) and
//! a body `{"error": "<the message>"}` the page shows as it is.

use super::Studio;
use super::events::Start;
use super::views::WorkerView;
use crate::error::{Result, StudioError};
use axum::Json;
use axum::body::{Body, Bytes};
use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::sse::{Event as SseEvent, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use restauro_farm::error::FarmError;
use restauro_farm::ids::JobId;
use restauro_farm::job::JobStatus;
use serde::{Deserialize, Serialize};
use std::convert::Infallible;
use std::sync::Arc;
use tokio::sync::broadcast::error::RecvError;
use tokio_stream::wrappers::ReceiverStream;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SignIn {
    token: String,
}

/// `POST /api/session {"token": "…"}`: the client token for a session cookie. The page sends
/// it once; the cookie then goes with every request, and no script can read it.
pub async fn sign_in(
    State(studio): State<Arc<Studio>>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<Response> {
    super::session::same_origin(&headers)?;
    let SignIn { token } = serde_json::from_slice(&body).map_err(|e| {
        StudioError::Request(format!("the body must be {{\"token\": \"<client token>\"}} ({e})"))
    })?;
    let cookie = studio.gate.sign_in(token.trim())?;
    Ok(with_cookie(StatusCode::NO_CONTENT, &cookie))
}

/// `DELETE /api/session`: ends the page's session.
pub async fn sign_out(State(studio): State<Arc<Studio>>) -> Response {
    with_cookie(StatusCode::NO_CONTENT, &studio.gate.sign_out())
}

fn with_cookie(status: StatusCode, cookie: &str) -> Response {
    let mut response = status.into_response();
    if let Ok(value) = HeaderValue::from_str(cookie) {
        response.headers_mut().insert(header::SET_COOKIE, value);
    }
    response
}

#[derive(Serialize)]
pub struct Whoami {
    role: &'static str,
    /// The coordinator's own trouble (its store cannot be written), shown as a banner.
    problem: Option<String>,
}

/// `GET /api/whoami`: 200 when signed in (the page's first call), else 401.
pub async fn whoami(State(studio): State<Arc<Studio>>) -> Json<Whoami> {
    Json(Whoami { role: "client", problem: studio.farm.problem() })
}

/// `GET /api/jobs`
pub async fn jobs(State(studio): State<Arc<Studio>>) -> Json<Vec<JobStatus>> {
    Json(studio.farm.jobs())
}

/// `GET /api/jobs/{id}`
pub async fn job(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Json<JobStatus>> {
    Ok(Json(studio.farm.job(&JobId::parse(&id)?)?))
}

/// `POST /api/jobs/{id}/cancel`
pub async fn cancel(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Json<JobStatus>> {
    Ok(Json(studio.farm.cancel(&JobId::parse(&id)?)?))
}

/// `GET /api/jobs/{id}/results/{name}`: one result file of a finished job (an EXR is
/// downloaded, a PNG shown).
pub async fn result(
    State(studio): State<Arc<Studio>>,
    Path((id, name)): Path<(String, String)>,
) -> Result<Response> {
    let path = studio.farm.result_path(&JobId::parse(&id)?, &name)?;
    let file = tokio::fs::File::open(&path).await.map_err(|e| FarmError::io(&path, e))?;
    let length = file.metadata().await.map_err(|e| FarmError::io(&path, e))?.len();
    let kind = match name.rsplit('.').next() {
        Some("png") => "image/png",
        Some("exr") => "image/x-exr",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    };
    let body = Body::from_stream(tokio_util::io::ReaderStream::new(file));
    let mut response = (StatusCode::OK, body).into_response();
    let h = response.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(kind));
    h.insert(header::CONTENT_LENGTH, HeaderValue::from(length));
    if kind != "image/png" {
        // The file's own name, which the coordinator chose (`render.exr`, …): no quoting issue.
        if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
            h.insert(header::CONTENT_DISPOSITION, v);
        }
    }
    Ok(response)
}

/// `GET /api/workers`
pub async fn workers(State(studio): State<Arc<Studio>>) -> Json<Vec<WorkerView>> {
    Json(studio.farm.workers().into_iter().map(WorkerView::from).collect())
}

/// `GET /api/events`: the live events (see [`super::events`]), resumed after `Last-Event-ID`.
pub async fn events(State(studio): State<Arc<Studio>>, headers: HeaderMap) -> impl IntoResponse {
    let last = headers.get("last-event-id").and_then(|v| v.to_str().ok());
    let mut new = studio.events.subscribe();
    let Start { first, from_seq } = studio.events.start(last);
    let (tx, rx) = tokio::sync::mpsc::channel::<std::result::Result<SseEvent, Infallible>>(64);
    let (events, mut stop) = (studio.events.clone(), studio.stop.clone());
    let sse = move |e: &super::events::Event| {
        Ok(SseEvent::default().event(e.kind).id(events.id(e)).data(e.data.clone()))
    };
    tokio::spawn(async move {
        for e in &first {
            if tx.send(sse(e)).await.is_err() {
                return;
            }
        }
        loop {
            let next = tokio::select! {
                _ = stop.wait_for(|s| *s) => return,
                next = new.recv() => next,
            };
            match next {
                Ok(e) if e.seq.is_some_and(|s| s < from_seq) => {}
                Ok(e) => {
                    if tx.send(sse(&e)).await.is_err() {
                        return;
                    }
                }
                // Too slow a page: it reconnects, and is sent a snapshot or what it missed.
                Err(RecvError::Lagged(_)) | Err(RecvError::Closed) => return,
            }
        }
    });
    Sse::new(ReceiverStream::new(rx)).keep_alive(KeepAlive::default())
}

#[derive(Serialize)]
pub struct SceneEntryView {
    id: String,
    name: String,
    jobs: usize,
    /// Its latest revision.
    revision: u32,
}

/// `GET /api/scenes`: the scenes of the coordinator's jobs.
pub async fn scenes(State(studio): State<Arc<Studio>>) -> Json<Vec<SceneEntryView>> {
    let list = studio.farm.scenes().into_iter();
    Json(
        list.map(|s| SceneEntryView { id: s.id, name: s.name, jobs: s.jobs, revision: s.revision })
            .collect(),
    )
}

/// The value of `name` in a query string, decoded.
pub(super) fn query_value(query: Option<&str>, name: &str) -> Option<String> {
    form_urlencoded::parse(query?.as_bytes()).find(|(k, _)| k == name).map(|(_, v)| v.into_owned())
}

/// The revision a query asks for (`?revision=3`), the latest when it names none.
pub(super) fn revision(query: Option<&str>) -> Result<Option<u32>> {
    let Some(value) = query_value(query, "revision") else { return Ok(None) };
    value.parse::<u32>().map(Some).map_err(|_| {
        StudioError::Request(format!(
            "revision: `{}` is not a revision number (0, 1, 2, …)",
            value.chars().take(40).collect::<String>().escape_debug()
        ))
    })
}

/// A scene id from a caller: a BLAKE3 hash in hex.
pub(super) fn scene_id(text: &str) -> Result<&str> {
    if text.len() == 64 && text.bytes().all(|b| b.is_ascii_hexdigit()) {
        Ok(text)
    } else {
        Err(StudioError::Request(format!(
            "`{}` is not a scene id (64 hexadecimal digits, as /api/scenes lists them)",
            text.chars().take(80).collect::<String>().escape_debug()
        )))
    }
}

/// `GET /api/scenes/{id}`: what the page needs to show the scene: its camera, its materials
/// and their colours, the offset of its preview.
pub async fn scene(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    Ok(Json(&preview(&studio, &id, query.as_deref()).await?.view).into_response())
}

/// The preview of the revision a query names (the latest when none) of scene `id`.
async fn preview(
    studio: &Studio,
    id: &str,
    query: Option<&str>,
) -> Result<Arc<super::preview::ScenePreview>> {
    studio.previews.get(&studio.farm, scene_id(id)?, revision(query)?).await
}

/// `GET /api/scenes/{id}/preview.glb`: its geometry as glTF binary.
pub async fn scene_glb(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let preview = preview(&studio, &id, query.as_deref()).await?;
    let mut response = (StatusCode::OK, preview.glb.clone()).into_response();
    response
        .headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static("model/gltf-binary"));
    Ok(response)
}

/// `POST /api/scenes/{id}/snapshots`: renders the page's view on the farm (see
/// [`super::snapshot`]); the new job, which the events then follow.
pub async fn take_snapshot(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Bytes,
) -> Result<Json<JobStatus>> {
    let id = scene_id(&id)?;
    let request: super::snapshot::SnapshotRequest = parse(&body, "the snapshot request")?;
    let preview = studio.previews.get(&studio.farm, id, request.revision).await?;
    Ok(Json(super::snapshot::take(&studio.farm, id, &preview, request).await?))
}

/// A JSON body, refused naming the field that does not parse (`width: invalid value: …`).
pub(super) fn parse<T: serde::de::DeserializeOwned>(body: &[u8], what: &str) -> Result<T> {
    let mut json = serde_json::Deserializer::from_slice(body);
    serde_path_to_error::deserialize(&mut json).map_err(|e| {
        let path = e.path().to_string();
        let field = if path == "." { String::new() } else { format!("{path}: ") };
        StudioError::Request(format!("{what}: {field}{}", e.inner()))
    })
}
