//! What a run folder holds, and what `optimise` and `resume` may do with it: `optimise --out`
//! takes a new or empty folder, or one left by a run that never reached its first
//! checkpoint, whose files it can prove that run wrote (run.json names the run; the shards'
//! metadata name it too; problem.toml has the hash run.json recorded; the layout is
//! gripopt's; the CSV views start with gripopt's title line). A folder with recorded
//! generations is never taken for an empty one, and `resume` says why there is nothing to
//! resume, or which file is missing.

use super::info::{RunInfo, RunStatus, RUN_FILE};
use super::lock::LOCK_FILE;
use crate::error::shell_quote;
use crate::error::{Error, Result};
use crate::record::{index_entry_from_shard, layout, shard_generation, LAYOUT_FILE};
use std::path::{Path, PathBuf};

/// The CSV views a run writes every generation (before its first checkpoint too).
const VIEWS: [&str; 5] = super::outputs::VIEW_FILES;

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
    /// reached its first checkpoint wrote (provably: see the module doc). Returns that
    /// run's files, which the new run removes before it starts (everything but run.json,
    /// which it rewrites, and the lock's pid file).
    /// `problem` is the problem file given: when it is the folder's own `problem.toml` (a
    /// problem given as text, written there by the caller), it is the run's input, kept.
    pub fn check_new_run_folder(&self, problem: &Path) -> Result<Vec<PathBuf>> {
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
        let mut earlier = vec![];
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
            earlier.push(p);
        }
        for n in &self.recording_other {
            let tmp = n.ends_with(".tmp");
            if !(tmp || (n == "index.jsonl" && info.is_some())) {
                return Err(Error::RunDir {
                    path: rec.join(n),
                    message: "not a file of a run that never reached its first checkpoint; give a new or empty folder as --out".into(),
                });
            }
            earlier.push(rec.join(n));
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
            let ours = match n.as_str() {
                LOCK_FILE | RUN_FILE => true,
                "recording" => p.is_dir(),
                n if n.starts_with('.') && n.ends_with(".tmp") => true,
                _ => info.is_some_and(|i| self.proven(n, i)),
            };
            match ours {
                false => foreign.push(n.as_str()),
                true if ![LOCK_FILE, RUN_FILE, "recording"].contains(&n.as_str()) => earlier.push(p),
                true => {}
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

    /// `n` beside run.json `i` (of a run with no checkpoint) is provably that run's file.
    fn proven(&self, n: &str, i: &RunInfo) -> bool {
        let p = self.dir.join(n);
        let text = || crate::fsutil::read_regular_string(&p, crate::fsutil::caps::TABLE).unwrap_or_default();
        match n {
            "problem.toml" => crate::fsutil::sha256_hex(text().as_bytes()) == i.problem_sha256,
            LAYOUT_FILE => {
                let written = |s, f2| serde_json::to_string_pretty(&layout(s, f2)).is_ok_and(|l| l == text());
                [(true, false), (false, false), (true, true), (false, true)].iter().any(|&(s, f2)| written(s, f2))
            }
            n if VIEWS.contains(&n) => text().starts_with(&format!("# gripopt {n}")),
            // written beside the first checkpoint by a gripopt before issue 24
            "archive.json" => i.run_id.is_empty(),
            _ => false,
        }
    }
}

/// `a` and `b` are the same file (both exist and resolve to one path).
fn same_file(a: &Path, b: &Path) -> bool {
    matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}
