//! run.json against checkpoint.json: run.json names the checkpoint it was written with
//! (`checkpoint_sha256`, the checkpoint's content checksum). A run.json restored from a
//! backup beside a newer checkpoint (or a checkpoint beside a newer run.json) would
//! otherwise be taken for the run's state: `show` would report the older totals, `verify`
//! would attribute its results to a state run.json never names, and `resume` would rewrite
//! run.json without the resumes and wall time it lost. `resume` and `verify` refuse such a
//! pair (naming run.json), `show` says so.

use super::info::{RunInfo, RunStatus, RUN_FILE};
use crate::error::{Error, Result};
use std::path::Path;

fn short(s: &str) -> &str {
    &s[..s.len().min(12)]
}

/// Why run.json (`info`) does not belong with the checkpoint of generation `generation`
/// whose content checksum is `sha256` (None: it does). A checkpoint one generation ahead of
/// a run.json that says running is the run's own (killed between the checkpoint and
/// run.json's update); `running`: a process holds the folder now (then run.json may lag
/// any number of generations behind, up to its requested total).
pub(crate) fn run_json_mismatch(info: &RunInfo, generation: u64, sha256: &str, running: bool) -> Option<String> {
    let recorded = info.checkpoint_sha256.as_deref()?;
    if recorded == sha256 {
        return None;
    }
    let c = info.completed_generations;
    let says_running = info.status == RunStatus::Running;
    let own_next = says_running && generation == c + 1;
    let while_running = running && says_running && generation > c && generation <= info.generations;
    if own_next || while_running {
        return None;
    }
    let what = format!(
        "run.json records {} of {} generations ({}) and checkpoint sha256 {}, but checkpoint.json holds generation {generation} (sha256 {})",
        c,
        info.generations,
        format!("{:?}", info.status).to_lowercase(),
        short(recorded),
        short(sha256)
    );
    let why = if generation > c {
        "run.json is older than the checkpoint (restored from a backup?): restore the run.json written with this checkpoint"
    } else if generation < c {
        "the checkpoint is older than run.json (restored from a backup?): restore the checkpoint.json written with this run.json"
    } else {
        "they were written by different copies of the run: restore the pair written together"
    };
    Some(format!("does not match checkpoint.json: {what}; {why}"))
}

/// [`run_json_mismatch`] as the error refusing to use the run folder `dir`.
pub(crate) fn check_run_json(dir: &Path, info: &RunInfo, generation: u64, sha256: &str) -> Result<()> {
    match run_json_mismatch(info, generation, sha256, false) {
        None => Ok(()),
        Some(message) => Err(Error::RunDir { path: dir.join(RUN_FILE), message }),
    }
}
