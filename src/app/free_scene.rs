//! `gripopt replay RUN_DIR --design ID` of a single-object free-kind run (`[scene] kind =
//! "free"`, no `[robust]`): besides the replay, the design's free scene — the replay's own
//! re-evaluation of it, whose verdict the record holds — recorded to `RUN_DIR/free-ID.mcap`
//! by verify's recorder (`VerifyRecording::for_free`), in its own second of band 3 of the
//! run's time axis (docs/recording.md, "Bands"). The recording is a side effect: where it
//! cannot be written (another process holds the folder, a read-only folder, a full disk) the
//! replay's verdict stands and says why.

use super::replay::Replay;
use crate::error::{Error, Result};
use crate::record::VERIFY_METADATA;
use crate::run::{row_of, RunInfo, RunLock, VerifyRecording};
use std::path::{Path, PathBuf};

/// What `replay` did about the free scene of a design.
#[derive(Debug, Clone, PartialEq)]
pub enum FreeRecording {
    /// Written to this file.
    Recorded(PathBuf),
    /// Not written, and why (the design never reached the free scene, or the file could
    /// not be written).
    NotRecorded(String),
}

/// The file name of design `id`'s free-scene recording.
pub fn free_file_name(id: u64) -> String {
    format!("free-{id}.mcap")
}

/// Record the free scene of `replay` (design `id` of the run in `dir`) when the problem its
/// generation was evaluated with is a single-object free-kind one and the replay could use
/// it (None otherwise: nothing written). Under the run folder's lock. What stops the
/// recording without saying anything of the design — the folder held by another process, a
/// file that cannot be written (a read-only folder, a full disk) — is reported as
/// [`FreeRecording::NotRecorded`], so the replay's verdict stands; an existing
/// `free-ID.mcap` is replaced only when a replay of this run wrote it (its `gripopt.verify`
/// metadata: `free_design` and this run's `run_id`), otherwise refused naming it.
pub fn record_free_scene(dir: &Path, replay: &Replay) -> Result<Option<FreeRecording>> {
    let Some(free) = &replay.free_scene else { return Ok(None) };
    match write_free_scene(dir, replay, free) {
        Err(e @ (Error::Locked { .. } | Error::Io { .. } | Error::Mcap { .. })) => {
            Ok(Some(FreeRecording::NotRecorded(format!("free scene not recorded: {e}"))))
        }
        r => r.map(Some),
    }
}

/// Write `free-ID.mcap` of the replayed design.
fn write_free_scene(dir: &Path, replay: &Replay, free: &super::replay::FreeScene) -> Result<FreeRecording> {
    let id = replay.recorded.record.id;
    // a run (or verify) in the folder: the replay still runs, the free scene waits for it
    let _lock = RunLock::acquire(dir)?;
    let run_id = RunInfo::load(dir)?.run_id;
    let path = dir.join(free_file_name(id));
    check_replaceable(&path, &run_id)?;
    let design = replay.recorded.design();
    let Some(row) = free.evaluation.as_ref().and_then(|ev| row_of(id, &design, ev)) else {
        let why = replay.fresh.verdict.failed_stage.map_or("?".to_string(), |s| {
            format!("stage {s}: {}", replay.fresh.verdict.reason.as_deref().unwrap_or("?"))
        });
        return Ok(FreeRecording::NotRecorded(format!(
            "free scene not recorded: the design was discarded before it (at {why}), so there is no motion of the object to record"
        )));
    };
    let r = VerifyRecording::for_free(dir, &free_file_name(id), id, &run_id)?;
    let kept = crate::record::keep_poses(&free.poses, r.opts.scene_dt);
    Ok(FreeRecording::Recorded(r.write(&free.problem, vec![(row, kept)])?))
}

/// An existing `path` may be replaced only when it is a regular file this run's replay wrote.
fn check_replaceable(path: &Path, run_id: &str) -> Result<()> {
    let what = format!("a free-scene recording `replay` wrote for this run (run id {run_id})");
    check_ours(path, &what, |m| {
        if m.free_design.is_some() && m.run_id.as_deref() == Some(run_id) {
            Ok(())
        } else {
            Err(format!("written by another run or command (run id {})", m.run_id.as_deref().unwrap_or("none")))
        }
    })
}

/// An existing `path` (a file `replay` writes into a run folder) may be replaced only when
/// it is a regular, readable MCAP whose `gripopt.verify` metadata `ours` accepts (Err: why
/// not); otherwise an error naming it, saying it is not `what` and that nothing was done.
pub(crate) fn check_ours(
    path: &Path,
    what: &str,
    ours: impl Fn(&crate::record::RunMetadata) -> std::result::Result<(), String>,
) -> Result<()> {
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(());
    }
    let refuse = |why: &str| Error::RunDir {
        path: path.to_path_buf(),
        message: format!("{why}: it is not {what}; move it away to record it again (nothing was done)"),
    };
    let bytes = crate::fsutil::read_regular(path, 1 << 30).map_err(|_| refuse("not a readable regular file"))?;
    let summary = mcap::Summary::read(&bytes).ok().flatten().ok_or_else(|| refuse("not a readable MCAP"))?;
    let meta = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == VERIFY_METADATA)
        .and_then(|mi| mcap::read::metadata(&bytes, mi).ok())
        .ok_or_else(|| refuse("no gripopt.verify metadata"))?;
    let meta = crate::record::RunMetadata::from_map(&meta.metadata).map_err(|why| refuse(&why))?;
    ours(&meta).map_err(|why| refuse(&why))
}
