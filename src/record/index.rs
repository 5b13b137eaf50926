//! `recording/index.jsonl`: one line per shard ([`ShardEntry`]: its generation, file, id
//! range, designs and size, and what it is attributed to: the run and the problem it was
//! evaluated with), read and written whole; and which problem file of a run folder
//! evaluated which generations ([`ProblemUse`], kept in run.json).

use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
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
    /// The run that wrote the shard (run.json's `run_id`; absent in recordings of a gripopt
    /// before issue 24).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run_id: Option<String>,
    /// SHA-256 of the problem file the shard's designs were evaluated with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub problem_sha256: Option<String>,
}

/// A problem file of a run folder and the generations evaluated with it (run.json's
/// `problems`): a forced resume with a changed problem keeps the earlier file as
/// `problem-G.toml` (G its first generation) and writes the new one as `problem.toml`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProblemUse {
    /// First generation evaluated with it (it evaluated every later one up to the next
    /// entry's first generation).
    pub first_generation: u64,
    /// File name in the run folder.
    pub file: String,
    /// SHA-256 of the file.
    pub sha256: String,
}

impl ProblemUse {
    /// The entry of `list` that evaluated generation `g` (the last one starting at or
    /// before it; the first entry for generation 0).
    pub fn of_generation(list: &[ProblemUse], g: u64) -> Option<&ProblemUse> {
        list.iter().rev().find(|p| p.first_generation <= g).or(list.first())
    }
}

/// Read `index.jsonl` of a recording folder (errors name the file and line).
pub fn read_index(dir: &Path) -> Result<Vec<ShardEntry>> {
    let p = dir.join("index.jsonl");
    let text = crate::fsutil::read_regular_string(&p, crate::fsutil::caps::INDEX)
        .map_err(|e| Error::io(&p, "cannot read the recording index", e))?;
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
