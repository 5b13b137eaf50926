//! Reading a run folder back, typed ([`RunFolder`]): run.json, the CSV tables (read with
//! the csv crate into the rows they were written from), the recorded designs (their
//! `/designs` record and trajectory from the MCAP shards; its replay is the app layer's); the run's state
//! (running, stopped, interrupted, finished: run.json and the folder's lock) and its problem
//! files, checked against the hashes run.json recorded. What `gripopt show`, `verify` and
//! the Python package read.

use super::info::{RunInfo, RunStatus};
use super::lock::{LockHolder, RunLock};
use super::outputs::{DesignRow, HistoryRow, DESIGN_COLUMNS, HISTORY_COLUMNS};
use super::robust_columns::is_robust_column;
use crate::params::Problem;
use crate::record::{problem_of_generation, read_design, Recorded, RunProblem};
use crate::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A run folder written by `optimise`/`resume` (it may be running: its files are rewritten
/// whole, atomically, every generation).
#[derive(Debug, Clone)]
pub struct RunFolder {
    dir: PathBuf,
    /// Opened with [`RunFolder::open_pinned`]: the run id of the run it reads (set when
    /// run.json is first read), which every read checks.
    pinned: Option<OnceLock<String>>,
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
        Ok(RunFolder { dir: dir.to_path_buf(), pinned: None })
    }
    /// The run folder `dir`, pinned to the run it holds: the run id run.json records now
    /// (or, where it cannot be read yet, when it is first read). Every later read checks
    /// that run.json still records that run, before and after it reads, and is an error
    /// naming the folder where it holds another run or none (the folder replaced by a copy
    /// of another run, say): what is read is always the opened run's.
    pub fn open_pinned(dir: impl AsRef<Path>) -> Result<Self> {
        let mut f = Self::open(dir)?;
        f.pinned = Some(OnceLock::new());
        f.check_run()?;
        Ok(f)
    }
    /// The run id run.json records now (empty where it records none: a run of a gripopt
    /// before issue 24, or `run_id` null); None where run.json is missing or unreadable
    /// (a field of the wrong type included: [`super::RunHeader::load`]).
    fn current_run_id(&self) -> Option<String> {
        super::RunHeader::load(&self.dir).ok().map(|h| h.run_id().to_string())
    }
    /// For a folder opened with [`RunFolder::open_pinned`]: an error when it no longer holds
    /// the run it was opened on (run.json records another run id, or cannot be read).
    pub fn check_run(&self) -> Result<()> {
        let Some(pin) = &self.pinned else { return Ok(()) };
        let now = self.current_run_id();
        let ours = match (pin.get(), &now) {
            (Some(ours), _) => ours,
            (None, Some(id)) => pin.get_or_init(|| id.clone()),
            // nothing pinned yet, nothing to pin: the read itself names the missing run.json
            (None, None) => return Ok(()),
        };
        if now.as_ref() == Some(ours) {
            return Ok(());
        }
        let shown = |id: &str| if id.is_empty() { "none".to_string() } else { id.to_string() };
        let holds = match now {
            Some(id) => format!("another run (run id {}, run.json)", shown(&id)),
            None => "another run or none (run.json is missing or unreadable)".to_string(),
        };
        Err(Error::RunDir {
            path: self.dir.clone(),
            message: format!(
                "the folder now holds {holds}, not the run it was opened on (run id {}): nothing of it is read as that run's; open the folder again to read the run it holds",
                shown(ours)
            ),
        })
    }
    /// `read`, with the folder's run checked before and after (a pinned folder).
    fn of_run<T>(&self, read: impl FnOnce() -> Result<T>) -> Result<T> {
        self.check_run()?;
        let r = read();
        self.check_run()?;
        r
    }
    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
    /// `run.json`: settings, status, generations, resumes.
    pub fn info(&self) -> Result<RunInfo> {
        self.of_run(|| RunInfo::load(&self.dir))
    }
    /// What the run is doing: run.json's status, told apart by the folder's lock (a run
    /// that says running but whose folder no process holds was killed).
    pub fn state(&self) -> Result<RunState> {
        self.of_run(|| {
            let info = RunInfo::load(&self.dir)?;
            Ok(match (info.status, RunLock::holder(&self.dir)?) {
                (RunStatus::Running, LockHolder::Held(pid)) => RunState::Running(pid),
                (RunStatus::Running, LockHolder::Free) => RunState::Stopped,
                (RunStatus::Interrupted, _) => RunState::Interrupted,
                (RunStatus::Finished, _) => RunState::Finished,
            })
        })
    }
    /// The run can be resumed: it has a checkpoint and no process holds it.
    pub fn resumable(&self) -> Result<bool> {
        self.of_run(
            || Ok(self.dir.join("checkpoint.json").is_file() && RunLock::holder(&self.dir)? == LockHolder::Free),
        )
    }
    /// The run's problem in force (`problem.toml`), checked against the hash run.json
    /// recorded: an edited copy is an error naming it.
    pub fn problem(&self) -> Result<Problem> {
        self.problem_in_force().map(|(p, _)| p)
    }
    /// [`RunFolder::problem`] with its file.
    pub fn problem_in_force(&self) -> Result<(Problem, PathBuf)> {
        self.of_run(|| {
            let g = RunInfo::load(&self.dir)?.problem_files().last().map_or(1, |p| p.first_generation);
            self.checked_problem(g)
        })
    }
    /// The problem generation `g` was evaluated with (after a forced resume with another
    /// problem, the earlier `problem-G.toml` for the generations before it), checked
    /// against the hash run.json recorded: an edited file is an error naming it.
    pub fn problem_of_generation(&self, g: u64) -> Result<Problem> {
        self.problem_file_of_generation(g).map(|(p, _)| p)
    }
    /// [`RunFolder::problem_of_generation`] with its file.
    pub fn problem_file_of_generation(&self, g: u64) -> Result<(Problem, PathBuf)> {
        self.of_run(|| self.checked_problem(g))
    }
    fn checked_problem(&self, g: u64) -> Result<(Problem, PathBuf)> {
        let p: RunProblem = problem_of_generation(&self.dir, g)?;
        match p.edited() {
            Some(why) => Err(Error::RunDir {
                path: p.file,
                message: format!("{why}: restore it (replay and verify need the problem the run used)"),
            }),
            // a problem without `solver.method` as the run evaluated it: with the method its
            // checkpoint records (RADAU5 for a run of before session 38)
            None => match super::checkpoint::recorded_method(&self.dir.join("checkpoint.json")) {
                Some(m) => Ok((p.problem.with_run_method(m), p.file)),
                None => Ok((p.problem, p.file)),
            },
        }
    }
    /// pareto.csv: the run's reported front (the best non-dominated designs it found;
    /// docs/outputs.md).
    pub fn front(&self) -> Result<Vec<DesignRow>> {
        self.of_run(|| read_design_table(&self.dir.join("pareto.csv")))
    }
    /// archive.csv: every feasible non-dominated design of the run.
    pub fn archive(&self) -> Result<Vec<DesignRow>> {
        self.of_run(|| read_design_table(&self.dir.join("archive.csv")))
    }
    /// population.csv: the whole population.
    pub fn population(&self) -> Result<Vec<DesignRow>> {
        self.of_run(|| read_design_table(&self.dir.join("population.csv")))
    }
    /// history.csv: one row per generation.
    pub fn history(&self) -> Result<Vec<HistoryRow>> {
        self.of_run(|| read_history(&self.dir.join("history.csv")))
    }
    /// Design `id` as recorded: its `/designs` record and trajectory (one chunk read).
    pub fn design(&self, id: u64) -> Result<Recorded> {
        self.of_run(|| read_design(&self.dir, id))
    }
}

/// The rows of pareto.csv, archive.csv or population.csv ([`read_table`]), whose header
/// must be the documented one: the columns of [`DESIGN_COLUMNS`] in order, then only a
/// robust problem's (`scenarios_run`, `scenarios_saved`, each object's `NAME.column`).
pub fn read_design_table(path: &Path) -> Result<Vec<DesignRow>> {
    read_table_with_header(path, |h| {
        let fixed = DESIGN_COLUMNS.map(|c| c.0);
        if h.len() < fixed.len() || h.iter().zip(fixed).any(|(a, b)| *a != b) {
            return Err(format!("expected the columns {}", fixed.join(",")));
        }
        match h.iter().skip(fixed.len()).find(|c| !is_robust_column(c)) {
            Some(c) => Err(format!(
                "column `{c}` is not one of a design table (after {}, only a robust problem's columns)",
                fixed.join(",")
            )),
            None => Ok(()),
        }
    })
}

/// The rows of history.csv ([`read_table`]), whose header must be [`HISTORY_COLUMNS`] (or, of a
/// gripopt before issue 42, its columns but the last: `pareto_hypervolume` empty).
pub fn read_history(path: &Path) -> Result<Vec<HistoryRow>> {
    read_table_with_header(path, |h| {
        let names = HISTORY_COLUMNS.map(|c| c.0);
        // a history.csv of a gripopt before issue 42 ends before `pareto_hypervolume`
        let of = |n: usize| h.len() == n && h.iter().zip(names).all(|(a, b)| *a == b);
        (of(names.len()) || of(names.len() - 1))
            .then_some(())
            .ok_or_else(|| format!("expected the columns {}", names.join(",")))
    })
}

/// A check of a table's column names: why they are not the documented ones.
type HeaderCheck<'a> = &'a dyn Fn(&[&str]) -> std::result::Result<(), String>;

/// [`read_table`] with the header (its column names) checked by `header` first: a header
/// that is not the documented one is an error naming the file, never read as a table of
/// no rows.
fn read_table_with_header<T: DeserializeOwned>(
    path: &Path,
    header: impl Fn(&[&str]) -> std::result::Result<(), String>,
) -> Result<Vec<T>> {
    read_checked_table(path, Some(&header))
}

/// The rows of one of the run's CSV tables (`#` lines are comments). A missing or
/// unreadable file, one without a header, a row cut short or a last line without its line
/// break (the files are written whole) is an error naming the file and line.
pub fn read_table<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    read_checked_table(path, None)
}

fn read_checked_table<T: DeserializeOwned>(path: &Path, header: Option<HeaderCheck<'_>>) -> Result<Vec<T>> {
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
    if let (Some(check), Ok(h)) = (header, r.headers()) {
        let names: Vec<&str> = h.iter().collect();
        check(&names).map_err(|why| Error::RunDir {
            path: path.to_path_buf(),
            message: format!(
                "the header line is not a gripopt table's ({why}; found {}): the file is damaged or not gripopt's",
                names.join(",")
            ),
        })?;
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
