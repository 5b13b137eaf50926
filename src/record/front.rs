//! Which recorded designs are on the run's final Pareto front: one small file for each
//! shard, `RUN_DIR/recording/front-NNNNN.mcap` (the front information of shard
//! `gen-NNNNN.mcap`), written with the run's final outputs (at the end of `optimise` and of
//! every `resume`, replacing the previous ones), because the front is known only when the
//! last generation is done, long after the shards of the earlier generations were written.
//!
//! One `/front` message (JSON, `gripopt.Front`) per design of the shard, at the start of the
//! design's window (epoch + id s, as in the shard): opened together with its shard (or with
//! several shards and theirs), the latest `/front` message at any instant is the design under
//! the playhead's (the layout's "Final front" indicator shows it), and the files span exactly
//! the shard's time range — the timeline starts at the shard's first design and is not
//! stretched over the whole run. Metadata record `gripopt.front`: `generation`, `designs`,
//! `first_id`, `last_id`, `front_size`, `generations`, `epoch_s`, `status`. (Until session 38
//! one `front.mcap` held a message for every design of the run; a run folder's own
//! `front.mcap` is removed when the per-shard files replace it.)

use super::index::read_index;
use super::messages::window_start_ns;
use super::metadata::RunMetadata;
use super::RecordOptions;
use crate::Result;
use mcap::records::{MessageHeader, Metadata};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// File name of the whole-run front recording written until session 38 (replaced by the
/// per-shard files, [`front_file`]).
pub const FRONT_FILE: &str = "front.mcap";

/// The front file of the shard of generation `generation` (`gen-NNNNN.mcap` →
/// `front-NNNNN.mcap`: not matched by `gen-*.mcap`, the shards' pattern).
pub fn front_file(generation: u64) -> String {
    format!("front-{generation:05}.mcap")
}

/// Name of the front files' metadata record.
pub const FRONT_METADATA: &str = "gripopt.front";

/// The `/front` message of one design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrontRecord {
    /// Design id.
    pub id: u64,
    /// On the run's final Pareto front (pareto.csv).
    pub on_final_front: bool,
    /// Designs on the final front.
    pub final_front_size: u64,
    /// Generations the run had completed when the front was taken.
    pub generations: u64,
}

/// JSON schema of `/front` (`gripopt.Front`).
pub fn front_schema() -> Value {
    let int = || json!({"type": "integer", "minimum": 0});
    json!({
        "title": "gripopt.Front", "type": "object",
        "properties": {"id": int(), "on_final_front": {"type": "boolean"}, "final_front_size": int(), "generations": int()},
        "required": ["id", "on_final_front", "final_front_size", "generations"]
    })
}

/// Write the front file of every shard of the recording's index (`front-NNNNN.mcap`,
/// [`front_file`]), with `front` the ids of the final front; `meta` is added to the metadata
/// records (e.g. the run's `status`). Removes the run folder's own whole-run `front.mcap` of an
/// earlier version (its `gripopt.front` metadata has this run's epoch), which the new files
/// replace. Nothing when recording is off or the run has no recording folder; the paths
/// written.
pub fn write_front(
    run_dir: &Path,
    opts: &RecordOptions,
    front: &[u64],
    generations: u64,
    meta: &RunMetadata,
) -> Result<Vec<PathBuf>> {
    let dir = run_dir.join("recording");
    if !opts.enabled || !dir.join("index.jsonl").is_file() {
        return Ok(vec![]);
    }
    let on_front: BTreeSet<u64> = front.iter().copied().collect();
    let mut written = vec![];
    for e in read_index(&dir)? {
        let path = dir.join(front_file(e.generation));
        let meta = RunMetadata { generation: Some(e.generation), ..meta.clone() };
        write_front_file(&path, opts, &on_front, e.first_id..=e.last_id, generations, &meta)?;
        written.push(path);
    }
    remove_whole_run_front(&dir.join(FRONT_FILE), opts.epoch_s);
    Ok(written)
}

/// Write the front file `path` of designs `ids` (one shard's).
fn write_front_file(
    path: &Path,
    opts: &RecordOptions,
    on_front: &BTreeSet<u64>,
    ids: std::ops::RangeInclusive<u64>,
    generations: u64,
    meta: &RunMetadata,
) -> Result<()> {
    let tmp = super::mcapfile::temporary(path);
    let mc = super::mcapfile::error(&tmp);
    let mut w = super::mcapfile::open(&tmp, opts.zstd_level, 0)?;
    let meta = RunMetadata {
        designs: Some(ids.clone().count() as u64),
        first_id: Some(Some(*ids.start())),
        last_id: Some(Some(*ids.end())),
        front_size: Some(on_front.len() as u64),
        generations: Some(generations),
        epoch_s: Some(opts.epoch_s),
        time_convention: Some("design k: /front at epoch_s + k s (its window start in its shard)".into()),
        ..meta.clone()
    };
    w.write_metadata(&Metadata { name: FRONT_METADATA.into(), metadata: meta.to_map() }).map_err(mc)?;
    let schema = w
        .add_schema("gripopt.Front", "jsonschema", &serde_json::to_vec(&front_schema()).expect("schema serialises"))
        .map_err(mc)?;
    let channel = w.add_channel(schema, "/front", "json", &BTreeMap::new()).map_err(mc)?;
    for (k, id) in ids.enumerate() {
        let r = FrontRecord {
            id,
            on_final_front: on_front.contains(&id),
            final_front_size: on_front.len() as u64,
            generations,
        };
        let t = window_start_ns(opts.epoch_ns(), id);
        let header = MessageHeader { channel_id: channel, sequence: k as u32 + 1, log_time: t, publish_time: t };
        w.write_to_known_channel(&header, &serde_json::to_vec(&r).expect("records serialise")).map_err(mc)?;
    }
    super::mcapfile::finish(w, &tmp, path)?;
    Ok(())
}

/// Remove `path`, a whole-run `front.mcap` an earlier gripopt wrote for this run (its
/// `gripopt.front` metadata has the run's epoch `epoch_s`); anything else there is left
/// alone. Best effort: the per-shard files are written whatever happens here.
fn remove_whole_run_front(path: &Path, epoch_s: u64) {
    let Ok(bytes) = crate::fsutil::read_regular(path, 1 << 30) else { return };
    let ours = mcap::Summary::read(&bytes)
        .ok()
        .flatten()
        .and_then(|s| s.metadata_indexes.iter().find(|m| m.name == FRONT_METADATA).cloned())
        .and_then(|mi| mcap::read::metadata(&bytes, &mi).ok())
        .is_some_and(|m| m.metadata.get("epoch_s").is_some_and(|e| *e == epoch_s.to_string()));
    if ours {
        let _ = std::fs::remove_file(path);
    }
}
