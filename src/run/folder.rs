//! Reading a run folder back, typed ([`RunFolder`]): run.json, the CSV tables (read with
//! the csv crate into the rows they were written from), the recorded designs (their
//! `/designs` record and trajectory from the MCAP shards) and replay. What `gripopt show`,
//! `verify` and the Python package read.

use super::outputs::{DesignRow, HistoryRow};
use super::rundir::RunInfo;
use crate::params::Problem;
use crate::record::{read_design, replay, Recorded, Replay};
use crate::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A run folder written by `optimise`/`resume` (it may be running: its files are rewritten
/// whole, atomically, every generation).
#[derive(Debug, Clone)]
pub struct RunFolder {
    dir: PathBuf,
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
        let p = self.dir.join("run.json");
        let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, "cannot read (is this a run folder?)", e))?;
        serde_json::from_str(&text).map_err(|source| Error::Json { path: p, what: "invalid run.json", source })
    }
    /// The run's problem (its copy in the folder).
    pub fn problem(&self) -> Result<Problem> {
        Problem::load(self.dir.join("problem.toml"))
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
    let text = std::fs::read(path)
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
