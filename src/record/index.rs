//! `recording/index.jsonl`: one line per shard ([`ShardEntry`]: its generation, file, id
//! range, designs and size), read and written whole.

use crate::fsutil::write_atomic;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One line of `index.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardEntry {
    /// Generation.
    pub generation: u64,
    /// File name inside `recording/`.
    pub file: String,
    /// Smallest design id in the shard.
    pub first_id: u64,
    /// Largest design id.
    pub last_id: u64,
    /// Number of designs.
    pub designs: u64,
    /// File size (bytes).
    pub bytes: u64,
}

/// Read `index.jsonl` of a recording folder (errors name the file and line).
pub fn read_index(dir: &Path) -> Result<Vec<ShardEntry>> {
    let p = dir.join("index.jsonl");
    let text = std::fs::read_to_string(&p).map_err(|e| Error::io(&p, "cannot read the recording index", e))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            serde_json::from_str(l)
                .map_err(|e| Error::Recording { path: p.clone(), message: format!("line {}: {e}", k + 1) })
        })
        .collect()
}

pub(crate) fn write_index(dir: &Path, entries: &[ShardEntry]) -> Result<()> {
    let path = dir.join("index.jsonl");
    let mut s = String::new();
    for e in entries {
        s.push_str(&serde_json::to_string(e).map_err(|source| Error::Json {
            path: path.clone(),
            what: "cannot serialise an index line",
            source,
        })?);
        s.push('\n');
    }
    write_atomic(&path, s.as_bytes())
}
