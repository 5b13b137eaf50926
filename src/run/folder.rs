//! Reading a run folder back, typed ([`RunFolder`]): run.json, the CSV tables (read with
//! the csv crate into the rows they were written from), the recorded designs (their
//! `/designs` record and trajectory from the MCAP shards) and replay; the run's state
//! (running, stopped, interrupted, finished: run.json and the folder's lock) and its problem
//! files, checked against the hashes run.json recorded. What `gripopt show`, `verify` and
//! the Python package read.

use super::info::{RunInfo, RunStatus};
use super::lock::{LockHolder, RunLock};
use super::outputs::{DesignRow, HistoryRow};
use crate::params::Problem;
use crate::record::{problem_of_generation, read_design, replay, Recorded, Replay, RunProblem};
use crate::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A run folder written by `optimise`/`resume` (it may be running: its files are rewritten
/// whole, atomically, every generation).
#[derive(Debug, Clone)]
pub struct RunFolder {
    dir: PathBuf,
}

/// What a run is doing, from run.json and the folder's lock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunState {
    /// A process runs or resumes it (its pid, when known).
    Running(Option<u32>),
    /// It was killed (or crashed) while running: run.json says running, but no process
    /// holds the folder; resumable when it has a checkpoint.
    Stopped,
    /// Stopped by ctrl-c or an error after a checkpoint; resumable.
    Interrupted,
    /// All requested generations are done (a resume with more generations continues it).
    Finished,
}

impl RunState {
    /// The state as one word: running, stopped, interrupted, finished.
    pub fn word(&self) -> &'static str {
        match self {
            RunState::Running(_) => "running",
            RunState::Stopped => "stopped",
            RunState::Interrupted => "interrupted",
            RunState::Finished => "finished",
        }
    }
}

impl RunFolder {
    /// The run folder `dir` (an error when it is not a folder).
    pub fn open(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref();
        if !dir.is_dir() {
            return Err(Error::RunDir { path: dir.to_path_buf(), message: "not a folder".into() });
        }
        Ok(RunFolder { dir: dir.to_path_buf() })
    }
    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
    /// `run.json`: settings, status, generations, resumes.
    pub fn info(&self) -> Result<RunInfo> {
        RunInfo::load(&self.dir)
    }
    /// What the run is doing: run.json's status, told apart by the folder's lock (a run
    /// that says running but whose folder no process holds was killed).
    pub fn state(&self) -> Result<RunState> {
        let info = self.info()?;
        Ok(match (info.status, RunLock::holder(&self.dir)?) {
            (RunStatus::Running, LockHolder::Held(pid)) => RunState::Running(pid),
            (RunStatus::Running, LockHolder::Free) => RunState::Stopped,
            (RunStatus::Interrupted, _) => RunState::Interrupted,
            (RunStatus::Finished, _) => RunState::Finished,
        })
    }
    /// The run can be resumed: it has a checkpoint and no process holds it.
    pub fn resumable(&self) -> Result<bool> {
        Ok(self.dir.join("checkpoint.json").is_file() && RunLock::holder(&self.dir)? == LockHolder::Free)
    }
    /// The run's problem in force (`problem.toml`), checked against the hash run.json
    /// recorded: an edited copy is an error naming it.
    pub fn problem(&self) -> Result<Problem> {
        let g = self.info()?.problem_files().last().map_or(1, |p| p.first_generation);
        self.problem_of_generation(g)
    }
    /// The problem generation `g` was evaluated with (after a forced resume with another
    /// problem, the earlier `problem-G.toml` for the generations before it), checked
    /// against the hash run.json recorded: an edited file is an error naming it.
    pub fn problem_of_generation(&self, g: u64) -> Result<Problem> {
        let p: RunProblem = problem_of_generation(&self.dir, g)?;
        match p.edited() {
            Some(why) => Err(Error::RunDir {
                path: p.file,
                message: format!("{why}: restore it (replay and verify need the problem the run used)"),
            }),
            None => Ok(p.problem),
        }
    }
    /// pareto.csv: the population's feasible non-dominated designs.
    pub fn front(&self) -> Result<Vec<DesignRow>> {
        read_table(&self.dir.join("pareto.csv"))
    }
    /// archive.csv: every feasible non-dominated design of the run.
    pub fn archive(&self) -> Result<Vec<DesignRow>> {
        read_table(&self.dir.join("archive.csv"))
    }
    /// population.csv: the whole population.
    pub fn population(&self) -> Result<Vec<DesignRow>> {
        read_table(&self.dir.join("population.csv"))
    }
    /// history.csv: one row per generation.
    pub fn history(&self) -> Result<Vec<HistoryRow>> {
        read_table(&self.dir.join("history.csv"))
    }
    /// Design `id` as recorded: its `/designs` record and trajectory (one chunk read).
    pub fn design(&self, id: u64) -> Result<Recorded> {
        read_design(&self.dir, id)
    }
    /// Re-simulate design `id` and compare it with its recording.
    pub fn replay(&self, id: u64) -> Result<Replay> {
        replay(&self.dir, id)
    }
}

/// The rows of one of the run's CSV tables (`#` lines are comments). A missing or
/// unreadable file, one without a header, a row cut short or a last line without its line
/// break (the files are written whole) is an error naming the file and line.
pub fn read_table<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let text = crate::fsutil::read_regular(path, crate::fsutil::caps::TABLE)
        .map_err(|e| Error::io(path, "cannot read (is this a run folder with a completed generation?)", e))?;
    let bad = |line: u64, what: String| Error::RunDir {
        path: path.to_path_buf(),
        message: format!(
            "line {line}: {what}; the file is damaged or truncated (gripopt rewrites it whole every generation)"
        ),
    };
    let mut r = csv::ReaderBuilder::new().comment(Some(b'#')).from_reader(&text[..]);
    let header_ok = r.headers().map(|h| !h.is_empty()).unwrap_or(false);
    if !header_ok {
        return Err(Error::RunDir { path: path.to_path_buf(), message: "empty: no header line".into() });
    }
    let rows = r.deserialize().collect::<std::result::Result<Vec<T>, csv::Error>>().map_err(|e| {
        let line = e.position().map_or(0, |p| p.line());
        let what = match e.kind() {
            csv::ErrorKind::UnequalLengths { len, expected_len, .. } => {
                format!("{len} fields, the header has {expected_len}")
            }
            _ => e.to_string(),
        };
        bad(line, what)
    })?;
    if !text.ends_with(b"\n") {
        let lines = text.split(|b| *b == b'\n').count() as u64;
        return Err(bad(lines, "the last line ends without a line break".into()));
    }
    Ok(rows)
}
