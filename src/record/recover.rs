//! Recovery of a recording folder when a run resumes: the index is rebuilt from the shards
//! themselves where it is missing, corrupt or incomplete, and nothing the checkpoint covers
//! is ever deleted. Only shards of generations after the checkpoint (left by a generation
//! that was being recorded when the run stopped) and temporary files are removed. A covered
//! shard that must be re-indexed but cannot be read stops the recovery before anything is
//! removed (its designs would silently leave the index); a covered generation without a
//! shard is reported, and stays visible as a gap in the index's ids.
//!
//! A shard's index line is rebuilt from the MCAP file alone, without decoding any message
//! payload: the generation, the first and last design ids and the number of designs from
//! its `gripopt.run` metadata record; where a key is missing, the generation from the file
//! name, the ids from the chunk indexes' log times (design k lives in
//! [epoch + k s, epoch + k s + 1 s), `epoch_s` from the same record, else 0) and the count
//! from the `/designs` channel's statistics; the size from the file system.

use super::index::ShardEntry;
use crate::{Error, Result};
use std::path::Path;

/// What recovery did to a recording folder.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recovery {
    /// The index after recovery (sorted by generation).
    pub index: Vec<ShardEntry>,
    /// Index lines rebuilt from shards (the index was missing, corrupt or lacked them).
    pub rebuilt: Vec<String>,
    /// Files removed (shards of generations after the checkpoint, temporary files).
    pub removed: Vec<String>,
    /// Generations the checkpoint covers that have no shard (moved away or lost): their
    /// designs are not in the recording; the index keeps the gap in ids, which
    /// [`read_design`](super::read_design) names.
    pub missing: Vec<u64>,
}

impl Recovery {
    /// One warning per run of consecutive generations without a shard (see `missing`),
    /// naming the recording folder `dir`, the generations and the shard files.
    pub fn warnings(&self, dir: &Path) -> Vec<String> {
        let mut out = vec![];
        let mut k = 0;
        while k < self.missing.len() {
            let a = self.missing[k];
            let mut b = a;
            while k + 1 < self.missing.len() && self.missing[k + 1] == b + 1 {
                k += 1;
                b += 1;
            }
            k += 1;
            let (gens, files) = if a == b {
                (format!("generation {a} has"), format!("gen-{a:05}.mcap"))
            } else {
                (format!("generations {a}..={b} have"), format!("gen-{a:05}.mcap..gen-{b:05}.mcap"))
            };
            out.push(format!("{}: {gens} no shard ({files}): those designs are not in the recording; restore the file(s) and resume again to index them", dir.display()));
        }
        out
    }
}

/// Generation from a shard file name `gen-NNNNN.mcap`.
pub fn shard_generation(name: &str) -> Option<u64> {
    name.strip_prefix("gen-")?.strip_suffix(".mcap")?.parse().ok()
}

/// Rebuild the index line of one shard from the file (see the module doc).
pub fn index_entry_from_shard(path: &Path) -> Result<ShardEntry> {
    let file = path.file_name().and_then(|s| s.to_str()).unwrap_or_default().to_string();
    let bad = |message: String| Error::Recording { path: path.to_path_buf(), message };
    let buf = std::fs::read(path).map_err(|e| Error::io(path, "cannot read the shard", e))?;
    let summary = mcap::Summary::read(&buf)
        .map_err(|source| Error::DamagedRecording {
            path: path.to_path_buf(),
            what: "cannot read the MCAP summary (the file is truncated or damaged)".into(),
            source: source.into(),
        })?
        .ok_or_else(|| bad("no MCAP summary; the file is truncated or corrupt".into()))?;
    let (mut generation, mut first, mut last, mut count, mut epoch_s) = (None, None, None, None, 0u64);
    for mi in summary.metadata_indexes.iter().filter(|m| m.name == "gripopt.run") {
        let m = mcap::read::metadata(&buf, mi).map_err(|source| Error::DamagedRecording {
            path: path.to_path_buf(),
            what: "cannot read the metadata record".into(),
            source: source.into(),
        })?;
        let num = |k: &str| m.metadata.get(k).and_then(|g| g.parse::<u64>().ok());
        generation = num("generation");
        first = num("first_id");
        last = num("last_id");
        count = num("designs");
        epoch_s = num("epoch_s").unwrap_or(0);
    }
    let generation = generation
        .or_else(|| shard_generation(&file))
        .ok_or_else(|| bad("no generation in the metadata or the file name".into()))?;
    let start = summary.chunk_indexes.iter().map(|c| c.message_start_time).min();
    let end = summary.chunk_indexes.iter().map(|c| c.message_end_time).max();
    let (Some(start), Some(end)) = (start, end) else { return Err(bad("the shard holds no messages".into())) };
    let designs_channel = summary.channels.values().find(|c| c.topic == "/designs").map(|c| c.id);
    let designs = count
        .or(match (&summary.stats, designs_channel) {
            (Some(st), Some(ch)) => st.channel_message_counts.get(&ch).copied(),
            _ => None,
        })
        .unwrap_or(summary.chunk_indexes.len() as u64);
    let bytes = buf.len() as u64;
    let id_at = |t: u64| (t / 1_000_000_000).saturating_sub(epoch_s);
    Ok(ShardEntry {
        generation,
        file,
        first_id: first.unwrap_or(id_at(start)),
        last_id: last.unwrap_or(id_at(end)),
        designs,
        bytes,
    })
}

/// What is wrong with a shard, without its path (the caller names it).
fn detail(e: &Error) -> String {
    match e {
        Error::DamagedRecording { what, source, .. } => format!("{what}: {source}"),
        Error::Recording { message, .. } => message.clone(),
        Error::Io { action, source, .. } => format!("{action}: {source}"),
        e => e.to_string(),
    }
}

/// Recover the recording folder `dir` of a run whose checkpoint covers generations
/// `1..=completed`: keep every shard of those generations in the index (rebuilding lines
/// the index lacks), remove shards of later generations and `.tmp` files. Writes nothing
/// else; the caller writes the returned index.
///
/// A shard of a covered generation whose index line must be rebuilt but which cannot be
/// read is an error ([`Error::Recording`], naming the shard), returned before anything is
/// removed: its designs would otherwise vanish from the index. A covered generation with
/// no shard at all (moved away) is reported in [`Recovery::missing`].
pub fn recover(dir: &Path, completed: u64) -> Result<Recovery> {
    let idx_path = dir.join("index.jsonl");
    let text = match std::fs::read_to_string(&idx_path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(Error::io(&idx_path, "cannot read the recording index", e)),
    };
    // lines that parse and name an existing shard are kept; anything else is rebuilt
    let mut listed: Vec<ShardEntry> = text.lines().filter_map(|l| serde_json::from_str::<ShardEntry>(l).ok()).collect();
    let mut out = Recovery::default();
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list the recording folder", e))?;
    let mut names: Vec<String> = rd.flatten().map(|f| f.file_name().to_string_lossy().to_string()).collect();
    names.sort();
    listed.retain(|e| names.contains(&e.file) && shard_generation(&e.file) == Some(e.generation));
    // first every covered shard (reading only), so that an error leaves the folder untouched
    let mut remove = vec![];
    for n in &names {
        if n.ends_with(".tmp") {
            remove.push(n.clone());
            continue;
        }
        let Some(g) = shard_generation(n) else { continue };
        if g > completed {
            remove.push(n.clone());
            continue;
        }
        let p = dir.join(n);
        if let Some(e) = listed.iter().find(|e| &e.file == n) {
            let size = std::fs::metadata(&p).map(|m| m.len()).ok();
            if size == Some(e.bytes) {
                out.index.push(e.clone());
                continue;
            }
        }
        let refuse = |why: String| {
            Error::Recording {
            path: p.clone(),
            message: format!("{why}; the index cannot be rebuilt without it (generation {g} is covered by the checkpoint): restore the file, or move it away to resume without its designs"),
        }
        };
        match index_entry_from_shard(&p) {
            Ok(e) if e.generation == g => {
                out.rebuilt.push(n.clone());
                out.index.push(e);
            }
            Ok(e) => {
                return Err(refuse(format!(
                    "its metadata names generation {}, its file name generation {g}",
                    e.generation
                )))
            }
            Err(e) => return Err(refuse(format!("cannot read its metadata ({})", detail(&e)))),
        }
    }
    out.index.sort_by_key(|e| e.generation);
    out.missing = (1..=completed).filter(|g| !out.index.iter().any(|e| e.generation == *g)).collect();
    for n in remove {
        let p = dir.join(&n);
        let what = if n.ends_with(".tmp") {
            "cannot remove the temporary file"
        } else {
            "cannot remove the shard of a generation after the checkpoint"
        };
        std::fs::remove_file(&p).map_err(|e| Error::io(&p, what, e))?;
        out.removed.push(n);
    }
    Ok(out)
}
