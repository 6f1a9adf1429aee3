//! The scenes the studio shows and edits. A scene is first the bundle of a submitted job, known
//! by [`scene_identity`] (its manifest without the camera, so snapshots of it from anywhere are
//! the same scene). Every edit made in the studio makes a new revision of it: the whole
//! manifest, checked as a worker checks one, kept in the store under the scene's id and the
//! revision's number. Revision 0 is the first job's manifest; nothing is overwritten, so any
//! earlier revision can be opened again. Jobs submitted from a revision belong to its scene.

use super::{Farm, FarmState, now_unix_ms};
use crate::error::{FarmError, Result};
use crate::ids::JobId;
use restauro_scene::bundle::Bundle;
use restauro_scene::edit::Edit;
use restauro_scene::load::LoadedScene;
use restauro_scene::scene_file::SceneFile;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use tracing::info;

/// A scene's identity in the studio: the BLAKE3 hash of its canonical manifest without its
/// camera (JSON objects serialise with sorted keys, so the hash is stable).
pub fn scene_identity(manifest_json: &str) -> String {
    let text = match serde_json::from_str::<serde_json::Value>(manifest_json) {
        Ok(serde_json::Value::Object(mut scene)) => {
            scene.remove("camera");
            serde_json::Value::Object(scene).to_string()
        }
        _ => manifest_json.to_owned(),
    };
    blake3::hash(text.as_bytes()).to_hex().to_string()
}

/// A scene the coordinator holds (see [`Farm::scenes`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneEntry {
    /// The [`scene_identity`] of its first job.
    pub id: String,
    /// The name of its first job.
    pub name: String,
    pub jobs: usize,
    pub first_ms: u64,
    /// Its latest revision (0 when never edited).
    pub revision: u32,
}

/// What an edit made: the new revision (or the latest, when the edit changed nothing), and,
/// when one was made, its scene as loaded to check it, so that the caller shows it without
/// loading the whole scene again.
pub struct Revised {
    pub revision: RevisionInfo,
    pub scene: Option<LoadedScene>,
}

/// A revision as the store keeps it.
#[derive(Clone, Serialize, Deserialize)]
struct Revision {
    manifest_json: String,
    summary: String,
    created_unix_ms: u64,
}

/// What a revision was, for the page's list.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RevisionInfo {
    pub number: u32,
    pub summary: String,
    pub created_unix_ms: u64,
}

#[derive(Default)]
pub(super) struct Scenes {
    /// Revisions 1, 2, … of each edited scene, in order.
    revisions: BTreeMap<String, Vec<Revision>>,
    /// The scene that each revision's manifest identity belongs to.
    owner: HashMap<String, String>,
    /// Each job's manifest identity, worked out once.
    identity: HashMap<JobId, String>,
}

impl Scenes {
    fn add(&mut self, scene: &str, revision: Revision) {
        self.owner.insert(scene_identity(&revision.manifest_json), scene.to_owned());
        self.revisions.entry(scene.to_owned()).or_default().push(revision);
    }
}

/// The scene id `id` as a message may quote it (at most 80 characters).
fn no_such_scene(id: &str) -> FarmError {
    FarmError::NoSuchScene(id.chars().take(80).collect())
}

impl FarmState {
    /// Every job's scene id (its own identity, or the scene whose revision it was made from),
    /// with its record.
    fn jobs_by_scene(&mut self) -> Vec<(String, &crate::job::JobRecord)> {
        let FarmState { jobs, scenes, .. } = self;
        jobs.iter()
            .map(|(id, r)| {
                let identity = scenes
                    .identity
                    .entry(id.clone())
                    .or_insert_with(|| scene_identity(&r.manifest_json));
                let scene = scenes.owner.get(identity.as_str()).unwrap_or(identity).clone();
                (scene, r)
            })
            .collect()
    }

    /// The manifest of revision `number` of scene `id` (the latest when `None`), and its number.
    fn manifest(&mut self, id: &str, number: Option<u32>) -> Result<(u32, String)> {
        let latest = self.scenes.revisions.get(id).map_or(0, |r| r.len() as u32);
        let number = number.unwrap_or(latest);
        if number > latest {
            return Err(FarmError::Request(format!(
                "scene {}… has no revision {number}; its latest is {latest}",
                &id[..id.len().min(12)]
            )));
        }
        if number > 0 {
            return Ok((
                number,
                self.scenes.revisions[id][number as usize - 1].manifest_json.clone(),
            ));
        }
        let first = self
            .jobs_by_scene()
            .into_iter()
            .filter(|(scene, _)| scene == id)
            .min_by_key(|(_, r)| r.submitted_unix_ms)
            .map(|(_, r)| r.manifest_json.clone());
        Ok((0, first.ok_or_else(|| no_such_scene(id))?))
    }
}

impl Farm {
    /// Takes the scene revisions kept in the store.
    pub(super) fn resume_scenes(&self) -> Result<()> {
        let kept = self.store.revisions().map_err(FarmError::StoreAtStart)?;
        let mut st = self.lock();
        for (scene, number, bytes) in kept {
            let revision: Revision =
                serde_json::from_slice(&bytes).map_err(|e| FarmError::UnreadableRevision {
                    scene: scene.clone(),
                    number,
                    problem: e.to_string(),
                })?;
            st.scenes.add(&scene, revision);
        }
        Ok(())
    }

    /// The scenes the coordinator holds: the bundles of its jobs, one per scene whatever its
    /// camera (a studio snapshot changes only the camera) and whatever its revision, named by
    /// its first job.
    pub fn scenes(&self) -> Vec<SceneEntry> {
        let mut st = self.lock();
        let mut by_id: BTreeMap<String, SceneEntry> = BTreeMap::new();
        for (id, r) in st.jobs_by_scene() {
            let entry = by_id.entry(id.clone()).or_insert_with(|| SceneEntry {
                id,
                name: String::new(),
                jobs: 0,
                first_ms: u64::MAX,
                revision: 0,
            });
            entry.jobs += 1;
            if r.submitted_unix_ms < entry.first_ms {
                entry.first_ms = r.submitted_unix_ms;
                entry.name = r.spec.name.to_string();
            }
        }
        for entry in by_id.values_mut() {
            entry.revision = st.scenes.revisions.get(&entry.id).map_or(0, |r| r.len() as u32);
        }
        by_id.into_values().collect()
    }

    /// The canonical manifest of scene `id` (see [`Farm::scenes`]) at its latest revision,
    /// camera included.
    pub fn scene_manifest(&self, id: &str) -> Result<String> {
        Ok(self.lock().manifest(id, None)?.1)
    }

    /// The manifest of revision `number` of scene `id` (the latest when `None`), and its number.
    pub fn scene_revision(&self, id: &str, number: Option<u32>) -> Result<(u32, String)> {
        self.lock().manifest(id, number)
    }

    /// Every revision of scene `id`, the first job's (0) first.
    pub fn revisions(&self, id: &str) -> Result<Vec<RevisionInfo>> {
        let first_ms = self
            .scenes()
            .into_iter()
            .find(|s| s.id == id)
            .ok_or_else(|| no_such_scene(id))?
            .first_ms;
        let st = self.lock();
        let first =
            RevisionInfo { number: 0, summary: "as submitted".into(), created_unix_ms: first_ms };
        let later = st.scenes.revisions.get(id).into_iter().flatten();
        let later = later.enumerate().map(|(i, r)| RevisionInfo {
            number: i as u32 + 1,
            summary: r.summary.clone(),
            created_unix_ms: r.created_unix_ms,
        });
        Ok(std::iter::once(first).chain(later).collect())
    }

    /// Revision `number` of scene `id` (the latest when `None`), loaded from the store as a
    /// worker loads it, with its number.
    pub async fn load_scene(
        self: &Arc<Self>,
        id: &str,
        number: Option<u32>,
    ) -> Result<(u32, LoadedScene)> {
        let (number, manifest) = self.scene_revision(id, number)?;
        let farm = self.clone();
        let scene = self
            .loading_scene(move || -> Result<LoadedScene> {
                Ok(farm.bundle(&manifest)?.load(&farm.config.limits)?)
            })
            .await?;
        Ok((number, scene))
    }

    /// Revision `number` of scene `id` (the latest when `None`) as a scene folder in a tar
    /// (`restauro_assets::folder`), and the folder's name: `<scene>-revision-<n>`.
    pub async fn scene_folder(
        self: &Arc<Self>,
        id: &str,
        number: Option<u32>,
    ) -> Result<(String, Vec<u8>)> {
        let (number, manifest) = self.scene_revision(id, number)?;
        let scene = self.scenes().into_iter().find(|s| s.id == id).map(|s| s.name);
        let stem: String = scene
            .unwrap_or_else(|| "scene".into())
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' })
            .collect();
        let name = format!("{stem}-revision-{number}");
        let comment = format!(
            "Scene {id}, revision {number}, as the restauro studio keeps it.\n\
             `restauro scene check {name}/scene.toml` checks it; `restauro render` renders it."
        );
        let farm = self.clone();
        let folder = name.clone();
        tokio::task::spawn_blocking(move || -> Result<Vec<u8>> {
            let bundle = farm.bundle(&manifest)?;
            Ok(restauro_assets::folder::folder_tar(&bundle, &folder, &comment)?)
        })
        .await?
        .map(|tar| (name, tar))
    }

    /// Applies `edit` to the latest revision of scene `id`, making the next revision: checked
    /// as any scene is (the same messages as `scene check`), then kept. When the edit changes
    /// nothing, no revision is made and the latest is returned. The scene is parsed, not loaded,
    /// to apply the edit; the new revision is loaded once, to check it, and handed back.
    pub async fn edit_scene(self: &Arc<Self>, id: &str, edit: &Edit) -> Result<Revised> {
        let _one_at_a_time = self.editing.lock().await;
        let (_, manifest) = self.scene_revision(id, None)?;
        let mut scene = Bundle::parse_manifest(&manifest)?;
        let summary = edit.apply(&mut scene)?;
        self.keep_revision(id, scene, summary).await
    }

    /// Makes revision `number` of scene `id` its latest again, as a new revision.
    pub async fn revert_scene(self: &Arc<Self>, id: &str, number: u32) -> Result<Revised> {
        let _one_at_a_time = self.editing.lock().await;
        let (_, manifest) = self.scene_revision(id, Some(number))?;
        let scene = Bundle::parse_manifest(&manifest)?;
        self.keep_revision(id, scene, format!("back to revision {number}")).await
    }

    async fn keep_revision(
        self: &Arc<Self>,
        id: &str,
        scene: SceneFile,
        summary: String,
    ) -> Result<Revised> {
        let manifest_json = serde_json::to_string(&scene)
            .map_err(|e| FarmError::Internal(format!("the scene does not serialise: {e}")))?;
        let (latest, current) = self.scene_revision(id, None)?;
        if manifest_json == current {
            let revision = self.revisions(id)?.swap_remove(latest as usize);
            return Ok(Revised { revision, scene: None });
        }
        let farm = self.clone();
        let checked = manifest_json.clone();
        let loaded = tokio::task::spawn_blocking(move || -> Result<LoadedScene> {
            Ok(farm.bundle(&checked)?.load(&farm.config.limits)?)
        })
        .await??;
        let revision = Revision { manifest_json, summary, created_unix_ms: now_unix_ms() };
        let number = latest + 1;
        let bytes = serde_json::to_vec(&revision)
            .map_err(|e| FarmError::Internal(format!("a revision does not serialise: {e}")))?;
        let (store, key) = (self.store.clone(), id.to_owned());
        tokio::task::spawn_blocking(move || store.put_revision(&key, number, &bytes)).await??;
        info!(scene = %&id[..id.len().min(12)], number, summary = %revision.summary, "scene revised");
        let made = RevisionInfo {
            number,
            summary: revision.summary.clone(),
            created_unix_ms: revision.created_unix_ms,
        };
        self.lock().scenes.add(id, revision);
        self.bump();
        Ok(Revised { revision: made, scene: Some(loaded) })
    }
}

/// The largest photometric file the studio takes, in bytes (an IES file of a fine web is a
/// few hundred kilobytes).
pub const MAX_PHOTOMETRY_BYTES: usize = 1 << 20;

/// A photometric file taken from the studio: its reference in a scene, and what it says.
#[derive(Serialize)]
pub struct PhotometryInfo {
    /// `blake3:<hash>.ies` or `.ldt`: what a light's `ies` names in the scene.
    pub reference: String,
    pub file_name: String,
    pub flux_lm: f64,
    pub peak_cd: f64,
    pub beam_angle_deg: f64,
    pub description: String,
}

impl Farm {
    /// Reads an IES (LM-63) or EULUMDAT file named `file_name` as a scene would, and keeps it
    /// among the assets; refused with the reader's message, naming the file.
    pub fn keep_photometry(&self, file_name: &str, bytes: &[u8]) -> Result<PhotometryInfo> {
        use restauro_scene::formats::photometric;
        type Reader = fn(&str, &std::path::Path) -> restauro_scene::Result<photometric::Photometry>;
        let extension = sent_file(file_name, bytes, &["ies", "ldt"], MAX_PHOTOMETRY_BYTES)?;
        let parse: Reader =
            if extension == "ies" { photometric::parse_ies } else { photometric::parse_ldt };
        let text = photometric::decode_text(bytes.to_vec());
        let p = parse(&text, std::path::Path::new(file_name))?;
        let reference = self.keep_file(file_name, bytes, &extension)?;
        Ok(PhotometryInfo {
            reference,
            file_name: file_name.to_owned(),
            flux_lm: p.flux_lm(),
            peak_cd: p.peak_cd(),
            beam_angle_deg: p.beam_angle_deg(),
            description: p.description.clone(),
        })
    }
}

/// Checks a file the studio was sent before it is read: its name (letters, digits, `.`, `_`,
/// `-`, at most 100 characters, ending in one of `extensions`) and its size. Its extension, in
/// lower case.
pub fn sent_file(
    name: &str,
    bytes: &[u8],
    extensions: &[&str],
    max_bytes: usize,
) -> Result<String> {
    let extension = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase()).unwrap_or_default();
    let sane = !name.is_empty()
        && name.len() <= 100
        && name.chars().all(|c| c.is_ascii_alphanumeric() || "._- ".contains(c))
        && extensions.contains(&extension.as_str());
    if !sane {
        let endings: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        return Err(FarmError::Request(format!(
            "name: give the file's name, ending in {}, in letters, digits, `.`, `_` and `-`",
            endings.join(" or ")
        )));
    }
    if bytes.len() > max_bytes {
        return Err(FarmError::Request(format!(
            "{name}: {} bytes; a file of this kind may have at most {max_bytes}",
            bytes.len()
        )));
    }
    Ok(extension)
}

impl Farm {
    /// The bytes of the asset with BLAKE3 `hash` (hex), when the coordinator holds it intact.
    pub fn read_asset(&self, hash: &str) -> Result<Option<Vec<u8>>> {
        self.assets.read(hash)
    }

    /// Keeps `bytes` (a file the studio was sent, already read as its kind) among the assets:
    /// its reference in a scene, `blake3:<hash>.<extension>`.
    pub fn keep_file(&self, file_name: &str, bytes: &[u8], extension: &str) -> Result<String> {
        let hash = blake3::hash(bytes).to_hex().to_string();
        self.assets
            .keep(&hash, bytes)
            .map_err(|e| FarmError::Internal(format!("keeping {file_name}: {e}")))?;
        info!(file = file_name, hash = %&hash[..12], "file kept");
        Ok(format!("blake3:{hash}.{extension}"))
    }
}

/// The largest scene folder the studio takes in one upload, in bytes.
pub const MAX_FOLDER_BYTES: usize = 512 << 20;

impl Farm {
    /// Takes a scene folder sent as one tar or zip (or a bundle archive): bundled and checked as the
    /// command line bundles a folder, its files kept among the assets, and sent to the farm with
    /// a quick preview render (160 × 90 px, 1 sample per pixel, as `restauro studio` sends a
    /// scene), so that it is one of the studio's scenes. The preview job and the scene's id.
    pub async fn open_folder(
        self: &Arc<Self>,
        name: &str,
        scene: Option<String>,
        archive: Vec<u8>,
    ) -> Result<(crate::job::JobStatus, String)> {
        use restauro_scene::job::{JobName, JobSpec};
        use restauro_scene::plan::RenderOptions;
        let name =
            JobName::new(name).map_err(|e| FarmError::Request(format!("name: {}", e.problem)))?;
        let farm = self.clone();
        let bundle = tokio::task::spawn_blocking(move || -> Result<Bundle> {
            let limits = &farm.config.limits;
            let bundle =
                restauro_assets::folder::bundle_folder_archive(&archive, scene.as_deref(), limits)?;
            for (hash, bytes) in &bundle.files {
                if !farm.assets.has(hash) {
                    farm.assets
                        .keep(hash, bytes)
                        .map_err(|e| FarmError::Internal(format!("keeping file {hash}: {e}")))?;
                }
            }
            Ok(bundle)
        })
        .await??;
        let spec = JobSpec { name, render: RenderOptions::quick_preview(), ..JobSpec::default() };
        info!(files = bundle.files.len(), "scene folder taken");
        let manifest = bundle.canonical_json();
        let scene = scene_identity(&manifest);
        Ok((self.submit(manifest, spec).await?, scene))
    }
}
