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
pub use restauro_proto::job_status::{JobState, JobStatus};

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
