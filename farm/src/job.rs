//! A job's durable record — what was asked (the scene's manifest and the [`JobSpec`]), what was
//! planned (the [`Plan`], resolved once, at submission), and where it stands — and its
//! lifecycle, an explicit state machine:
//!
//! ```text
//!            start          all tiles stored      Retinex, files       files written
//!  queued ─────────► running ─────────► assembling ─────────► post-processing ─────────► done
//!    │                  │                    │                       │
//!    └──────────────────┴────────────────────┴───────────────────────┴──► failed | cancelled
//! ```
//!
//! Moves are methods that refuse what the diagram does not allow: a final state (done,
//! failed, cancelled) never changes again, so a cancel that lands while a job is assembled
//! stands, and the assembly that finishes afterwards is refused instead of overturning it. A job
//! resumed with all its tiles stored goes from queued straight to assembling.

use crate::ids::JobId;
use restauro_scene::job::JobSpec;
use restauro_scene::plan::Plan;
use serde::{Deserialize, Serialize};

/// The job's state and the status a client is sent live with the wire types, which the command
/// line shares; the diagram above is [`JobState::allows`].
pub use restauro_proto::job_status::{FrameProgress, JobState, JobStatus};

/// A lifecycle move the job's state does not allow (e.g. finishing a cancelled job).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("job {job} is {from}; it cannot become {to}")]
pub struct IllegalTransition {
    pub job: JobId,
    pub from: JobState,
    pub to: JobState,
}

type Moved<T = ()> = std::result::Result<T, IllegalTransition>;

/// The record's layout in the store; a record of another layout was written by an earlier
/// release.
pub const RECORD_FORMAT: u32 = 2;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JobRecord {
    pub format: u32,
    pub id: JobId,
    pub spec: JobSpec,
    /// The scene: the canonical JSON manifest of its bundle.
    pub manifest_json: String,
    pub plan: Plan,
    state: JobState,
    /// Why the job failed, when it did.
    pub error: String,
    pub submitted_unix_ms: u64,
    /// Tiles finished when the job left the scheduler (failed or cancelled).
    pub tiles_done_at_end: u32,
    /// Times a tile went back to the queue, counted until the job left the scheduler.
    pub tiles_requeued_at_end: u32,
    /// The result files, once done; a sequence's grow as its frames are ready.
    pub results: Vec<String>,
    /// A sequence's plans (frames with the same plan share it; usually one or two, the sun up
    /// and down); empty for a still.
    #[serde(default)]
    pub frame_plans: Vec<Plan>,
    /// Each frame's first tile in the job's numbering and its plan in `frame_plans`; the
    /// frames' tiles follow each other, frame 0's first.
    #[serde(default)]
    pub frame_tiles: Vec<(u32, u32)>,
    /// Frames whose files are written, in order: `0..frames_ready`.
    #[serde(default)]
    pub frames_ready: u32,
    /// The eye's state after the last ready frame's seen image: the next frame's, if it follows
    /// in time (`Frame::elapsed_s`), is seen by that eye — after a restart too.
    #[serde(default)]
    pub eye: Option<restauro_spectral::seen::EyeState>,
}

/// Where a tile of a job is: its frame (0 for a still), the frame's plan and the tile's number
/// in that plan.
pub struct TilePlace<'a> {
    pub frame: u32,
    pub plan: &'a Plan,
    pub tile: u32,
}

impl JobRecord {
    pub fn new(id: JobId, spec: JobSpec, manifest_json: String, plan: Plan, now_ms: u64) -> Self {
        Self {
            format: RECORD_FORMAT,
            id,
            spec,
            manifest_json,
            plan,
            state: JobState::Queued,
            error: String::new(),
            submitted_unix_ms: now_ms,
            tiles_done_at_end: 0,
            tiles_requeued_at_end: 0,
            results: Vec::new(),
            frame_plans: Vec::new(),
            frame_tiles: Vec::new(),
            frames_ready: 0,
            eye: None,
        }
    }

    /// Whether the job is a sequence of frames.
    pub fn is_sequence(&self) -> bool {
        !self.frame_tiles.is_empty()
    }

    /// The frames of the job: 0 for a still.
    pub fn frame_count(&self) -> u32 {
        self.frame_tiles.len() as u32
    }

    /// Every tile of the job, all its frames together.
    pub fn tile_count(&self) -> u32 {
        match self.frame_tiles.last() {
            None => self.plan.tile_count(),
            Some(&(first, plan)) => first + self.frame_plans[plan as usize].tile_count(),
        }
    }

    /// The plan of frame `frame` (the job's plan for a still).
    pub fn frame_plan(&self, frame: u32) -> Option<&Plan> {
        match self.frame_tiles.get(frame as usize) {
            None if self.frame_tiles.is_empty() && frame == 0 => Some(&self.plan),
            None => None,
            Some(&(_, plan)) => self.frame_plans.get(plan as usize),
        }
    }

    /// The job's tiles of frame `frame`.
    pub fn frame_range(&self, frame: u32) -> std::ops::Range<u32> {
        let Some(&(first, _)) = self.frame_tiles.get(frame as usize) else {
            return 0..self.tile_count();
        };
        let plan = self.frame_plan(frame).expect("each frame names a plan of the record");
        first..first + plan.tile_count()
    }

    /// Where tile `tile` of the job is; `None` past the last.
    pub fn place(&self, tile: u32) -> Option<TilePlace<'_>> {
        if tile >= self.tile_count() {
            return None;
        }
        if self.frame_tiles.is_empty() {
            return Some(TilePlace { frame: 0, plan: &self.plan, tile });
        }
        let frame = self.frame_tiles.partition_point(|&(first, _)| first <= tile) - 1;
        let (first, plan) = self.frame_tiles[frame];
        Some(TilePlace {
            frame: frame as u32,
            plan: &self.frame_plans[plan as usize],
            tile: tile - first,
        })
    }

    /// The stem of frame `frame`'s files: the job's name and the frame's number.
    pub fn frame_stem(&self, frame: u32) -> String {
        format!("{}-{frame:04}", self.spec.name.file_stem())
    }

    pub fn state(&self) -> JobState {
        self.state
    }

    fn advance(&mut self, to: JobState) -> Moved {
        if !self.state.allows(to) {
            return Err(IllegalTransition { job: self.id.clone(), from: self.state, to });
        }
        self.state = to;
        Ok(())
    }

    /// Queued → running, when its first tile is leased. False when it was running already.
    pub fn start(&mut self) -> bool {
        self.advance(JobState::Running).is_ok()
    }

    /// Every tile is stored: queued or running → assembling.
    pub fn begin_assembly(&mut self) -> Moved {
        self.advance(JobState::Assembling)
    }

    /// A resumed job goes to assembling again when it was being assembled or post-processed
    /// when the coordinator stopped, or when every tile is stored (`all_tiles`). Whether it did.
    pub fn resume_assembly(&mut self, all_tiles: bool) -> bool {
        match self.state {
            JobState::Assembling | JobState::PostProcessing => {
                self.state = JobState::Assembling;
                true
            }
            JobState::Queued | JobState::Running if all_tiles => {
                self.state = JobState::Assembling;
                true
            }
            _ => false,
        }
    }

    /// The framebuffer is whole: assembling → post-processing (the Retinex, the files).
    pub fn begin_post_processing(&mut self) -> Moved {
        self.advance(JobState::PostProcessing)
    }

    /// The result files are written: post-processing → done.
    pub fn finish(&mut self, results: Vec<String>) -> Moved {
        self.advance(JobState::Done)?;
        self.results = results;
        Ok(())
    }

    pub fn fail(&mut self, reason: String, tiles_done: u32) -> Moved {
        self.advance(JobState::Failed)?;
        self.error = reason;
        self.tiles_done_at_end = tiles_done;
        Ok(())
    }

    pub fn cancel(&mut self, tiles_done: u32) -> Moved {
        self.advance(JobState::Cancelled)?;
        self.tiles_done_at_end = tiles_done;
        Ok(())
    }

    /// What the renders were made with, for the files' headers.
    pub fn info(&self) -> String {
        self.info_of(&self.plan)
    }

    /// What a render of `plan` was made with, for the files' headers.
    pub fn info_of(&self, p: &Plan) -> String {
        format!(
            "variant={} integrator={} spp={} max_depth={} seed={}",
            p.variant.as_deref().unwrap_or("base"),
            p.integrator.keyword(),
            p.samples_per_pixel,
            p.max_depth,
            p.seed
        )
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("a record always serialises")
    }

    /// A stored record. One of an earlier release's layout cannot be resumed: it comes back
    /// failed, with its id and name and the reason, so it stays listed and nothing is silent.
    /// Refused only when it is not JSON at all.
    pub fn from_bytes(id: &str, bytes: &[u8]) -> Result<Self, serde_json::Error> {
        if let Ok(record) = serde_json::from_slice::<JobRecord>(bytes)
            && record.format == RECORD_FORMAT
        {
            return Ok(record);
        }
        let old: serde_json::Value = serde_json::from_slice(bytes)?;
        let name = old.get("name").and_then(|n| n.as_str()).unwrap_or_default();
        let spec = JobSpec {
            name: restauro_scene::job::JobName::new(name).unwrap_or_default(),
            ..JobSpec::default()
        };
        let plan = Plan {
            width: 0,
            height: 0,
            variant: None,
            integrator: restauro_scene::scene_file::Integrator::Path,
            samples_per_pixel: 0,
            max_depth: 0,
            seed: 0,
            spectral: false,
            sky: false,
            lit: false,
            white: false,
            tile: 1,
            grids: false,
            noise_target: 0.0,
        };
        let was_final = matches!(
            old.get("state").and_then(|s| s.as_str()),
            Some("done" | "failed" | "cancelled")
        );
        let mut record = JobRecord::new(JobId::from(id), spec, String::new(), plan, 0);
        // Marked as read from an earlier layout, so the coordinator stores it anew.
        record.format = 1;
        record.state = JobState::Failed;
        record.error = if was_final {
            "stored by an earlier restauro release; its results, if any, are kept in its folder"
                .into()
        } else {
            "stored by an earlier restauro release, which this one cannot resume; submit it again"
                .into()
        };
        Ok(record)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> JobRecord {
        let plan = Plan {
            width: 8,
            height: 8,
            variant: None,
            integrator: restauro_scene::scene_file::Integrator::Whitted,
            samples_per_pixel: 1,
            max_depth: 1,
            seed: 0,
            spectral: false,
            sky: false,
            lit: false,
            white: false,
            tile: 8,
            grids: false,
            noise_target: 0.0,
        };
        JobRecord::new(JobId::from("j"), JobSpec::default(), "{}".into(), plan, 0)
    }

    #[test]
    fn the_happy_path_and_nothing_after_a_final_state() {
        let mut r = record();
        assert!(r.start());
        assert!(!r.start(), "running already");
        r.begin_assembly().unwrap();
        r.begin_post_processing().unwrap();
        r.finish(vec!["a.exr".into()]).unwrap();
        assert_eq!(r.state(), JobState::Done);
        for e in [r.cancel(0), r.fail("x".into(), 0), r.begin_assembly()] {
            assert!(matches!(e, Err(IllegalTransition { from: JobState::Done, .. })));
        }
    }

    /// The race of defect 7: a cancel while the job is assembled stands.
    #[test]
    fn a_cancel_during_assembly_is_not_overturned() {
        let mut r = record();
        r.start();
        r.begin_assembly().unwrap();
        r.cancel(1).unwrap();
        let e = r.begin_post_processing().unwrap_err();
        assert!(e.to_string().contains("cancelled; it cannot become post-processing"), "{e}");
        assert!(r.finish(Vec::new()).is_err());
        assert_eq!(r.state(), JobState::Cancelled);
        assert!(r.results.is_empty());
    }

    #[test]
    fn a_resumed_job_may_assemble_from_queued_but_not_skip_steps() {
        let mut r = record();
        assert!(r.begin_post_processing().is_err());
        assert!(r.finish(Vec::new()).is_err());
        r.begin_assembly().unwrap();
        assert!(!r.start(), "no way back to running");
    }

    /// A sequence's tiles are its frames' one after another; each tile maps to its frame and
    /// its number in the frame's plan.
    #[test]
    fn a_sequences_tiles_map_to_their_frames() {
        let mut r = record();
        let one = r.plan.clone(); // 8 × 8 in one 8-px tile
        let four = Plan { width: 16, height: 16, ..one.clone() };
        r.frame_plans = vec![one, four];
        r.frame_tiles = vec![(0, 0), (1, 1), (5, 0)];
        assert_eq!((r.tile_count(), r.frame_count()), (6, 3));
        let at = |t| r.place(t).map(|p| (p.frame, p.tile, p.plan.width));
        assert_eq!(at(0), Some((0, 0, 8)));
        assert_eq!(at(1), Some((1, 0, 16)));
        assert_eq!(at(4), Some((1, 3, 16)));
        assert_eq!(at(5), Some((2, 0, 8)));
        assert_eq!(at(6), None);
        assert_eq!(r.frame_range(1), 1..5);
        assert_eq!(r.frame_stem(2), "render-0002");
        assert_eq!(JobRecord::from_bytes("j", &r.to_bytes()).unwrap(), r);
    }

    #[test]
    fn records_survive_the_store_and_old_ones_come_back_failed() {
        let r = record();
        assert_eq!(JobRecord::from_bytes("j", &r.to_bytes()).unwrap(), r);
        let old = br#"{"id":"o","name":"aosta","state":"running","options":{}}"#;
        let o = JobRecord::from_bytes("o", old).unwrap();
        assert_eq!((o.state(), o.spec.name.as_str()), (JobState::Failed, "aosta"));
        assert_ne!(o.format, RECORD_FORMAT);
        assert!(o.error.contains("earlier restauro release"));
        assert!(JobRecord::from_bytes("x", b"not json").is_err());
    }
}
