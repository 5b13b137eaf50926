//! `gripopt replay RUN_DIR --design ID` of a single-object free-kind run (`[scene] kind =
//! "free"`, no `[robust]`): besides the replay, the design's free scene — the optimisation's
//! own evaluation of it, whose verdict the record holds — recorded to `RUN_DIR/free-ID.mcap`
//! by verify's recorder ([`VerifyRecording::for_free`]), in its own second of band 3 of the
//! run's time axis (docs/recording.md, "Bands").

use super::info::RunInfo;
use super::lock::RunLock;
use super::verify::row_of;
use super::verify_rec::VerifyRecording;
use crate::eval::{evaluate_into, EvalOptions};
use crate::params::SceneKind;
use crate::record::VERIFY_METADATA;
use crate::sim::PoseSample;
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// What `replay` did about the free scene of a design.
#[derive(Debug, Clone, PartialEq)]
pub enum FreeRecording {
    /// Written to this file.
    Recorded(PathBuf),
    /// Not written, and why (the design never reached the free scene).
    NotRecorded(String),
}

/// The file name of design `id`'s free-scene recording.
pub fn free_file_name(id: u64) -> String {
    format!("free-{id}.mcap")
}

/// Record design `id`'s free scene of the run in `dir` when the problem its generation was
/// evaluated with is a single-object free-kind one (None otherwise: nothing written). Under
/// the run folder's lock (held by another process: not recorded, saying so); an existing `free-ID.mcap` is replaced only when a replay of this
/// run wrote it (its `gripopt.verify` metadata: `free_design` and this run's `run_id`),
/// otherwise refused naming it.
pub fn record_free_scene(
    dir: &Path,
    id: u64,
    generation: u64,
    design: &crate::params::Design,
) -> Result<Option<FreeRecording>> {
    let folder = super::folder::RunFolder::open(dir)?;
    let p = folder.problem_of_generation(generation)?;
    if p.scene.setup.kind != SceneKind::Free || p.robust.is_some() {
        return Ok(None);
    }
    // a run (or verify) in the folder: the replay still runs, the free scene waits for it
    let _lock = match RunLock::acquire(dir) {
        Err(e @ Error::Locked { .. }) => {
            return Ok(Some(FreeRecording::NotRecorded(format!("free scene not recorded: {e}"))));
        }
        l => l?,
    };
    let run_id = RunInfo::load(dir)?.run_id;
    let path = dir.join(free_file_name(id));
    check_replaceable(&path, &run_id)?;
    let mut poses: Vec<PoseSample> = vec![];
    let ev = evaluate_into(design, &p.scene, &EvalOptions::full(&p), &mut poses);
    let Some(row) = row_of(id, design, &ev) else {
        let why = ev.discard.as_ref().map_or("?".to_string(), |d| format!("stage {}: {}", d.stage, d.reason));
        return Ok(Some(FreeRecording::NotRecorded(format!(
            "free scene not recorded: the design was discarded before it (at {why}), so there is no motion of the object to record"
        ))));
    };
    let r = VerifyRecording::for_free(dir, &free_file_name(id), id, &run_id)?;
    let kept = crate::record::keep_poses(&poses, r.opts.scene_dt);
    Ok(Some(FreeRecording::Recorded(r.write(&p, vec![(row, kept)])?)))
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
pub(super) fn check_ours(
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
