//! A sequence on the farm: one job whose tiles are its frames' tiles one after another (frame
//! 0's first), so the scheduler, the leases and the store treat it as any job, and its frames
//! are rendered in order. Each frame is planned at submission from its own scene (the job's
//! with the frame's changes: a sun below the horizon lights nothing, so a frame's plan may
//! differ), and a worker renders a frame from exactly that scene and plan: a frame is the same
//! frame rendered alone, bit for bit.
//!
//! A frame is ready once its files are written. Frames are written in order, by one thread a
//! job (the seen image of a frame may come to depend on the frames before it, as an eye's
//! adaptation does), as soon as each frame's tiles are all stored; then its tiles leave the
//! store. The job is done when its last frame is.

use super::{Farm, FarmState, assembly};
use crate::error::{FarmError, Result};
use crate::ids::JobId;
use crate::job::JobRecord;
use restauro_scene::bundle::Bundle;
use restauro_scene::job::JobSpec;
use restauro_scene::plan::Plan;
use restauro_scene::scene_file::{Light, SceneFile};
use restauro_scene::sequence::{Frame, check_count};
use restauro_scene::sun::{Site, sun_position};
use restauro_spectral::seen::{EyeHistory, EyeState};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// A sequence's plans, each once, and each frame's first tile and plan.
pub(super) struct FramePlans {
    pub plans: Vec<Plan>,
    pub tiles: Vec<(u32, u32)>,
}

/// The manifest of frame `frame` of the job whose scene is `manifest_json`.
pub(super) fn frame_manifest(manifest_json: &str, frame: &Frame) -> Result<String> {
    let mut scene = Bundle::parse_manifest(manifest_json)?;
    frame.apply(&mut scene, Path::new("the job's scene"))?;
    serde_json::to_string(&scene)
        .map_err(|e| FarmError::Internal(format!("a frame's scene does not serialise: {e}")))
}

impl Farm {
    /// Plans every frame of `spec` for the scene of `manifest_json`, within the limits. A
    /// frame's plan depends on its variant and on which of its suns are up (a sun below the
    /// horizon lights nothing, and a plan records whether any light but the sky does); the
    /// camera changes none. So the scene is loaded once for each variant and each set of suns
    /// up: a day of 4096 frames is loaded about twice, not 4096 times. Runs on a blocking
    /// thread.
    pub(super) fn plan_frames(&self, manifest_json: &str, spec: &JobSpec) -> Result<FramePlans> {
        let limits = self.config.limits;
        let label = format!("scene {}", spec.name);
        let path = Path::new(&label);
        check_count(spec.frames.len(), path, &limits)?;
        let bundle = self.bundle(manifest_json)?;
        let mut plans: Vec<Plan> = Vec::new();
        let mut by_change: HashMap<(Vec<Option<bool>>, Option<&str>), u32> = HashMap::new();
        let mut tiles = Vec::with_capacity(spec.frames.len());
        let mut next_tile: u32 = 0;
        for (index, frame) in spec.frames.iter().enumerate() {
            let key = (suns_up(&bundle.scene, frame.datetime.as_deref()), frame.variant.as_deref());
            let plan = match by_change.get(&key) {
                Some(&plan) => plan,
                None => {
                    let mut scene = bundle.scene.clone();
                    frame.apply(&mut scene, path)?;
                    let loaded = restauro_scene::load::load(scene, &bundle.assets(), &limits)
                        .map_err(|e| frame_error(index, frame, e))?;
                    let mut options = spec.render.clone();
                    if frame.variant.is_some() {
                        options.variant.clone_from(&frame.variant);
                    }
                    let plan = Plan::new(&loaded, &options, &limits, path)
                        .map_err(|e| frame_error(index, frame, e))?;
                    let at = match plans.iter().position(|p| *p == plan) {
                        Some(at) => at,
                        None => {
                            plans.push(plan);
                            plans.len() - 1
                        }
                    } as u32;
                    by_change.insert(key, at);
                    at
                }
            };
            tiles.push((next_tile, plan));
            next_tile = next_tile
                .checked_add(plans[plan as usize].tile_count())
                .filter(|&n| n <= limits.max_job_tiles)
                .ok_or(FarmError::Limit {
                    what: "the tiles of the sequence's frames".into(),
                    value: u64::from(next_tile) + u64::from(plans[plan as usize].tile_count()),
                    limit: u64::from(limits.max_job_tiles),
                    flag: "--max-job-tiles",
                    fix: "take fewer frames, larger tiles (--tile) or raise the limit",
                })?;
        }
        Ok(FramePlans { plans, tiles })
    }

    /// Counts a stored tile towards its frame: true when it was the frame's last.
    pub(super) fn count_frame_tile(st: &mut FarmState, id: &JobId, tile: u32) -> bool {
        let Some(r) = st.jobs.get(id) else { return false };
        let Some(place) = r.place(tile) else { return false };
        let whole = r.frame_range(place.frame).len() as u32;
        let Some(done) = st.frame_done.get_mut(id).and_then(|d| d.get_mut(place.frame as usize))
        else {
            return false;
        };
        *done += 1;
        *done == whole
    }

    /// A tile counted towards its frame is to be rendered again (its worker was quarantined).
    pub(super) fn tile_undone(st: &mut FarmState, id: &JobId, tile: u32) {
        let Some(place) = st.jobs.get(id).and_then(|r| r.place(tile)) else { return };
        if let Some(done) = st.frame_done.get_mut(id).and_then(|d| d.get_mut(place.frame as usize))
        {
            *done = done.saturating_sub(1);
        }
    }

    /// Starts the thread that writes the frames of sequence `id` that are whole, in order, and
    /// ends the job after its last; nothing when one runs already (it will see them).
    pub(super) fn kick_frames(self: &Arc<Self>, id: &JobId) {
        if !self.lock().assembling_frames.insert(id.clone()) {
            return;
        }
        let (farm, id) = (self.clone(), id.clone());
        std::thread::spawn(move || assembly::assemble_frames(&farm, &id));
    }

    /// What the frame thread does next for sequence `id`; when nothing, it is no longer
    /// running (decided under the lock, so a frame made whole meanwhile starts another).
    pub(super) fn next_frame_step(&self, id: &JobId) -> FrameStep {
        let mut st = self.lock();
        let step = match st.jobs.get(id) {
            None => FrameStep::Stop,
            Some(r) if r.state().is_final() => FrameStep::Stop,
            Some(r) if r.frames_ready == r.frame_count() => match r.state() {
                crate::job::JobState::Assembling => FrameStep::Finish,
                _ => FrameStep::Stop,
            },
            Some(r) => {
                let frame = r.frames_ready;
                let whole = r.frame_range(frame).len() as u32;
                let done = st.frame_done.get(id).and_then(|d| d.get(frame as usize)).copied();
                match done == Some(whole) {
                    true => FrameStep::Frame(Box::new(FrameWork::of(r, frame))),
                    false => FrameStep::Stop,
                }
            }
        };
        if matches!(step, FrameStep::Stop) {
            st.assembling_frames.remove(id);
        }
        step
    }

    /// Frame `frame`'s files are written: it is ready, unless the job ended meanwhile. Whether
    /// it is.
    pub(super) fn frame_ready(
        &self,
        id: &JobId,
        frame: u32,
        files: &[String],
        eye: Option<EyeState>,
    ) -> bool {
        let ready = {
            let mut st = self.lock();
            match st.jobs.get_mut(id) {
                Some(r) if !r.state().is_final() && r.frames_ready == frame => {
                    r.frames_ready += 1;
                    r.results.extend(files.iter().cloned());
                    r.eye = eye;
                    true
                }
                _ => false,
            }
        };
        if ready {
            self.persist(id);
            self.bump();
        }
        ready
    }
}

/// What the frame thread does next.
pub(super) enum FrameStep {
    /// Write this frame's files.
    Frame(Box<FrameWork>),
    /// Every frame is ready and every tile stored: the job is done.
    Finish,
    /// Nothing more for now.
    Stop,
}

/// What writing one frame needs of its job's record.
pub(super) struct FrameWork {
    pub frame: u32,
    pub plan: Plan,
    pub tiles: std::ops::Range<u32>,
    pub stem: String,
    pub info: String,
    pub spec: JobSpec,
    /// The eye the frame is seen by: the one after the frame before, when both have a time.
    pub eye: Option<EyeHistory>,
}

impl FrameWork {
    fn of(r: &JobRecord, frame: u32) -> Self {
        let plan = r.frame_plan(frame).expect("the frame is the record's").clone();
        Self {
            frame,
            // The header a still of the frame's scene gets: the files are the same bytes.
            info: r.info_of(&plan),
            plan,
            tiles: r.frame_range(frame),
            stem: r.frame_stem(frame),
            spec: JobSpec { frames: Vec::new(), ..r.spec.clone() },
            eye: eye_history(r, frame),
        }
    }
}

/// The eye frame `frame` of `r` is seen by: the state after the frame before and the time
/// between them, when both frames have a time and the frame before left a state.
fn eye_history(r: &JobRecord, frame: u32) -> Option<EyeHistory> {
    let before = r.spec.frames.get(usize::try_from(frame).ok()?.checked_sub(1)?)?;
    let this = r.spec.frames.get(frame as usize)?;
    let elapsed_s = this.elapsed_s? - before.elapsed_s?;
    Some(EyeHistory { before: r.eye?, elapsed_s })
}

/// Whether each light of `scene` with a site has the sun above the horizon at `datetime` (none
/// without a date-time: the frame keeps the scene's own); `None` for a date-time the sun's
/// position cannot be computed for, so that such a frame's scene is loaded, and refused.
fn suns_up(scene: &SceneFile, datetime: Option<&str>) -> Vec<Option<bool>> {
    let Some(datetime) = datetime else { return Vec::new() };
    scene
        .lights
        .iter()
        .filter_map(|light| match light {
            Light::Sun { site: Some(s), .. } | Light::Sky { site: Some(s), .. } => {
                let site = Site::new(s.latitude_deg, s.longitude_deg, s.height_m);
                Some(sun_position(site, datetime, None).ok().map(|p| p.elevation_deg > 0.0))
            }
            _ => None,
        })
        .collect()
}

/// A frame's scene or plan refused: which frame, and why.
fn frame_error(index: usize, frame: &Frame, e: restauro_scene::SceneError) -> FarmError {
    FarmError::Frame { index, label: frame.label.clone(), problem: Box::new(e) }
}
