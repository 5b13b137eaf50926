//! Recovery of a recording folder when a run resumes: the index is rebuilt from the shards
//! themselves where it is missing, unreadable, corrupt or incomplete (whatever the damage:
//! it is read as bytes, and every line is checked against its shard), every shard the
//! checkpoint covers is checked against what wrote it (its generation, and the run that
//! wrote it: an MCAP without a `gripopt.run` metadata record is another program's, never
//! this run's), and nothing the checkpoint covers is ever deleted. Shards of generations
//! after the checkpoint (left by a generation that was being recorded when the run stopped)
//! are removed when they are provably this run's (their metadata names it); one that
//! cannot be read, is not a regular file, or that another run or program wrote, is set
//! aside (moved into `recording/set-aside/`, never deleted), and so is a temporary file
//! (`*.tmp`: its content proves nothing, a name is no proof). A
//! covered shard whose summary or metadata cannot be read (listed in the index or not), or
//! that another run or program wrote, stops the recovery before anything is changed (its
//! designs would silently leave the index, or be taken for this run's); a covered
//! generation without a shard is reported, and stays visible as a gap in the index's ids.
//!
//! A shard's index line is rebuilt from the MCAP file alone (mapped, only its summary and
//! metadata read), without decoding any message payload: the generation, the first and last
//! design ids, the number of designs, the run id and the problem's hash from its
//! `gripopt.run` metadata record; where a key is missing, the generation from the file
//! name, the ids from the chunk indexes' log times (design k lives in
//! [epoch + k s, epoch + k s + 1 s), `epoch_s` from the same record, else 0) and the count
//! from the `/designs` channel's statistics; the size from the file system.

use super::index::ShardEntry;
use super::metadata::{RunMetadata, RUN_METADATA};
use crate::error::{Error, Result};
use std::path::Path;

/// What recovery did to a recording folder.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recovery {
    /// The index after recovery (sorted by generation).
    pub index: Vec<ShardEntry>,
    /// Index lines rebuilt from shards (the index was missing, corrupt or lacked them).
    pub rebuilt: Vec<String>,
    /// Files removed: this run's shards of generations after the checkpoint (their metadata
    /// names the run).
    pub removed: Vec<String>,
    /// Files set aside (moved into `recording/set-aside/`): shards of generations after the
    /// checkpoint that cannot be read or that another run wrote, temporary files.
    pub set_aside: Vec<String>,
    /// Where each of `set_aside` went, relative to the recording folder
    /// (`set-aside/NAME`, `set-aside/NAME.1` when taken).
    pub set_aside_as: Vec<String>,
    /// Generations the checkpoint covers that have no shard (moved away or lost): their
    /// designs are not in the recording; the index keeps the gap in ids, which
    /// [`read_design`](super::read_design) names.
    pub missing: Vec<u64>,
}

impl Recovery {
    /// One warning per run of consecutive generations without a shard (see `missing`),
    /// naming the recording folder `dir`, the generations and the shard files; one per
    /// file set aside.
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
        for (f, to) in self.set_aside.iter().zip(&self.set_aside_as) {
            let what = if f.ends_with(".tmp") {
                "is a temporary file (a write the run did not finish; its content proves nothing)"
            } else {
                "is not this run's shard (unreadable, not a regular file, or written by another run or program) and lies after the checkpoint"
            };
            out.push(format!("{}: {f} {what}: set aside as {to} (never deleted)", dir.display()));
        }
        out
    }
}

/// Generation from a shard file name `gen-NNNNN.mcap`.
pub fn shard_generation(name: &str) -> Option<u64> {
    name.strip_prefix("gen-")?.strip_suffix(".mcap")?.parse().ok()
}

/// Map the shard `path` for reading; refused (naming it, [`Error::Recording`]) when it is not
/// a regular file (a folder, or a FIFO whose open would wait for a writer forever).
pub(super) fn map_shard(path: &Path) -> Result<memmap2::Mmap> {
    let kind = std::fs::metadata(path).map_err(|e| Error::io(path, "cannot read the shard", e))?;
    if !kind.is_file() {
        return Err(Error::Recording {
            path: path.to_path_buf(),
            message: "not a regular file (a folder, pipe or device where a recording shard should be)".into(),
        });
    }
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, "cannot open the shard", e))?;
    // SAFETY: shards are written to a temporary name and renamed when complete; nothing
    // writes to a shard after that, so the mapping does not change under us.
    unsafe { memmap2::Mmap::map(&f) }.map_err(|e| Error::io(path, "cannot map the shard", e))
}

/// Whether `file` (an index line's) is a plain file name, one that stays inside
/// `recording/` (no folder, no `..`, not absolute).
pub(super) fn is_plain_name(file: &str) -> bool {
    let mut parts = Path::new(file).components();
    matches!((parts.next(), parts.next()), (Some(std::path::Component::Normal(_)), None))
}

/// Whether a shard read as `e` is not run `run_id`'s: it has no `gripopt.run` metadata
/// record (`gripopt` false: another program's MCAP), or its run id (none: empty, as in
/// recordings of a gripopt before issue 24) is not `run_id`. None: not checked.
fn foreign(run_id: Option<&str>, e: &ShardEntry, gripopt: bool) -> bool {
    !gripopt || run_id.is_some_and(|ours| e.run_id.as_deref().unwrap_or_default() != ours)
}

/// Who wrote a shard read as `e` (for a refusal): its run id, or no gripopt metadata.
fn origin(e: &ShardEntry, gripopt: bool) -> String {
    if gripopt {
        format!("run id {}", e.run_id.as_deref().filter(|r| !r.is_empty()).unwrap_or("none"))
    } else {
        "another program's MCAP: no gripopt.run metadata record".into()
    }
}

/// The MCAP summary of the shard `path` mapped as `buf` (an error naming it when the file
/// is truncated or damaged).
fn summary_of(path: &Path, buf: &[u8]) -> Result<mcap::Summary> {
    mcap::Summary::read(buf)
        .map_err(|source| Error::DamagedRecording {
            path: path.to_path_buf(),
            what: "cannot read the MCAP summary (the file is truncated or damaged)".into(),
            source: source.into(),
        })?
        .ok_or_else(|| Error::Recording {
            path: path.to_path_buf(),
            message: "no MCAP summary; the file is truncated or corrupt".into(),
        })
}

/// The `gripopt.run` metadata record of the shard `path` (mapped as `buf`, its `summary`
/// read); None: it has none (another program's MCAP).
fn metadata_of(path: &Path, buf: &[u8], summary: &mcap::Summary) -> Result<Option<RunMetadata>> {
    let mut meta = None;
    for mi in summary.metadata_indexes.iter().filter(|m| m.name == RUN_METADATA) {
        let m = mcap::read::metadata(buf, mi).map_err(|source| Error::DamagedRecording {
            path: path.to_path_buf(),
            what: "cannot read the metadata record".into(),
            source: source.into(),
        })?;
        meta = Some(
            RunMetadata::from_map(&m.metadata)
                .map_err(|message| Error::Recording { path: path.to_path_buf(), message })?,
        );
    }
    Ok(meta)
}

/// The `gripopt.run` metadata record of the MCAP file `path` (only its summary and that
/// record read): what a cleanup decides from (the run, or the benchmark, that wrote it);
/// None: another program's MCAP; an error when it cannot be read.
pub fn shard_metadata(path: &Path) -> Result<Option<RunMetadata>> {
    let buf = map_shard(path)?;
    let summary = summary_of(path, &buf)?;
    metadata_of(path, &buf, &summary)
}

/// Rebuild the index line of one shard from the file (see the module doc).
pub fn index_entry_from_shard(path: &Path) -> Result<ShardEntry> {
    read_shard(path).map(|(e, _)| e)
}

/// [`index_entry_from_shard`], and whether the file has a `gripopt.run` metadata record.
fn read_shard(path: &Path) -> Result<(ShardEntry, bool)> {
    let file = path.file_name().and_then(|s| s.to_str()).unwrap_or_default().to_string();
    let bad = |message: String| Error::Recording { path: path.to_path_buf(), message };
    let buf = map_shard(path)?;
    let summary = summary_of(path, &buf)?;
    let meta = metadata_of(path, &buf, &summary)?;
    let gripopt = meta.is_some();
    let meta = meta.unwrap_or_default();
    let (generation, first, last, count) =
        (meta.generation, meta.first_id.flatten(), meta.last_id.flatten(), meta.designs);
    let epoch_s = meta.epoch_s.unwrap_or(0);
    let (run_id, problem_sha256) = (meta.run_id, meta.problem_sha256);
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
    let entry = ShardEntry {
        generation,
        file,
        first_id: first.unwrap_or(id_at(start)),
        last_id: last.unwrap_or(id_at(end)),
        designs,
        bytes,
        run_id,
        problem_sha256,
    };
    Ok((entry, gripopt))
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

/// The lines of `index.jsonl` that parse, whatever else the file holds (bytes that are not
/// UTF-8, a cut line, garbage); none when it cannot be read at all.
fn readable_lines(path: &Path) -> Vec<ShardEntry> {
    let bytes = crate::fsutil::read_regular(path, crate::fsutil::caps::INDEX).unwrap_or_default();
    String::from_utf8_lossy(&bytes).lines().filter_map(|l| serde_json::from_str::<ShardEntry>(l).ok()).collect()
}

/// The shard files (`gen-NNNNN.mcap`) and the other names of the recording folder `dir`.
fn names(dir: &Path) -> Result<Vec<String>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list the recording folder", e))?;
    let mut names: Vec<String> = rd.flatten().map(|f| f.file_name().to_string_lossy().to_string()).collect();
    names.sort();
    Ok(names)
}

/// The index of the recording folder `dir` for a reader: `index.jsonl` when it can be read
/// and every line parses; otherwise (missing, unreadable, damaged: whatever the damage)
/// the index rebuilt from the shards themselves.
pub fn index_or_rebuilt(dir: &Path) -> Result<Vec<ShardEntry>> {
    match super::index::read_index(dir) {
        Ok(index) => Ok(index),
        Err(_) => rebuilt_index(dir),
    }
}

/// The index of the recording folder `dir` rebuilt in memory from its shards (unreadable
/// shards and MCAPs without a `gripopt.run` metadata record left out; nothing is written),
/// sorted by generation.
pub fn rebuilt_index(dir: &Path) -> Result<Vec<ShardEntry>> {
    let mut out = vec![];
    for n in names(dir)? {
        if shard_generation(&n).is_some() {
            if let Ok((e, true)) = read_shard(&dir.join(&n)) {
                out.push(e);
            }
        }
    }
    out.sort_by_key(|e| e.generation);
    Ok(out)
}

/// Recover the recording folder `dir` of a run whose checkpoint covers generations
/// `1..=completed` (see [`recover_run`]; no run id: shards are not checked for the run
/// that wrote them).
pub fn recover(dir: &Path, completed: u64) -> Result<Recovery> {
    recover_run(dir, completed, None)
}

/// Recover the recording folder `dir` of run `run_id` whose checkpoint covers generations
/// `1..=completed`: keep every shard of those generations in the index (rebuilding lines
/// the index lacks or gets wrong), remove this run's shards of later generations (their
/// metadata names `run_id`), set aside ([`crate::fsutil::set_aside`]) later shards that
/// are not provably this run's and `.tmp` files. Writes nothing else; the caller writes the
/// returned index.
///
/// A shard of a covered generation that another run wrote (its metadata's `run_id`; an MCAP
/// without a `gripopt.run` metadata record is another program's), or whose summary and
/// metadata cannot be read (damaged, truncated, not a regular file), whether it is listed
/// or not, is an error ([`Error::Recording`], naming the shard), returned before anything
/// is changed. A covered generation with no shard at all (moved away) is reported in
/// [`Recovery::missing`]. Only the summary and the metadata record of each shard are read:
/// damage inside a design's chunk is found when that design is read.
pub fn recover_run(dir: &Path, completed: u64, run_id: Option<&str>) -> Result<Recovery> {
    let mut listed = readable_lines(&dir.join("index.jsonl"));
    let mut out = Recovery::default();
    let names = names(dir)?;
    listed.retain(|e| names.contains(&e.file) && shard_generation(&e.file) == Some(e.generation));
    // first every shard (reading only), so that an error leaves the folder untouched
    let (mut remove, mut aside) = (vec![], vec![]);
    for n in &names {
        if n.ends_with(".tmp") {
            // a name proves nothing: set aside, never deleted
            aside.push(n.clone());
            continue;
        }
        let Some(g) = shard_generation(n) else { continue };
        let p = dir.join(n);
        let read = read_shard(&p);
        if g > completed {
            match read {
                // removed only when its metadata names this run (no run id to compare: set aside)
                Ok((e, gripopt)) if run_id.is_some() && !foreign(run_id, &e, gripopt) => remove.push(n.clone()),
                _ => aside.push(n.clone()),
            }
            continue;
        }
        let line = listed.iter().find(|l| &l.file == n);
        let refuse = |why: String| {
            let need = if line.is_some() {
                "a shard the checkpoint covers must be readable to resume"
            } else {
                "the index cannot be rebuilt without it"
            };
            Error::Recording {
                path: p.clone(),
                message: format!("{why}; {need} (generation {g} is covered by the checkpoint): restore the file, or move it away to resume without its designs"),
            }
        };
        match read {
            Ok((e, gripopt)) if foreign(run_id, &e, gripopt) => {
                return Err(Error::Recording {
                    path: p.clone(),
                    message: format!("written by another run ({}; this run's id {}): it is not this run's generation {g}; restore this run's shard, or move it away to resume without its designs", origin(&e, gripopt), run_id.filter(|r| !r.is_empty()).unwrap_or("none")),
                })
            }
            Ok((e, _)) if e.generation != g => {
                return Err(refuse(format!(
                    "its metadata names generation {}, its file name generation {g}",
                    e.generation
                )))
            }
            Ok((e, _)) => {
                let same = line.is_some_and(|l| {
                    (l.first_id, l.last_id, l.designs, l.bytes) == (e.first_id, e.last_id, e.designs, e.bytes)
                });
                if !same {
                    out.rebuilt.push(n.clone());
                }
                out.index.push(e);
            }
            Err(err) => return Err(refuse(format!("cannot read its summary and metadata ({})", detail(&err)))),
        }
    }
    out.index.sort_by_key(|e| e.generation);
    out.missing = (1..=completed).filter(|g| !out.index.iter().any(|e| e.generation == *g)).collect();
    for n in remove {
        let p = dir.join(&n);
        std::fs::remove_file(&p)
            .map_err(|e| Error::io(&p, "cannot remove the shard of a generation after the checkpoint", e))?;
        out.removed.push(n);
    }
    for n in aside {
        let to = crate::fsutil::set_aside(dir, &n)?;
        let rel = to.strip_prefix(dir).unwrap_or(&to).to_string_lossy().into_owned();
        out.set_aside.push(n);
        out.set_aside_as.push(rel);
    }
    Ok(out)
}
