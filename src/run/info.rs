//! `run.json`: a run's settings, status and totals ([`RunInfo`]), written first when a run
//! starts (so that every other file of the folder is attributable to it), after every
//! checkpoint (completed generations, evaluations, the checkpoint's hash), and at the end.

use super::archive::Discards;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::optim::Nsga2Settings;
use crate::record::{ProblemUse, RecordOptions};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// File name of the run's settings and status.
pub const RUN_FILE: &str = "run.json";

/// State of a run as written to `run.json` (`"running"`, `"finished"`, `"interrupted"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// A process is running it, or was killed while running it (the folder's lock tells
    /// which: [`super::RunFolder::state`]).
    Running,
    /// All requested generations are done.
    Finished,
    /// Stopped by ctrl-c or an error; resumable.
    Interrupted,
}

/// `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunInfo {
    /// gripopt version.
    pub gripopt_version: String,
    /// The run's id (random, set when the run starts): every checkpoint, shard and index
    /// line carries it, so that a file of another run is never taken for this run's (empty
    /// in run folders of a gripopt before issue 24).
    #[serde(default)]
    pub run_id: String,
    /// Problem name.
    pub problem_name: String,
    /// Path of the problem file given at the start (absolute; relative in run folders of a
    /// gripopt before issue 24).
    pub problem_path: PathBuf,
    /// SHA-256 of the problem in force (`problem.toml`; the start's unless a forced resume
    /// changed it).
    pub problem_sha256: String,
    /// The run's problem files and the generations each evaluated (empty in run folders of
    /// a gripopt before issue 24: then `problem.toml` evaluated every generation).
    #[serde(default)]
    pub problems: Vec<ProblemUse>,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// Total generations requested.
    pub generations: u64,
    /// Completed generations (those of the last checkpoint written).
    pub completed_generations: u64,
    /// Evaluations (of the last checkpoint).
    pub evaluations: u64,
    /// Content checksum (`sha256`) of the last checkpoint written.
    #[serde(default)]
    pub checkpoint_sha256: Option<String>,
    /// Threads of the last process.
    pub threads: usize,
    /// Wall time over all processes (s).
    pub wall_s: f64,
    /// Whether the run is running, finished or interrupted.
    pub status: RunStatus,
    /// Resumes: generation at which each happened, new total, and whether forced.
    pub resumes: Vec<Resume>,
    /// Recording options.
    pub recording: RecordOptions,
    /// Bytes recorded, over all processes (a process killed with -9 does not add its own).
    pub recording_bytes: u64,
    /// Seconds spent recording, over all processes (as `recording_bytes`).
    pub recording_s: f64,
    /// Every design evaluated up to the last checkpoint, counted by what discarded it.
    #[serde(default)]
    pub discards: Discards,
}

/// One resume.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Resume {
    /// Completed generations when resumed.
    pub at_generation: u64,
    /// New total.
    pub generations: u64,
    /// Forced despite a changed problem file.
    pub forced: bool,
    /// Note (e.g. what changed).
    pub note: String,
}

impl RunInfo {
    /// Read `RUN_DIR/run.json` (errors name the file).
    pub fn load(dir: &Path) -> Result<RunInfo> {
        let p = dir.join(RUN_FILE);
        let text = crate::fsutil::read_regular_string(&p, crate::fsutil::caps::RUN_JSON)
            .map_err(|e| Error::io(&p, "cannot read (is this a run folder?)", e))?;
        serde_json::from_str(&text).map_err(|source| Error::Json { path: p, what: "invalid run.json", source })
    }

    /// The run's problem files (run.json's `problems`, or for an older run folder its one
    /// `problem.toml`).
    pub fn problem_files(&self) -> Vec<ProblemUse> {
        if self.problems.is_empty() {
            vec![ProblemUse { first_generation: 1, file: "problem.toml".into(), sha256: self.problem_sha256.clone() }]
        } else {
            self.problems.clone()
        }
    }

    /// The command that starts this run again from its first generation (for a run that
    /// never reached its first checkpoint).
    pub fn optimise_command(&self, dir: &Path) -> String {
        let q = |p: &Path| crate::error::shell_quote(&p.to_string_lossy());
        let mut c = format!(
            "gripopt optimise {} --out {} --pop {} --generations {} --seed {}",
            q(&self.problem_path),
            q(dir),
            self.settings.pop_size,
            self.generations,
            self.settings.seed
        );
        if !self.recording.enabled {
            c.push_str(" --record none");
        }
        c
    }
}

/// The parts of `run.json` that identify a run and place its recordings, read tolerantly:
/// every field may be missing or `null` (run folders of older gripopt versions, or a run.json
/// written before its first checkpoint), unknown fields are ignored; a field present with a
/// wrong type is an error naming it. [`RunInfo`] is the whole, strict record.
#[derive(Debug, Clone, Default, Deserialize)]
pub struct RunHeader {
    /// The run's id (`None` in run folders of a gripopt before issue 24).
    #[serde(default)]
    pub run_id: Option<String>,
    /// Problem name.
    #[serde(default)]
    pub problem_name: Option<String>,
    /// SHA-256 of the problem in force.
    #[serde(default)]
    pub problem_sha256: Option<String>,
    /// Evaluations of the last checkpoint.
    #[serde(default, deserialize_with = "evaluations_field")]
    pub evaluations: Option<u64>,
    /// The recording settings (their epoch).
    #[serde(default)]
    pub recording: Option<RecordingHeader>,
}

/// `run.json` → `recording`, as far as [`RunHeader`] reads it.
#[derive(Debug, Clone, Default, Deserialize)]
pub struct RecordingHeader {
    /// Epoch of the recording's time axis, whole seconds since 1970.
    #[serde(default, deserialize_with = "epoch_s_field")]
    pub epoch_s: Option<u64>,
}

fn evaluations_field<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<u64>, D::Error> {
    Option::<u64>::deserialize(d)
        .map_err(|e| serde::de::Error::custom(format!("field `evaluations` is not a whole number ({e})")))
}

fn epoch_s_field<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Option<u64>, D::Error> {
    Option::<u64>::deserialize(d).map_err(|e| {
        serde::de::Error::custom(format!("field `recording.epoch_s` is not a whole number of seconds ({e})"))
    })
}

impl RunHeader {
    /// Read `RUN_DIR/run.json` (errors name the file, and the field where one has a wrong type).
    pub fn load(dir: &Path) -> Result<RunHeader> {
        let p = dir.join(RUN_FILE);
        let text = crate::fsutil::read_regular_string(&p, crate::fsutil::caps::RUN_JSON)
            .map_err(|e| Error::io(&p, "cannot read", e))?;
        serde_json::from_str(&text).map_err(|source| Error::Json { path: p, what: "invalid run.json", source })
    }
    /// The run id (empty for a run of a gripopt before issue 24).
    pub fn run_id(&self) -> &str {
        self.run_id.as_deref().unwrap_or("")
    }
    /// The recording's epoch (0 = 1970 where run.json has none).
    pub fn epoch_s(&self) -> u64 {
        self.recording.as_ref().and_then(|r| r.epoch_s).unwrap_or(0)
    }
}

/// A new run id: 16 hex digits from the clock, the process and the folder (unique, not a
/// secret; never part of a result).
pub fn new_run_id(dir: &Path) -> String {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let seed = format!("{now} {} {}", std::process::id(), dir.display());
    crate::fsutil::sha256_hex(seed.as_bytes())[..16].to_string()
}

/// Write `v` as pretty JSON to `path`, atomically.
pub fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<()> {
    let mut s = serde_json::to_string_pretty(v).map_err(|source| Error::Json {
        path: path.to_path_buf(),
        what: "cannot serialise",
        source,
    })?;
    s.push('\n');
    write_atomic(path, s.as_bytes())
}
