//! Which recorded designs are on the run's final Pareto front: `RUN_DIR/recording/front.mcap`,
//! written with the run's final outputs (at the end of `optimise` and of every `resume`,
//! replacing the previous one), because the front is known only when the last generation is
//! done, long after the shards of the earlier generations were written.
//!
//! One `/front` message (JSON, `gripopt.Front`) per recorded design, at the start of the
//! design's window (epoch + id s, as in the shards): opened together with the shards, the
//! latest `/front` message at any instant is the design under the playhead's (the layout's
//! "Final front" indicator shows it). Metadata record `gripopt.front`: `designs`, `first_id`,
//! `last_id`, `front_size`, `generations`, `epoch_s`, `status`.

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

/// File name of the front recording inside `RUN_DIR/recording/`.
pub const FRONT_FILE: &str = "front.mcap";
/// Name of its metadata record.
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

/// Write `RUN_DIR/recording/front.mcap` for every design of the recording's index, with
/// `front` the ids of the final front; `meta` is added to the metadata record (e.g. the run's
/// `status`). Nothing when recording is off or the run has no recording folder.
pub fn write_front(
    run_dir: &Path,
    opts: &RecordOptions,
    front: &[u64],
    generations: u64,
    meta: &RunMetadata,
) -> Result<Option<PathBuf>> {
    let dir = run_dir.join("recording");
    if !opts.enabled || !dir.join("index.jsonl").is_file() {
        return Ok(None);
    }
    let ids: Vec<u64> = read_index(&dir)?.iter().flat_map(|e| e.first_id..=e.last_id).collect();
    let on_front: BTreeSet<u64> = front.iter().copied().collect();
    let path = dir.join(FRONT_FILE);
    let tmp = super::mcapfile::temporary(&path);
    let mc = super::mcapfile::error(&tmp);
    let mut w = super::mcapfile::open(&tmp, opts.zstd_level, 0)?;
    let meta = RunMetadata {
        designs: Some(ids.len() as u64),
        // written empty for a recording of no design
        first_id: Some(ids.first().copied()),
        last_id: Some(ids.last().copied()),
        front_size: Some(on_front.len() as u64),
        generations: Some(generations),
        epoch_s: Some(opts.epoch_s),
        time_convention: Some("design k: /front at epoch_s + k s (its window start in the shards)".into()),
        ..meta.clone()
    };
    w.write_metadata(&Metadata { name: FRONT_METADATA.into(), metadata: meta.to_map() }).map_err(mc)?;
    let schema = w
        .add_schema("gripopt.Front", "jsonschema", &serde_json::to_vec(&front_schema()).expect("schema serialises"))
        .map_err(mc)?;
    let channel = w.add_channel(schema, "/front", "json", &BTreeMap::new()).map_err(mc)?;
    for (k, &id) in ids.iter().enumerate() {
        let r = FrontRecord {
            id,
            on_final_front: on_front.contains(&id),
            final_front_size: on_front.len() as u64,
            generations,
        };
        let t = window_start_ns(opts.epoch_ns(), id);
        let header = MessageHeader { channel_id: channel, sequence: k as u32 + 1, log_time: t, publish_time: t };
        w.write_to_known_channel(&header, &serde_json::to_vec(&r).expect("records serialise")).map_err(mc)?;
        if (k + 1) % 1000 == 0 {
            w.flush().map_err(mc)?;
        }
    }
    super::mcapfile::finish(w, &tmp, &path)?;
    Ok(Some(path))
}
