//! Editing a scene from the page: each edit (`restauro_scene::edit::Edit`) makes a new revision
//! through [`Farm::edit_scene`], checked as a scene file is and refused with the same messages;
//! the answer is the new revision's view, so the page redraws from what the server keeps. That
//! view is built from the scene the farm loaded to check the revision
//! ([`Revised`](restauro_farm::farm::Revised)): an edit loads the whole scene once. The
//! shipped spectra are listed for the material panel's library.
//!
//! The page holds positions in the preview's frame (Y up, offset removed): a saved view's
//! pose is turned back into the world's here, the one place that knows both.

use super::Studio;
use super::api::{parse, revision, scene_id};
use super::appearance::appearance;
use super::preview::{pose_to_world, to_world};
use crate::error::{Result, StudioError};
use axum::Json;
use axum::body::Bytes;
use axum::extract::{Path, RawQuery, State};
use axum::response::{IntoResponse, Response};
use restauro_farm::farm::RevisionInfo;
use restauro_scene::edit::{self, Edit, SaveAnnotation, SaveView};
use restauro_scene::scene_file::View;
use restauro_spectral::library;
use serde::{Deserialize, Serialize};
use std::sync::{Arc, OnceLock};

/// `POST /api/scenes/{id}/edits`: one edit; the new revision's view.
pub async fn edit(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Bytes,
) -> Result<Response> {
    let id = scene_id(&id)?;
    let mut edit = parse_edit(&body)?;
    if matches!(edit, Edit::SaveView(_) | Edit::SaveAnnotation(_)) {
        let offset = studio.previews.get(&studio.farm, id, None).await?.view.offset_m;
        to_world_edit(&mut edit, offset);
    }
    let made = studio.farm.edit_scene(id, &edit).await?;
    let preview = studio.previews.revised(&studio.farm, id, made).await?;
    Ok(Json(&preview.view).into_response())
}

/// The positions of a view or a note, sent in the preview's frame, in the world's.
fn to_world_edit(edit: &mut Edit, offset: [f64; 3]) {
    match edit {
        Edit::SaveView(SaveView { view }) => {
            *view = View::at(std::mem::take(&mut view.name), pose_to_world(&view.pose(), offset));
        }
        Edit::SaveAnnotation(SaveAnnotation { annotation }) => {
            annotation.position = to_world(annotation.position, offset);
            annotation.pose = annotation.pose.take().map(|p| pose_to_world(&p, offset));
        }
        _ => {}
    }
}

/// An edit from its JSON, refused naming the field that does not parse. serde reads an
/// internally tagged enum through a buffer that loses the path, so the kind is read first and
/// its fields then parsed as the kind's own type.
fn parse_edit(body: &[u8]) -> Result<Edit> {
    let refuse = |problem: String| StudioError::Request(format!("the edit: {problem}"));
    let mut json: serde_json::Value =
        serde_json::from_slice(body).map_err(|e| refuse(e.to_string()))?;
    let kinds = edit::KINDS.join(", ");
    let kind = match json.as_object_mut().and_then(|o| o.remove("edit")) {
        Some(serde_json::Value::String(k)) => k,
        _ => return Err(refuse(format!("give `edit`, the kind of edit: one of {kinds}"))),
    };
    let fields = serde_json::to_vec(&json).map_err(|e| refuse(e.to_string()))?;
    let what = format!("the {kind} edit");
    Ok(match kind.as_str() {
        "material" => Edit::Material(parse(&fields, &what)?),
        "sun" => Edit::Sun(parse(&fields, &what)?),
        "save-view" => Edit::SaveView(parse(&fields, &what)?),
        "delete-view" => Edit::DeleteView(parse(&fields, &what)?),
        "save-annotation" => Edit::SaveAnnotation(parse(&fields, &what)?),
        "delete-annotation" => Edit::DeleteAnnotation(parse(&fields, &what)?),
        "save-variant" => Edit::SaveVariant(parse(&fields, &what)?),
        "rename-variant" => Edit::RenameVariant(parse(&fields, &what)?),
        "delete-variant" => Edit::DeleteVariant(parse(&fields, &what)?),
        "save-light" => Edit::SaveLight(parse(&fields, &what)?),
        "delete-light" => Edit::DeleteLight(parse(&fields, &what)?),
        "save-grid" => Edit::SaveGrid(parse(&fields, &what)?),
        "rename-grid" => Edit::RenameGrid(parse(&fields, &what)?),
        "delete-grid" => Edit::DeleteGrid(parse(&fields, &what)?),
        other => {
            let other = other.chars().take(40).collect::<String>();
            return Err(refuse(format!("unknown kind `{}`; use {kinds}", other.escape_debug())));
        }
    })
}

/// `POST /api/scenes/{id}/photometry?name=FILE.ies` (or `.ldt`), the file as the body: read
/// as a scene reads it and kept; its reference (for a light's `ies`) and what it says (flux,
/// peak intensity, beam angle).
pub async fn photometry(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
    body: Bytes,
) -> Result<Json<restauro_farm::farm::PhotometryInfo>> {
    studio.farm.scene_revision(scene_id(&id)?, None)?;
    let name = super::api::query_value(query.as_deref(), "name").unwrap_or_default();
    let farm = studio.farm.clone();
    let info = tokio::task::spawn_blocking(move || farm.keep_photometry(&name, &body)).await??;
    Ok(Json(info))
}

/// `POST /api/scenes?name=NAME[&scene=PATH]`, a scene folder as a tar or a zip (or a bundle archive from `restauro
/// scene bundle --out`) as the body: bundled, checked and sent to the farm with a quick preview
/// render; that job, whose scene the studio then holds.
pub async fn open_folder(
    State(studio): State<Arc<Studio>>,
    RawQuery(query): RawQuery,
    body: Bytes,
) -> Result<Json<OpenedFolder>> {
    let name = super::api::query_value(query.as_deref(), "name").unwrap_or_else(|| "scene".into());
    let chosen = super::api::query_value(query.as_deref(), "scene");
    let (job, scene) = studio.farm.open_folder(&name, chosen, body.to_vec()).await?;
    Ok(Json(OpenedFolder { job, scene }))
}

/// A scene folder taken: its preview job and the scene's id.
#[derive(Serialize)]
pub struct OpenedFolder {
    pub job: restauro_farm::job::JobStatus,
    pub scene: String,
}

/// A measured reflectance the studio was sent: its reference (for a material edit's `file`), and
/// what it is, as the material panel shows a spectrum.
#[derive(Serialize)]
pub struct SpectrumInfo {
    pub reference: String,
    pub file_name: String,
    /// ρ(λ) at 380, 385, … 780 nm.
    pub reflectance: Vec<f32>,
    pub lab: [f64; 3],
    pub colour_linear_srgb: [f32; 3],
    /// What reading it found worth saying (a range held at its ends, say).
    pub notes: Vec<String>,
}

/// The largest spectrum file the studio takes, in bytes.
pub const MAX_SPECTRUM_BYTES: usize = 1 << 20;

/// `POST /api/scenes/{id}/spectrum?name=FILE.csv[&extrapolate=true]`, a measured reflectance as
/// CSV (nm, value 0–1; the format `[spectra]` files have) as the body: read as a scene reads it,
/// refused in the reader's words naming the file and line, else kept.
pub async fn spectrum(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
    body: Bytes,
) -> Result<Json<SpectrumInfo>> {
    use restauro_spectral::csv::{Quantity, load};
    use restauro_spectral::tabulated::Coverage;
    studio.farm.scene_revision(scene_id(&id)?, None)?;
    let name = super::api::query_value(query.as_deref(), "name").unwrap_or_default();
    let extrapolate =
        super::api::query_value(query.as_deref(), "extrapolate").as_deref() == Some("true");
    restauro_farm::farm::sent_file(&name, &body, &["csv", "txt"], MAX_SPECTRUM_BYTES)?;
    let text = std::str::from_utf8(&body)
        .map_err(|_| StudioError::Request(format!("{name}: not UTF-8 text")))?;
    let coverage = if extrapolate { Coverage::HoldEnds } else { Coverage::Require };
    let loaded = load(text, &name, Quantity::Reflectance, coverage)
        .map_err(|e| StudioError::Request(e.to_string()))?;
    let reference = studio.farm.keep_file(&name, &body, "csv")?;
    let (lab, colour_linear_srgb) = appearance(&loaded.spectrum);
    Ok(Json(SpectrumInfo {
        reference,
        file_name: name,
        reflectance: loaded.spectrum.0.to_vec(),
        lab,
        colour_linear_srgb,
        notes: loaded.notes.iter().map(ToString::to_string).collect(),
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Revert {
    revision: u32,
}

/// `POST /api/scenes/{id}/revert {"revision": N}`: revision N made the latest again (as a new
/// revision: nothing is lost); the new revision's view.
pub async fn revert(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    body: Bytes,
) -> Result<Response> {
    let id = scene_id(&id)?;
    let Revert { revision } = parse(&body, "the revert request")?;
    let made = studio.farm.revert_scene(id, revision).await?;
    let preview = studio.previews.revised(&studio.farm, id, made).await?;
    Ok(Json(&preview.view).into_response())
}

/// `GET /api/scenes/{id}/revisions`: every revision, the first job's (0) first.
pub async fn revisions(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
) -> Result<Json<Vec<RevisionInfo>>> {
    Ok(Json(studio.farm.revisions(scene_id(&id)?)?))
}

/// `GET /api/scenes/{id}/scene.json?revision=N`: the revision's canonical scene (every file
/// named by its hash), as a worker receives it.
pub async fn manifest(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let (_, manifest) = studio.farm.scene_revision(scene_id(&id)?, revision(query.as_deref())?)?;
    Ok(([(axum::http::header::CONTENT_TYPE, "application/json")], manifest).into_response())
}

/// `GET /api/scenes/{id}/download?revision=N`: the revision as a scene folder (`scene.toml`
/// and its files) in a tar, to check and render with the command line.
pub async fn download(
    State(studio): State<Arc<Studio>>,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response> {
    let id = scene_id(&id)?;
    let (name, tar) = studio.farm.scene_folder(id, revision(query.as_deref())?).await?;
    let disposition = format!("attachment; filename=\"{name}.tar\"");
    let headers = [
        (axum::http::header::CONTENT_TYPE, "application/x-tar".to_owned()),
        (axum::http::header::CONTENT_DISPOSITION, disposition),
    ];
    Ok((headers, tar).into_response())
}

/// A shipped spectrum, as the library panel lists it.
#[derive(Serialize)]
pub struct LibrarySpectrum {
    pub name: String,
    /// What it is of (the file's `# material:` line).
    pub material: String,
    /// ρ(λ) at 380, 385, … 780 nm.
    pub reflectance: Vec<f32>,
    /// CIE 1976 L*a*b* under D65 (2° observer).
    pub lab: [f64; 3],
    pub colour_linear_srgb: [f32; 3],
}

/// Every shipped reflectance, loaded once.
fn shipped() -> &'static [LibrarySpectrum] {
    static SHIPPED: OnceLock<Vec<LibrarySpectrum>> = OnceLock::new();
    SHIPPED.get_or_init(|| {
        library::names()
            .filter_map(|name| {
                let loaded = library::load_reflectance(name).ok()?;
                let (lab, colour_linear_srgb) = appearance(&loaded.spectrum);
                Some(LibrarySpectrum {
                    name: name.to_owned(),
                    material: library::material(name).unwrap_or("").to_owned(),
                    reflectance: loaded.spectrum.0.to_vec(),
                    lab,
                    colour_linear_srgb,
                })
            })
            .collect()
    })
}

/// `GET /api/spectra`: the shipped reflectance spectra, each with its curve and colour.
pub async fn spectra() -> Result<Json<&'static [LibrarySpectrum]>> {
    let all = tokio::task::spawn_blocking(shipped).await?;
    Ok(Json(all))
}

/// The sun over one day at a site, for the page's sun-path chart.
#[derive(Serialize)]
pub struct SunPathPoint {
    /// Local time, `HH:MM`.
    pub time: String,
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

/// `GET /api/sun-path?latitude_deg=…&longitude_deg=…&date=YYYY-MM-DD&utc_offset=+01:00`: where
/// the sun is every 15 minutes of that local day, by the same solar position algorithm the
/// render uses (NREL SPA).
pub async fn sun_path(RawQuery(query): RawQuery) -> Result<Json<Vec<SunPathPoint>>> {
    let field = |name: &str| -> Result<String> {
        super::api::query_value(query.as_deref(), name)
            .ok_or_else(|| StudioError::Request(format!("{name}: missing from the query")))
    };
    let number = |name: &str| -> Result<f64> {
        field(name)?
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| StudioError::Request(format!("{name}: not a number of degrees")))
    };
    let (latitude, longitude) = (number("latitude_deg")?, number("longitude_deg")?);
    if !(-90.0..=90.0).contains(&latitude) || !(-180.0..=180.0).contains(&longitude) {
        return Err(StudioError::Request(
            "latitude_deg must be within ±90 and longitude_deg within ±180".into(),
        ));
    }
    let (date, offset) = (field("date")?, field("utc_offset")?);
    let site = restauro_scene::sun::Site::new(latitude, longitude, 0.0);
    let mut out = Vec::new();
    for quarter in 0..96 {
        let time = format!("{:02}:{:02}", quarter / 4, quarter % 4 * 15);
        let at = format!("{date}T{time}:00{offset}");
        let p = restauro_scene::sun::sun_position(site, &at, None)
            .map_err(|e| StudioError::Request(format!("date, utc_offset: {e}")))?;
        out.push(SunPathPoint { time, azimuth_deg: p.azimuth_deg, elevation_deg: p.elevation_deg });
    }
    Ok(Json(out))
}
