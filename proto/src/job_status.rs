//! A job's status as both sides of the wire read it: its id ([`JobId`], a UUID the coordinator
//! chooses), its state ([`JobState`], with the lifecycle's diagram, which the farm's job record
//! enforces) and the [`JobStatus`] a client is sent, through either door — the studio as JSON
//! (its [`Serialize`], below), the gRPC services as `pb::JobStatus` (the `From`/`TryFrom`
//! below). The coordinator converts to the wire once, the command line back once, at its edge;
//! neither side reads a `pb::JobStatus` past that.
//!
//! ```text
//!            start          all tiles stored      Retinex, files       files written
//!  queued ─────────► running ─────────► assembling ─────────► post-processing ─────────► done
//!    │                  │                    │                       │
//!    └──────────────────┴────────────────────┴───────────────────────┴──► failed | cancelled
//! ```
//!
//! | wire | domain |
//! |---|---|
//! | `pb::JobStatus.job_id` | [`JobId`] (a UUID, else refused) |
//! | `pb::JobState` | [`JobState`] (unspecified: refused) |
//! | `pb::JobStatus` | [`JobStatus`] |

use crate::convert::WireError;
use crate::pb;
use serde::{Deserialize, Serialize};
use std::borrow::Borrow;
use std::fmt;
use std::ops::Deref;
use std::sync::Arc;

/// A job's id: a UUID chosen by the coordinator. Cheap to clone (an `Arc<str>` inside), so a
/// lease carries it without allocating.
#[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(from = "String", into = "String")]
pub struct JobId(Arc<str>);

impl JobId {
    /// A new, random id.
    pub fn random() -> Self {
        Self::from(uuid::Uuid::new_v4().to_string())
    }

    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// A job id from a caller: the coordinator's ids are UUIDs, and nothing else names a job.
    pub fn parse(text: &str) -> Result<Self, WireError> {
        if uuid::Uuid::parse_str(text).is_err() {
            let problem = format!("`{}` is not a job id", text.escape_debug());
            return Err(WireError::new("job_id", problem));
        }
        Ok(JobId::from(text))
    }
}

impl From<&str> for JobId {
    fn from(s: &str) -> Self {
        Self(Arc::from(s))
    }
}

impl From<String> for JobId {
    fn from(s: String) -> Self {
        Self(Arc::from(s))
    }
}

impl From<JobId> for String {
    fn from(id: JobId) -> String {
        id.0.to_string()
    }
}

impl Deref for JobId {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl Borrow<str> for JobId {
    fn borrow(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for JobId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl fmt::Debug for JobId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&*self.0, f)
    }
}

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

    /// Whether the diagram (in this module's header) allows `self → to`: a final state never
    /// changes again. The farm's job record refuses every other move.
    pub fn allows(self, to: JobState) -> bool {
        use JobState::*;
        match (self, to) {
            (Queued, Running) | (Queued | Running, Assembling) => true,
            (Assembling, PostProcessing) | (PostProcessing, Done) => true,
            (from, Failed | Cancelled) => !from.is_final(),
            _ => false,
        }
    }

    /// The state as the command line prints it (`restauro jobs`, `watch`, `cancel`, the progress
    /// bar): the wire enum's name in lower case. It differs from [`Display`](fmt::Display) only
    /// in `post_processing`, which the command line has always printed so.
    pub fn wire_name(self) -> String {
        pb::JobState::from(self).as_str_name().trim_start_matches("JOB_STATE_").to_lowercase()
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
    /// A sequence's frames; 0 for a still.
    pub frames_total: u32,
    /// Frames whose files are written: they are ready in order, frames `0..frames_ready`.
    pub frames_ready: u32,
    /// Each frame begun and not yet ready.
    pub frames: Vec<FrameProgress>,
}

/// How far one frame of a sequence is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameProgress {
    pub index: u32,
    pub label: String,
    pub tiles_done: u32,
    pub tiles_total: u32,
}

/// The studio's JSON of a job: every field, the id as a string, the state in words (`queued`,
/// `running`, `assembling`, `post-processing`, `done`, `failed` or `cancelled`), and `finished`,
/// whether the state is final (the page stops following the job then).
impl Serialize for JobStatus {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut out = s.serialize_struct("JobStatus", 17)?;
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
        out.serialize_field("frames_total", &self.frames_total)?;
        out.serialize_field("frames_ready", &self.frames_ready)?;
        out.serialize_field("frames", &self.frames)?;
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
    fn try_from(s: pb::JobState) -> Result<Self, WireError> {
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
            frames_total: s.frames_total,
            frames_ready: s.frames_ready,
            frames: s
                .frames
                .into_iter()
                .map(|f| pb::FrameProgress {
                    index: f.index,
                    label: f.label,
                    tiles_done: f.tiles_done,
                    tiles_total: f.tiles_total,
                })
                .collect(),
        }
    }
}

impl TryFrom<pb::JobStatus> for JobStatus {
    type Error = WireError;
    fn try_from(s: pb::JobStatus) -> Result<Self, WireError> {
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
            frames_total: s.frames_total,
            frames_ready: s.frames_ready,
            frames: s
                .frames
                .into_iter()
                .map(|f| FrameProgress {
                    index: f.index,
                    label: f.label,
                    tiles_done: f.tiles_done,
                    tiles_total: f.tiles_total,
                })
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            frames_total: 3,
            frames_ready: 1,
            frames: vec![FrameProgress {
                index: 1,
                label: "06:15".into(),
                tiles_done: 2,
                tiles_total: 4,
            }],
        }
    }

    /// The studio's page reads these fields by name (studio/web/farm.js): the state in words,
    /// and whether it is final.
    #[test]
    fn a_status_is_the_json_the_studio_page_reads() {
        let json = serde_json::to_value(status(JobState::PostProcessing)).unwrap();
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(String::as_str).collect();
        assert_eq!(keys.len(), 17, "{keys:?}");
        assert_eq!(json["frames"][0]["label"], "06:15");
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

    /// What the command line printed when it read the wire's state itself; `restauro jobs`
    /// keeps printing it.
    #[test]
    fn the_command_line_names_a_state_as_the_wire_does() {
        use JobState::*;
        let all = [Queued, Running, Assembling, PostProcessing, Done, Failed, Cancelled];
        for state in all {
            let expected = if state == PostProcessing {
                "post_processing".to_owned()
            } else {
                state.to_string()
            };
            assert_eq!(state.wire_name(), expected);
        }
    }

    #[test]
    fn a_bad_id_or_an_unspecified_state_names_its_field() {
        let bad_id = pb::JobStatus {
            job_id: "../etc".into(),
            ..pb::JobStatus::from(status(JobState::Done))
        };
        assert_eq!(JobStatus::try_from(bad_id).unwrap_err().field, "job_id");
        let unspecified = pb::JobStatus { state: 0, ..pb::JobStatus::from(status(JobState::Done)) };
        assert_eq!(JobStatus::try_from(unspecified).unwrap_err().to_string(), "state: missing");
    }
}
