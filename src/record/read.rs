//! Reading a recorded design back: find it through the index and the MCAP summary (one
//! chunk read), its `/designs` message and its trajectory, typed; and the problem file the
//! run evaluated its generation with. Nothing is evaluated here: a replay (the app layer)
//! re-runs the design through its study and compares with `compare`.

use super::index::{read_index, ProblemUse, ShardEntry};
use super::messages::{samples_from, window_start_ns, Finger2Columns};
use super::metadata::{RunMetadata, RUN_METADATA};
use super::proto::GraspSeries;
use super::schema::DesignMessage;
use super::{RecordOptions, Resolution};
use crate::error::{Error, Result};
use crate::eval::ScenarioRecord;
use crate::params::{Design, Problem};
use crate::sim::Sample;
use prost::Message;
use std::path::{Path, PathBuf};

/// A design read back from a recording.
#[derive(Debug, Clone)]
pub struct Recorded {
    /// The shard it was found in.
    pub file: PathBuf,
    /// The `/designs` message.
    pub record: DesignMessage,
    /// The recorded trajectory (possibly a subset, see the run's recording options).
    pub samples: Vec<Sample>,
    /// Which of finger 2's columns the recording has (offset scene; NaN in `samples` where
    /// it lacks one).
    pub finger2_columns: Finger2Columns,
    /// Resolution of the recorded trajectory (compact: values to f32 precision).
    pub resolution: Resolution,
    /// SHA-256 of the problem the design was evaluated with, as the shard's metadata says
    /// (absent in shards of a very early gripopt).
    pub problem_sha256: Option<String>,
    /// The simulator revision that recorded it ([`crate::sim::SIMULATOR_REVISION`]; 1 for a
    /// shard written before the revision was stamped).
    pub simulator_revision: u32,
}

impl Recorded {
    /// The design of the `/designs` record (its `parameters`).
    pub fn design(&self) -> Design {
        Design::from_array(&self.record.parameters.to_array())
    }

    /// What the recording says of scenario `k` of object `o` (None: not a robust design's
    /// record, or its scenarios stopped early before it).
    pub fn scenario(&self, o: usize, k: usize) -> Option<&ScenarioRecord> {
        self.record.robust.as_ref()?.scenarios.iter().find(|s| s.object == o && s.k == k)
    }
}

/// The problem file a run evaluated one generation with, loaded and checked.
#[derive(Debug, Clone)]
pub struct RunProblem {
    /// The problem.
    pub problem: Problem,
    /// Its file in the run folder.
    pub file: PathBuf,
    /// SHA-256 the run recorded for it (run.json).
    pub recorded_sha256: String,
    /// SHA-256 of the file as it is now.
    pub sha256: String,
}

impl RunProblem {
    /// Why the file cannot be the one the run used (without the file's name): edited since
    /// (its hash differs from the recorded one); None when it is the run's.
    pub fn edited(&self) -> Option<String> {
        (self.sha256 != self.recorded_sha256).then(|| {
            format!(
                "edited after the run used it (sha256 {}, the run recorded {})",
                &self.sha256[..12],
                &self.recorded_sha256[..self.recorded_sha256.len().min(12)]
            )
        })
    }
}

/// The parts of run.json the record layer reads (the rest is the run layer's).
#[derive(serde::Deserialize)]
struct RunJson {
    recording: RecordOptions,
    #[serde(default)]
    problem_sha256: String,
    #[serde(default)]
    problems: Vec<ProblemUse>,
    /// The run's id (empty in run folders of a gripopt before issue 24).
    #[serde(default)]
    run_id: String,
}

fn run_json(run_dir: &Path) -> Result<RunJson> {
    let path = run_dir.join("run.json");
    let text = crate::fsutil::read_regular_string(&path, crate::fsutil::caps::RUN_JSON)
        .map_err(|e| Error::io(&path, "cannot read", e))?;
    serde_json::from_str::<RunJson>(&text).map_err(|source| Error::Json {
        path,
        what: "invalid run.json (fields `recording`, `problem_sha256`, `problems`)",
        source,
    })
}

/// The problem file of run folder `run_dir` that evaluated generation `generation` (run.json's
/// `problems`; a run folder without that list has one problem, `problem.toml`), loaded, with
/// the hash the run recorded for it and its hash now (see [`RunProblem::edited`]).
pub fn problem_of_generation(run_dir: &Path, generation: u64) -> Result<RunProblem> {
    let run = run_json(run_dir)?;
    let list = if run.problems.is_empty() {
        vec![ProblemUse { first_generation: 1, file: "problem.toml".into(), sha256: run.problem_sha256 }]
    } else {
        run.problems
    };
    let entry = ProblemUse::of_generation(&list, generation).expect("a non-empty list");
    let file = run_dir.join(&entry.file);
    let problem = Problem::load(&file)?;
    let sha256 = crate::fsutil::sha256_hex(problem.source_text.as_bytes());
    Ok(RunProblem { problem, file, recorded_sha256: entry.sha256.clone(), sha256 })
}

/// The run id run.json of `run_dir` records (empty in run folders of a gripopt before
/// issue 24), which a shard must carry to be read as this run's. A run.json that is
/// missing or cannot be read is an error naming it (a shard is never attributed without
/// it, so that a shard of another run copied in is never read as design `id` of this one).
fn recorded_run_id(run_dir: &Path, id: u64) -> Result<String> {
    let why = match run_json(run_dir) {
        Ok(r) => return Ok(r.run_id),
        Err(Error::Io { source, .. }) => format!("cannot be read ({source})"),
        Err(Error::Json { source, .. }) => format!("is not a valid run.json ({source})"),
        Err(e) => e.to_string(),
    };
    Err(Error::RunDir {
        path: run_dir.join("run.json"),
        message: format!("{why}: without the run id it records, design {id}'s shard cannot be told to be this run's (a shard of another run is never read as this run's design); restore run.json (e.g. from a backup)"),
    })
}

/// Why design `id` is in none of `index`'s shards: the recorded id ranges, and where `id`
/// falls in a gap between two shards (a generation whose shard was moved away or could not
/// be read when the index was rebuilt), the generations and shard files of the gap.
fn not_indexed(dir: &Path, index: &[ShardEntry], id: u64) -> String {
    let mut by_id: Vec<&ShardEntry> = index.iter().collect();
    by_id.sort_by_key(|e| e.first_id);
    // recorded ranges, contiguous shards merged
    let mut ranges: Vec<(u64, u64)> = vec![];
    for e in &by_id {
        match ranges.last_mut() {
            Some(r) if e.first_id <= r.1 + 1 => r.1 = r.1.max(e.last_id),
            _ => ranges.push((e.first_id, e.last_id)),
        }
    }
    let recorded = if ranges.is_empty() {
        "none".to_string()
    } else {
        ranges.iter().map(|(a, b)| format!("{a}..={b}")).collect::<Vec<_>>().join(", ")
    };
    let before = by_id.iter().rev().find(|e| e.last_id < id);
    let Some(after) = by_id.iter().find(|e| e.first_id > id) else {
        return format!("design {id} is not in this index (recorded ids: {recorded})");
    };
    let (lo, g0) = before.map_or((0, 1), |b| (b.last_id + 1, b.generation + 1));
    let g1 = after.generation.saturating_sub(1);
    let gens = match g1.cmp(&g0) {
        std::cmp::Ordering::Less => "no generation between them".to_string(),
        std::cmp::Ordering::Equal => {
            let f = format!("gen-{g0:05}.mcap");
            let state = if dir.join(&f).exists() { "is on disk but not indexed" } else { "is missing" };
            format!("generation {g0}, whose shard {f} {state}")
        }
        std::cmp::Ordering::Greater => {
            let files: Vec<String> =
                (g0..=g1).map(|g| format!("gen-{g:05}.mcap")).filter(|f| !dir.join(f).exists()).collect();
            format!(
                "generations {g0}..={g1} (missing shards: {})",
                if files.is_empty() { "none".into() } else { files.join(", ") }
            )
        }
    };
    format!(
        "design {id} is not recorded: ids {lo}..={} are missing from the index ({gens}; the shard was moved away or could not be read when the index was rebuilt); recorded ids: {recorded}",
        after.first_id - 1
    )
}

/// Largest chunk a replay decompresses (the writer closes chunks at 64 MiB).
const MAX_CHUNK_BYTES: u64 = 1 << 30;

/// Check that the chunk record `ci` points to agrees with `ci` (opcode, length, times,
/// uncompressed size) before the mcap crate reads it: a damaged size field makes its
/// reader allocate without bound (a panic), where this is an error naming the field.
fn check_chunk(buf: &[u8], ci: &mcap::records::ChunkIndex) -> std::result::Result<(), String> {
    let u64_at = |at: usize| buf.get(at..at + 8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")));
    let start = usize::try_from(ci.chunk_start_offset).map_err(|_| "offset beyond the file".to_string())?;
    ci.chunk_start_offset
        .checked_add(ci.chunk_length)
        .filter(|e| *e <= buf.len() as u64)
        .ok_or("the chunk index points beyond the end of the file")?;
    if buf.get(start) != Some(&0x06) {
        return Err("no chunk record at the offset the chunk index gives".into());
    }
    let fields = [
        ("record length", u64_at(start + 1), ci.chunk_length.checked_sub(9)),
        ("message start time", u64_at(start + 9), Some(ci.message_start_time)),
        ("message end time", u64_at(start + 17), Some(ci.message_end_time)),
        ("uncompressed size", u64_at(start + 25), Some(ci.uncompressed_size)),
    ];
    for (name, in_file, in_index) in fields {
        if in_file.is_none() || in_file != in_index {
            return Err(format!(
                "its {name} ({}) differs from the chunk index's ({})",
                in_file.map_or("missing".into(), |v| v.to_string()),
                in_index.map_or("invalid".into(), |v| v.to_string())
            ));
        }
    }
    if ci.uncompressed_size > MAX_CHUNK_BYTES {
        return Err(format!("uncompressed size {} exceeds {MAX_CHUNK_BYTES} bytes", ci.uncompressed_size));
    }
    Ok(())
}

/// The messages (channel id, log time, bytes) of the chunk `ci` points to, read with a record
/// length limit of the chunk's uncompressed size: the mcap crate's own chunk reader
/// (`Summary::stream_chunk`) has none, so a damaged record length inside a decompressed chunk
/// made it allocate that length (an abort, not an error).
fn chunk_messages<'a>(
    buf: &'a [u8],
    ci: &mcap::records::ChunkIndex,
) -> std::result::Result<Vec<(u16, u64, Vec<u8>)>, String> {
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let (start, end) = (ci.chunk_start_offset as usize, (ci.chunk_start_offset + ci.chunk_length) as usize);
    let mut input: &'a [u8] = &buf[start..end];
    // no record, the chunk record included, is longer than the chunk or its content
    let limit =
        usize::try_from(ci.uncompressed_size.max(ci.chunk_length)).map_err(|_| "size beyond memory".to_string())?;
    let mut r = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_skip_end_magic(true)
            .with_validate_chunk_crcs(true)
            .with_record_length_limit(limit),
    );
    let mut out = vec![];
    while let Some(event) = r.next_event() {
        match event.map_err(|e| e.to_string())? {
            LinearReadEvent::ReadRequest(n) => {
                let n = n.min(input.len());
                r.insert(n).copy_from_slice(&input[..n]);
                r.notify_read(n);
                input = &input[n..];
            }
            LinearReadEvent::Record { data, opcode } => {
                if let mcap::records::Record::Message { header, data } =
                    mcap::parse_record(opcode, data).map_err(|e| e.to_string())?
                {
                    out.push((header.channel_id, header.log_time, data.into_owned()));
                }
            }
        }
    }
    Ok(out)
}

/// One message of a chunk.
struct Msg {
    log_time: u64,
    data: Vec<u8>,
}

/// Why `run_dir` has no recording folder `dir`: run.json's recording settings say whether
/// the run recorded anything.
fn no_recording(run_dir: &Path, dir: &Path) -> String {
    /// run.json as far as this reads it (record does not know the run layer's `RunInfo`).
    #[derive(serde::Deserialize)]
    struct RunRecording {
        recording: Option<super::RecordOptions>,
    }
    let run_json = run_dir.join("run.json");
    let enabled = crate::fsutil::read_regular(&run_json, crate::fsutil::caps::RUN_JSON)
        .ok()
        .and_then(|b| serde_json::from_slice::<RunRecording>(&b).ok())
        .and_then(|v| v.recording.map(|r| r.enabled));
    match enabled {
        Some(false) => "the run was not recorded (run.json: recording off, started with `--record none`): no design can be replayed; `gripopt show` and `gripopt export` take its last designs from the checkpoint".into(),
        Some(true) => format!("{} is missing, but run.json says the run recorded its designs: restore it (e.g. from a backup)", dir.display()),
        None => format!("no recording ({} is missing, and {} does not say whether the run recorded)", dir.display(), run_json.display()),
    }
}

/// Find design `id` in the recording of `run_dir`.
pub fn read_design(run_dir: &Path, id: u64) -> Result<Recorded> {
    let dir = run_dir.join("recording");
    if !dir.exists() {
        return Err(Error::Recording { path: run_dir.to_path_buf(), message: no_recording(run_dir, &dir) });
    }
    // the index, or (unreadable, or without the design) the index rebuilt from the shards
    let holds = |index: &[ShardEntry]| index.iter().find(|e| e.first_id <= id && id <= e.last_id).cloned();
    let (index, entry) = match read_index(&dir) {
        Ok(index) => match holds(&index) {
            Some(e) => (index, Some(e)),
            None => {
                let rebuilt = super::recover::rebuilt_index(&dir)?;
                let e = holds(&rebuilt);
                (if e.is_some() { rebuilt } else { index }, e)
            }
        },
        Err(_) => {
            let rebuilt = super::recover::rebuilt_index(&dir)?;
            let e = holds(&rebuilt);
            (rebuilt, e)
        }
    };
    let entry = entry
        .ok_or_else(|| Error::Recording { path: dir.join("index.jsonl"), message: not_indexed(&dir, &index, id) })?;
    if !super::recover::is_plain_name(&entry.file) {
        return Err(Error::Recording {
            path: dir.join("index.jsonl"),
            message: format!("the line of generation {} names the shard {:?}, not a file name inside {}: a path out of the recording folder is never followed; move index.jsonl away (a resume rebuilds it from the shards)", entry.generation, entry.file, dir.display()),
        });
    }
    let path = dir.join(&entry.file);
    let buf = super::recover::map_shard(&path)?;
    let bad = |message: String| Error::Recording { path: path.clone(), message };
    let mc = |what: String| {
        |source: mcap::McapError| Error::DamagedRecording { path: path.clone(), what, source: source.into() }
    };
    let summary = mcap::Summary::read(&buf)
        .map_err(mc("cannot read the MCAP summary (the file is truncated or damaged)".into()))?
        .ok_or_else(|| bad("no MCAP summary; the file is truncated or corrupt".into()))?;
    // the epoch and the resolution from the shard's metadata record
    let meta = summary
        .metadata_indexes
        .iter()
        .find(|m| m.name == RUN_METADATA)
        .ok_or_else(|| bad("no gripopt.run metadata record".into()))
        .and_then(|mi| {
            mcap::read::metadata(&buf, mi).map_err(mc("cannot read the gripopt.run metadata record".into()))
        })?;
    let meta = RunMetadata::from_map(&meta.metadata).map_err(bad)?;
    // attributed: a shard of another run (copied in) is never read as this run's design
    let ours = recorded_run_id(run_dir, id)?;
    let theirs = meta.run_id.as_deref().unwrap_or_default();
    if theirs != ours {
        let name = |r: &str| if r.is_empty() { "none".to_string() } else { r.to_string() };
        return Err(bad(format!("written by another run (run id {}; this run's id {}, run.json): it is not this run's generation {}; restore this run's shard", name(theirs), name(&ours), entry.generation)));
    }
    let epoch_s = meta.require_epoch_s().map_err(bad)?;
    let resolution = meta.require_resolution().map_err(bad)?;
    let epoch_ns = epoch_s.saturating_mul(1_000_000_000);
    let (lo, hi) = (window_start_ns(epoch_ns, id), window_start_ns(epoch_ns, id + 1));
    let (mut design, mut series) = (None, None);
    for ci in summary.chunk_indexes.iter().filter(|c| c.message_start_time < hi && c.message_end_time >= lo) {
        check_chunk(&buf, ci)
            .map_err(|m| bad(format!("the file is damaged: chunk at offset {}: {m}", ci.chunk_start_offset)))?;
        let at = ci.chunk_start_offset;
        let messages = chunk_messages(&buf, ci)
            .map_err(|e| bad(format!("cannot read the chunk at offset {at} (the file is damaged): {e}")))?;
        for (channel, log_time, data) in messages {
            let m = Msg { log_time, data };
            if m.log_time < lo || m.log_time >= hi {
                continue;
            }
            let topic = summary.channels.get(&channel).map_or("", |c| c.topic.as_str());
            match topic {
                "/designs" => {
                    design = Some(serde_json::from_slice::<DesignMessage>(&m.data).map_err(|e| {
                        bad(format!("/designs message at {} ns is not a gripopt.Design: {e}", m.log_time))
                    })?)
                }
                "/grasp/series" => {
                    series = Some(
                        GraspSeries::decode(&m.data[..])
                            .map_err(|e| bad(format!("/grasp/series message at {} ns: {e}", m.log_time)))?,
                    )
                }
                _ => {}
            }
        }
    }
    let record = design.ok_or_else(|| bad(format!("no /designs message for design {id}")))?;
    let series = series.ok_or_else(|| bad(format!("no /grasp/series message for design {id}")))?;
    if series.design_id != id {
        return Err(bad(format!("the /grasp/series message in design {id}'s window is design {}'s", series.design_id)));
    }
    let samples = samples_from(&series)
        .ok_or_else(|| bad(format!("design {id}: the columns of /grasp/series differ in length")))?;
    let problem_sha256 = meta.problem_sha256;
    // absent in recordings of simulator revision 1
    let simulator_revision = meta.simulator_revision.unwrap_or(1);
    let finger2_columns = Finger2Columns::of(&series)
        .ok_or_else(|| bad(format!("design {id}: finger 2's columns of /grasp/series are not a set gripopt writes")))?;
    Ok(Recorded { file: path, record, samples, finger2_columns, resolution, problem_sha256, simulator_revision })
}

/// The recording options run.json of `run_dir` records (what a replay selects and rounds
/// the re-simulated trajectory with, as the run recorded it).
pub fn run_recording(run_dir: &Path) -> Result<RecordOptions> {
    Ok(run_json(run_dir)?.recording)
}
