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
use restauro_proto as pb;
use restauro_proto::convert::WireError;
use restauro_scene::job::JobSpec;
use restauro_scene::plan::Plan;
use serde::{Deserialize, Serialize};
use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JobState {
    Queued,
    Running,
    Assembling,
    PostProcessing,
    Done,
    Failed,
    Cancelled,
}

impl JobState {
    pub fn is_final(self) -> bool {
        matches!(self, JobState::Done | JobState::Failed | JobState::Cancelled)
    }

    /// Whether the diagram allows `self → to`.
    fn allows(self, to: JobState) -> bool {
        use JobState::*;
        match (self, to) {
            (Queued, Running) | (Queued | Running, Assembling) => true,
            (Assembling, PostProcessing) | (PostProcessing, Done) => true,
            (from, Failed | Cancelled) => !from.is_final(),
            _ => false,
        }
    }
}

impl fmt::Display for JobState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            JobState::Queued => "queued",
            JobState::Running => "running",
            JobState::Assembling => "assembling",
            JobState::PostProcessing => "post-processing",
            JobState::Done => "done",
            JobState::Failed => "failed",
            JobState::Cancelled => "cancelled",
        })
    }
}

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
    /// The result files, once done.
    pub results: Vec<String>,
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
        }
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
        let p = &self.plan;
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

/// A job as a client sees it, through either door: the studio sends it as JSON (its
/// [`Serialize`], below), the gRPC services as `pb::JobStatus` (the `From`/`TryFrom` below).
#[derive(Clone, Debug, PartialEq)]
pub struct JobStatus {
    pub id: JobId,
    pub name: String,
    pub state: JobState,
    pub tiles_total: u32,
    pub tiles_done: u32,
    pub tiles_leased: u32,
    pub tiles_requeued: u32,
    pub error: String,
    pub priority: i32,
    pub width: u32,
    pub height: u32,
    pub elapsed_s: f64,
    pub results: Vec<String>,
}

/// The studio's JSON of a job: every field, the id as a string, the state in words (`queued`,
/// `running`, `assembling`, `post-processing`, `done`, `failed` or `cancelled`), and `finished`,
/// whether the state is final (the page stops following the job then).
impl Serialize for JobStatus {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut out = s.serialize_struct("JobStatus", 14)?;
        out.serialize_field("id", &self.id)?;
        out.serialize_field("name", &self.name)?;
        out.serialize_field("state", &self.state)?;
        out.serialize_field("finished", &self.state.is_final())?;
        out.serialize_field("tiles_total", &self.tiles_total)?;
        out.serialize_field("tiles_done", &self.tiles_done)?;
        out.serialize_field("tiles_leased", &self.tiles_leased)?;
        out.serialize_field("tiles_requeued", &self.tiles_requeued)?;
        out.serialize_field("error", &self.error)?;
        out.serialize_field("priority", &self.priority)?;
        out.serialize_field("width", &self.width)?;
        out.serialize_field("height", &self.height)?;
        out.serialize_field("elapsed_s", &self.elapsed_s)?;
        out.serialize_field("results", &self.results)?;
        out.end()
    }
}

// The wire's job state and status: converted here, once, each way.

impl From<JobState> for pb::JobState {
    fn from(s: JobState) -> Self {
        match s {
            JobState::Queued => pb::JobState::Queued,
            JobState::Running => pb::JobState::Running,
            JobState::Assembling => pb::JobState::Assembling,
            JobState::PostProcessing => pb::JobState::PostProcessing,
            JobState::Done => pb::JobState::Done,
            JobState::Failed => pb::JobState::Failed,
            JobState::Cancelled => pb::JobState::Cancelled,
        }
    }
}

impl TryFrom<pb::JobState> for JobState {
    type Error = WireError;
    fn try_from(s: pb::JobState) -> std::result::Result<Self, WireError> {
        Ok(match s {
            pb::JobState::Queued => JobState::Queued,
            pb::JobState::Running => JobState::Running,
            pb::JobState::Assembling => JobState::Assembling,
            pb::JobState::PostProcessing => JobState::PostProcessing,
            pb::JobState::Done => JobState::Done,
            pb::JobState::Failed => JobState::Failed,
            pb::JobState::Cancelled => JobState::Cancelled,
            pb::JobState::Unspecified => return Err(WireError::missing("state")),
        })
    }
}

impl From<JobStatus> for pb::JobStatus {
    fn from(s: JobStatus) -> Self {
        pb::JobStatus {
            job_id: s.id.to_string(),
            name: s.name,
            state: pb::JobState::from(s.state) as i32,
            tiles_total: s.tiles_total,
            tiles_done: s.tiles_done,
            tiles_leased: s.tiles_leased,
            tiles_requeued: s.tiles_requeued,
            error: s.error,
            priority: s.priority,
            width: s.width,
            height: s.height,
            elapsed_s: s.elapsed_s,
            results: s.results,
        }
    }
}

impl TryFrom<pb::JobStatus> for JobStatus {
    type Error = WireError;
    fn try_from(s: pb::JobStatus) -> std::result::Result<Self, WireError> {
        let state = pb::JobState::try_from(s.state)
            .map_err(|_| WireError::new("state", format!("{} is not a job state", s.state)))?;
        Ok(JobStatus {
            id: JobId::parse(&s.job_id)?,
            name: s.name,
            state: JobState::try_from(state)?,
            tiles_total: s.tiles_total,
            tiles_done: s.tiles_done,
            tiles_leased: s.tiles_leased,
            tiles_requeued: s.tiles_requeued,
            error: s.error,
            priority: s.priority,
            width: s.width,
            height: s.height,
            elapsed_s: s.elapsed_s,
            results: s.results,
        })
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

    fn status(state: JobState) -> JobStatus {
        JobStatus {
            id: JobId::from("0b7e7c5c-7b1e-4a43-9c8e-4f3f5f2b9a10"),
            name: "aosta".into(),
            state,
            tiles_total: 4,
            tiles_done: 2,
            tiles_leased: 1,
            tiles_requeued: 0,
            error: String::new(),
            priority: 3,
            width: 64,
            height: 48,
            elapsed_s: 1.5,
            results: vec!["aosta.exr".into()],
        }
    }

    /// The studio's page reads these fields by name (studio/web/farm.js): the state in words,
    /// and whether it is final.
    #[test]
    fn a_status_is_the_json_the_studio_page_reads() {
        let json = serde_json::to_value(status(JobState::PostProcessing)).unwrap();
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(keys.len(), 14, "{keys:?}");
        assert_eq!(json["id"], "0b7e7c5c-7b1e-4a43-9c8e-4f3f5f2b9a10");
        assert_eq!(
            (json["state"].as_str(), json["finished"].as_bool()),
            (Some("post-processing"), Some(false))
        );
        let done = serde_json::to_value(status(JobState::Cancelled)).unwrap();
        assert_eq!(
            (done["state"].as_str(), done["finished"].as_bool()),
            (Some("cancelled"), Some(true))
        );
        assert_eq!(json["elapsed_s"], 1.5);
        assert_eq!(json["results"][0], "aosta.exr");
    }

    #[test]
    fn a_status_goes_over_the_wire_and_back_unchanged() {
        for state in [JobState::Queued, JobState::PostProcessing, JobState::Done] {
            let wire = pb::JobStatus::from(status(state));
            assert_eq!(JobStatus::try_from(wire).unwrap(), status(state));
        }
        let unknown = pb::JobStatus { state: 99, ..pb::JobStatus::from(status(JobState::Done)) };
        assert!(JobStatus::try_from(unknown).is_err());
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
