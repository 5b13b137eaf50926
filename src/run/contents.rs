//! What a run folder holds, and what `optimise` and `resume` may do with it: `optimise --out`
//! takes a new or empty folder, or one left by a run that never reached its first
//! checkpoint. Of that run's files, only those whose content proves they are its own are
//! removed (the shards whose metadata name the run run.json names; problem.toml with the
//! hash run.json recorded; the layout byte for byte as gripopt writes it; index lines naming
//! the run); what a name or a title line alone attributes (the CSV views, temporary files)
//! is set aside into `set-aside/` ([`crate::fsutil::set_aside`]), never removed. A folder
//! with recorded generations is never taken for an empty one, and `resume` says why there
//! is nothing to resume, or which file is missing.

use super::info::{RunInfo, RunStatus, RUN_FILE};
use super::lock::LOCK_FILE;
use crate::error::shell_quote;
use crate::error::{Error, Result};
use crate::fsutil::SET_ASIDE_DIR;
use crate::record::{index_entry_from_shard, run_layouts, shard_generation, ShardEntry, LAYOUT_FILE};
use std::path::{Path, PathBuf};

/// The CSV views a run writes every generation (before its first checkpoint too).
const VIEWS: [&str; 5] = super::outputs::VIEW_FILES;

/// What `optimise` does with the files of an earlier attempt that never reached its first
/// checkpoint, before it starts (see the module doc).
#[derive(Debug, Default)]
pub(crate) struct EarlierAttempt {
    /// Files whose content proves they are the earlier attempt's own: removed.
    pub remove: Vec<PathBuf>,
    /// Files only their name attributes: set aside (folder, name).
    pub set_aside: Vec<(PathBuf, String)>,
}

/// What a run folder holds, as far as `optimise` and `resume` care.
pub(crate) struct Scan {
    dir: PathBuf,
    /// The top-level names.
    names: Vec<String>,
    /// run.json, read (None: absent).
    pub run: Option<Result<RunInfo>>,
    /// checkpoint.json is there.
    pub checkpoint: bool,
    /// The shard files in recording/.
    pub shards: Vec<String>,
    /// The other names in recording/.
    recording_other: Vec<String>,
}

fn list(dir: &Path) -> Result<Vec<String>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list the folder", e))?;
    let mut v: Vec<String> = rd.flatten().map(|f| f.file_name().to_string_lossy().to_string()).collect();
    v.sort();
    Ok(v)
}

impl Scan {
    /// Look at `dir` (which exists).
    pub fn of(dir: &Path) -> Result<Scan> {
        let names = list(dir)?;
        let run = names.iter().any(|n| n == RUN_FILE).then(|| RunInfo::load(dir));
        let rec = dir.join("recording");
        let in_rec = if rec.is_dir() { list(&rec)? } else { vec![] };
        let (shards, recording_other) = in_rec.into_iter().partition(|n| shard_generation(n).is_some());
        Ok(Scan {
            dir: dir.to_path_buf(),
            checkpoint: names.iter().any(|n| n == "checkpoint.json"),
            names,
            run,
            shards,
            recording_other,
        })
    }

    fn err(&self, message: String) -> Error {
        Error::RunDir { path: self.dir.clone(), message }
    }

    fn quoted(&self) -> String {
        shell_quote(&self.dir.to_string_lossy())
    }

    fn shards_text(&self) -> String {
        match self.shards.len() {
            1 => "1 shard".to_string(),
            n => format!("{n} shards"),
        }
    }

    /// The error of a run whose checkpoint.json is missing although it completed
    /// generations (run.json says so).
    pub fn lost_checkpoint(&self, info: &RunInfo) -> Error {
        Error::RunDir {
            path: self.dir.join("checkpoint.json"),
            message: format!(
                "missing, but run.json records {} completed generations{} ({}): the run's state is lost with it. Restore checkpoint.json (e.g. from a backup) and run `gripopt resume {}`; gripopt will not start this run over its recorded generations (give another --out for a new run)",
                info.completed_generations,
                if info.status == RunStatus::Finished { " and a finished run" } else { "" },
                if self.shards.is_empty() { "no recording".to_string() } else { format!("recording/ holds {}", self.shards_text()) },
                self.quoted()
            ),
        }
    }

    /// Why `resume` has nothing to resume, or which file it misses, in a folder without
    /// checkpoint.json.
    pub fn no_checkpoint(&self) -> Error {
        match &self.run {
            None if self.shards.is_empty() => self.err(format!(
                "nothing to resume: the folder holds no run.json (the run stopped before it wrote one); start the run again with `gripopt optimise PROBLEM --out {}` (it reuses this folder)",
                self.quoted()
            )),
            None => Error::RunDir {
                path: self.dir.join(RUN_FILE),
                message: format!(
                    "missing (and checkpoint.json too), but recording/ holds {} of recorded generations: not a run gripopt can resume or start over; restore run.json and checkpoint.json (e.g. from a backup), or give `gripopt optimise` another --out",
                    self.shards_text()
                ),
            },
            Some(Err(e)) => self.err(format!("cannot tell which run this folder holds: {e}")),
            Some(Ok(info)) if info.completed_generations == 0 && info.status != RunStatus::Finished => self.err(format!(
                "nothing to resume: the run stopped before its first checkpoint; start it again with `{}` (it reuses this folder)",
                info.optimise_command(&self.dir)
            )),
            Some(Ok(info)) => self.lost_checkpoint(info),
        }
    }

    /// `optimise --out`: the folder is new or empty, or holds only what a run that never
    /// reached its first checkpoint wrote (see the module doc). Returns what the new run
    /// removes (content proves it the earlier attempt's) and sets aside (only a name or a
    /// title attributes it) before it starts; run.json, which it rewrites, the lock's pid
    /// file and `set-aside/` stay.
    /// `problem` is the problem file given: when it is the folder's own `problem.toml` (a
    /// problem given as text, written there by the caller), it is the run's input, kept.
    pub fn check_new_run_folder(&self, problem: &Path) -> Result<EarlierAttempt> {
        if self.checkpoint {
            return Err(self.err(format!(
                "already holds a run (checkpoint.json); use `gripopt resume {}` or another --out",
                self.quoted()
            )));
        }
        let info = match &self.run {
            None => None,
            Some(Ok(i)) => Some(i),
            Some(Err(e)) => {
                return Err(
                    self.err(format!("cannot tell which run this folder holds ({e}); give a new or empty folder"))
                )
            }
        };
        if let Some(i) = info.filter(|i| i.completed_generations > 0 || i.status == RunStatus::Finished) {
            return Err(self.lost_checkpoint(i));
        }
        let rec = self.dir.join("recording");
        let mut earlier = EarlierAttempt::default();
        for s in &self.shards {
            let p = rec.join(s);
            let e = index_entry_from_shard(&p);
            let ours = match (info, &e) {
                (Some(i), Ok(e)) => e.run_id.as_deref().unwrap_or_default() == i.run_id,
                _ => false,
            };
            if !ours {
                let why = match (&e, info) {
                    (_, None) => "and the folder has no run.json".to_string(),
                    (Ok(e), Some(_)) => {
                        format!("written by another run (run id {})", e.run_id.as_deref().unwrap_or("none"))
                    }
                    (Err(e), Some(_)) => format!("unreadable: {e}"),
                };
                return Err(Error::RunDir {
                    path: p,
                    message: format!("recorded designs ({why}): a folder with recorded generations ({} in recording/) is not an empty folder; resume its run, or give another --out", self.shards_text()),
                });
            }
            earlier.remove.push(p);
        }
        for n in &self.recording_other {
            let tmp = n.ends_with(".tmp");
            if n == SET_ASIDE_DIR && rec.join(n).is_dir() {
                continue;
            }
            if !(tmp || (n == "index.jsonl" && info.is_some())) {
                return Err(Error::RunDir {
                    path: rec.join(n),
                    message: "not a file of a run that never reached its first checkpoint; give a new or empty folder as --out".into(),
                });
            }
            match info {
                Some(i) if !tmp && index_names_only(&rec.join(n), &i.run_id) => earlier.remove.push(rec.join(n)),
                _ => earlier.set_aside.push((rec.clone(), n.clone())),
            }
        }
        let mut foreign = vec![];
        for n in &self.names {
            let p = self.dir.join(n);
            // a folder with a temporary file's name is no file of ours: left alone (a
            // write of that file then fails, naming it)
            if n.starts_with('.') && n.ends_with(".tmp") && p.is_dir() {
                continue;
            }
            if n == "problem.toml" && same_file(&p, problem) {
                continue;
            }
            let kept = [LOCK_FILE, RUN_FILE].contains(&n.as_str())
                || (["recording", SET_ASIDE_DIR].contains(&n.as_str()) && p.is_dir());
            if kept {
                continue;
            }
            let tmp = n.starts_with('.') && n.ends_with(".tmp");
            match info.map(|i| self.proven(n, i)) {
                Some(Proof::Content) => earlier.remove.push(p),
                Some(Proof::Title) => earlier.set_aside.push((self.dir.clone(), n.clone())),
                _ if tmp => earlier.set_aside.push((self.dir.clone(), n.clone())),
                _ => foreign.push(n.as_str()),
            }
        }
        if foreign.is_empty() {
            return Ok(earlier);
        }
        let shown: Vec<&str> = foreign.iter().copied().take(3).collect();
        Err(self.err(format!(
            "--out: the folder is not empty and is not a gripopt run that can be started over (it holds {}{}); give a new or empty folder",
            shown.join(", "),
            if foreign.len() > 3 { ", …" } else { "" }
        )))
    }

    /// What attributes `n` beside run.json `i` (of a run with no checkpoint) to that run.
    fn proven(&self, n: &str, i: &RunInfo) -> Proof {
        let p = self.dir.join(n);
        if !std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
            return Proof::None; // a link, folder, pipe: nothing gripopt wrote
        }
        let text = || crate::fsutil::read_regular_string(&p, crate::fsutil::caps::TABLE).unwrap_or_default();
        let proof = |content: bool| if content { Proof::Content } else { Proof::None };
        match n {
            "problem.toml" => proof(crate::fsutil::sha256_hex(text().as_bytes()) == i.problem_sha256),
            LAYOUT_FILE => {
                // a robust run's layout carries its problem's limits
                let problem = crate::params::Problem::load(self.dir.join("problem.toml")).ok();
                let layouts = run_layouts(problem.as_ref());
                proof(layouts.iter().any(|l| serde_json::to_string_pretty(l).is_ok_and(|l| l == text())))
            }
            // a title line names no run: any gripopt view (another run's, copied in) has it
            n if VIEWS.contains(&n) && text().starts_with(&format!("# gripopt {n}")) => Proof::Title,
            // written beside the first checkpoint by a gripopt before issue 24
            "archive.json" if i.run_id.is_empty() => Proof::Title,
            _ => Proof::None,
        }
    }
}

/// What attributes a file to a run that never reached its first checkpoint.
enum Proof {
    /// Its content: it is byte for byte what the run wrote (or names the run).
    Content,
    /// Only its name and gripopt's title line (another run's file would have them too).
    Title,
    /// Nothing.
    None,
}

/// Every line of the recording index `path` parses and names run `run_id` (an index only
/// that run wrote).
fn index_names_only(path: &Path, run_id: &str) -> bool {
    let Ok(text) = crate::fsutil::read_regular_string(path, crate::fsutil::caps::INDEX) else { return false };
    !run_id.is_empty()
        && text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .all(|l| serde_json::from_str::<ShardEntry>(l).is_ok_and(|e| e.run_id.as_deref() == Some(run_id)))
}

/// `a` and `b` are the same file (both exist and resolve to one path).
fn same_file(a: &Path, b: &Path) -> bool {
    matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// A new run's folder is never created inside another run's folder (its recording/ or any
/// folder below it): the nearest existing ancestor of `out` must not be, or lie inside, a run
/// folder (`crate::run_folder_around`; `out` itself being a run is the resume's case,
/// refused by the folder scan with its own message).
pub(super) fn refuse_run_inside_run(out: &Path) -> Result<()> {
    let existing =
        out.ancestors().skip(1).map(|a| if a.as_os_str().is_empty() { Path::new(".") } else { a }).find(|a| a.is_dir());
    let Some(dir) = existing else { return Ok(()) };
    match crate::fsutil::run_folder_around(&dir.join("_")) {
        Some((run, mark)) => Err(Error::RunDir {
            path: out.to_path_buf(),
            message: format!(
                "inside the run folder {} (it holds {mark}): a run is never created inside another run's folder; give a folder outside it",
                run.display()
            ),
        }),
        None => Ok(()),
    }
}
