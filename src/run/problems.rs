//! A run's problem files: `problem.toml` is the problem in force; a forced resume with a
//! changed problem keeps the earlier one as `problem-G.toml` (G: the first generation it
//! evaluated) and records in run.json's `problems` which file (and hash) evaluated which
//! generations, so that replay and verify use the right one. A problem file is written only
//! where none is, or over one whose content is a problem this run recorded (never over a
//! file edited by hand: that is refused, naming it).

use super::info::RunInfo;
use crate::error::{Error, Result};
use crate::fsutil::{sha256_hex, write_atomic};
use crate::params::Problem;
use crate::record::ProblemUse;
use std::path::Path;

/// The file name of the problem in force.
pub const PROBLEM_FILE: &str = "problem.toml";

/// The SHA-256 of a run folder's file `name` (None: no such file).
fn hash_of(dir: &Path, name: &str) -> Result<Option<String>> {
    let p = dir.join(name);
    match crate::fsutil::read_regular(&p, crate::params::MAX_FILE_BYTES) {
        Ok(b) => Ok(Some(sha256_hex(&b))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(Error::io(p, "cannot read the run's problem file", e)),
    }
}

/// The run's copy of its problem in force, `problem.toml`, is the one run.json recorded, or
/// missing (then written again from `problem` when that is the recorded problem); a copy
/// edited by hand is an error naming it (replay and verify would use it).
pub(crate) fn check_copy(dir: &Path, info: &RunInfo, problem: &Problem) -> Result<()> {
    let recorded: Vec<String> = info.problem_files().into_iter().map(|p| p.sha256).collect();
    match hash_of(dir, PROBLEM_FILE)? {
        Some(h) if recorded.contains(&h) => Ok(()),
        Some(h) => Err(Error::RunDir {
            path: dir.join(PROBLEM_FILE),
            message: format!(
                "edited after the run wrote it (sha256 {}; run.json records {}): replay and verify would use the edited problem. Restore it, or remove it and resume again (it is then written from {})",
                &h[..12],
                recorded.iter().map(|r| &r[..r.len().min(12)]).collect::<Vec<_>>().join(", "),
                info.problem_path.display()
            ),
        }),
        None => {
            let now = sha256_hex(problem.source_text.as_bytes());
            if recorded.last() == Some(&now) {
                write_atomic(&dir.join(PROBLEM_FILE), problem.source_text.as_bytes())
            } else {
                Ok(()) // a forced resume writes the new problem
            }
        }
    }
}

/// Before a resume from the checkpoint of generation `at` with `problem`: when its hash is
/// not the problem in force, keep the problem in force as `problem-G.toml` and record the
/// new one for generations `at + 1` on (in `info`; the caller writes run.json, then
/// [`write_current`]). Entries of generations after `at` (a forced resume from an older
/// checkpoint) are dropped. True when the problem changed.
pub(crate) fn switch(dir: &Path, info: &mut RunInfo, at: u64, problem: &Problem) -> Result<bool> {
    let now = sha256_hex(problem.source_text.as_bytes());
    let mut list: Vec<ProblemUse> = info.problem_files();
    let keep = list.iter().filter(|p| p.first_generation <= at.max(1)).count().max(1);
    list.truncate(keep);
    let changed = list.last().is_some_and(|p| p.sha256 != now);
    if changed {
        let last = list.last_mut().expect("a non-empty list");
        if last.file == PROBLEM_FILE {
            let kept = format!("problem-{}.toml", last.first_generation);
            let bytes = crate::fsutil::read_regular(&dir.join(PROBLEM_FILE), crate::params::MAX_FILE_BYTES)
                .map_err(|e| Error::io(dir.join(PROBLEM_FILE), "cannot read the run's problem to keep it", e))?;
            if sha256_hex(&bytes) != last.sha256 {
                return Err(Error::RunDir {
                    path: dir.join(PROBLEM_FILE),
                    message: format!("is not the problem generations {}..={at} were evaluated with (its sha256 differs from run.json's): it cannot be kept beside the new one; restore it", last.first_generation),
                });
            }
            if let Some(h) = hash_of(dir, &kept)?.filter(|h| *h != last.sha256) {
                return Err(Error::RunDir {
                    path: dir.join(&kept),
                    message: format!(
                        "exists and is not this run's earlier problem (sha256 {}): move it away",
                        &h[..12]
                    ),
                });
            }
            write_atomic(&dir.join(&kept), &bytes)?;
            last.file = kept;
        }
        list.push(ProblemUse { first_generation: at + 1, file: PROBLEM_FILE.into(), sha256: now.clone() });
    }
    info.problems = list;
    info.problem_sha256 = now;
    info.problem_name = problem.name.clone();
    Ok(changed)
}

/// Write `problem` as the run's `problem.toml` (where none is, or over one of this run's
/// recorded problems).
pub(crate) fn write_current(dir: &Path, info: &RunInfo, problem: &Problem) -> Result<()> {
    let recorded: Vec<String> = info.problem_files().into_iter().map(|p| p.sha256).collect();
    match hash_of(dir, PROBLEM_FILE)? {
        Some(h) if !recorded.contains(&h) && h != sha256_hex(problem.source_text.as_bytes()) => Err(Error::RunDir {
            path: dir.join(PROBLEM_FILE),
            message: "edited by hand: not overwritten; restore it or move it away".into(),
        }),
        _ => write_atomic(&dir.join(PROBLEM_FILE), problem.source_text.as_bytes()),
    }
}

/// A problem's robust object names, in order (None: not a robust problem).
fn robust_objects(problem: &Problem) -> Option<Vec<&str>> {
    problem.robust.as_ref().map(|r| r.objects.iter().map(|o| o.name.as_str()).collect())
}

/// A forced resume may change the problem, but not its robust objects (names, order, count)
/// nor whether it is robust: every table of the run (pareto.csv, population.csv,
/// archive.csv) has one fixed set of per-object `NAME.*` columns, and a row of another
/// object list would put one object's values under another's name. `old` is the problem
/// the checkpoint's generation was evaluated with, `new` the one in `new_path`.
pub(crate) fn check_same_objects(old: &Problem, new: &Problem, new_path: &Path) -> Result<()> {
    let (was, now) = (robust_objects(old), robust_objects(new));
    if was == now {
        return Ok(());
    }
    let list = |o: &Option<Vec<&str>>| match o {
        Some(names) => format!("robust objects [{}]", names.join(", ")),
        None => "not robust (no [robust])".to_string(),
    };
    Err(Error::RunDir {
        path: new_path.to_path_buf(),
        message: format!(
            "field `robust.objects`: the run was {}, the file now is {}; even with --force a resume cannot change the objects (names, order or count) or whether the problem is robust, because every table of the run has one fixed set of per-object columns. Start a new run (`gripopt optimise PROBLEM --out NEW_DIR`) for the new objects; nothing was changed",
            list(&was),
            list(&now)
        ),
    })
}
