//! Shard writer and the per-generation [`Recorder`] (shard files and `index.jsonl`).

use super::entry::{DesignEntry, Recordable};
use super::{messages, schema, RecordOptions};
use crate::{Error, Result};
use crate::fsutil::write_atomic;
use crate::model::Finger;
use crate::params::{Design, Problem};
use mcap::records::{MessageHeader, Metadata};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

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
        .map(|(k, l)| serde_json::from_str(l).map_err(|e| Error::Recording { path: p.clone(), message: format!("line {}: {e}", k + 1) }))
        .collect()
}

fn write_index(dir: &Path, entries: &[ShardEntry]) -> Result<()> {
    let path = dir.join("index.jsonl");
    let mut s = String::new();
    for e in entries {
        s.push_str(&serde_json::to_string(e).map_err(|source| Error::Json { path: path.clone(), what: "cannot serialise an index line", source })?);
        s.push('\n');
    }
    write_atomic(&path, s.as_bytes())
}

struct Channels {
    designs: u16,
    joints: u16,
    contacts: u16,
    energy: u16,
    scene: u16,
}

/// Write one shard with the given designs (in the order given; one zstd chunk per design)
/// to a temporary file renamed to `path` when complete. Returns the file size in bytes.
pub fn write_shard<R: Recordable>(path: &Path, problem: &Problem, meta: &BTreeMap<String, String>, designs: &[&R], opts: &RecordOptions) -> Result<u64> {
    let tmp = path.with_extension("mcap.tmp");
    let mc = |e: mcap::McapError| Error::Mcap { path: tmp.clone(), what: "cannot write".into(), source: e };
    let file = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, "cannot create", e))?;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(opts.zstd_threads)
        .compression_level(opts.zstd_level)
        .chunk_size(Some(64 << 20))
        .profile("")
        .library(format!("gripopt {}", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))
        .map_err(mc)?;
    // metadata before any channel: no empty chunk
    w.write_metadata(&Metadata { name: "gripopt.run".into(), metadata: meta.clone() }).map_err(mc)?;
    let none = BTreeMap::new();
    let mut add = |name: &str, s: serde_json::Value, topic: &str| -> Result<u16> {
        let sid = w.add_schema(name, "jsonschema", &to_json(&s)).map_err(mc)?;
        w.add_channel(sid, topic, "json", &none).map_err(mc)
    };
    let ch = Channels {
        designs: add("gripopt.Design", schema::design(), "/designs")?,
        joints: add("gripopt.Joints", schema::joints(), "/grasp/joints")?,
        contacts: add("gripopt.Contacts", schema::contacts(), "/grasp/contacts")?,
        energy: add("gripopt.Energy", schema::energy(), "/grasp/energy")?,
        scene: add("foxglove.SceneUpdate", schema::scene_update(), "/scene")?,
    };
    // serialise every design's messages in parallel, then write them in order
    let s = &problem.scene;
    let encoded: Vec<Vec<(usize, u64, Vec<u8>)>> = designs.par_iter().map(|d| encode_design(&d.entry(), problem, s, opts)).collect();
    let chans = [ch.designs, ch.joints, ch.contacts, ch.energy, ch.scene];
    let mut seq = [0u32; 5];
    for msgs in encoded {
        for (k, t_ns, data) in msgs {
            seq[k] += 1;
            w.write_to_known_channel(&MessageHeader { channel_id: chans[k], sequence: seq[k], log_time: t_ns, publish_time: t_ns }, &data).map_err(mc)?;
        }
        w.flush().map_err(mc)?; // one chunk per design
    }
    w.finish().map_err(mc)?;
    let inner = w.into_inner();
    let f = inner.into_inner().map_err(|e| Error::io(&tmp, "cannot write", e.into_error()))?;
    f.sync_all().map_err(|e| Error::io(&tmp, "cannot sync", e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, "cannot rename the temporary shard into place", e))?;
    Ok(std::fs::metadata(path).map_err(|e| Error::io(path, "cannot read the size of", e))?.len())
}

fn to_json<T: Serialize>(v: &T) -> Vec<u8> {
    // the messages are plain structs of numbers, strings and options: serialising cannot fail
    serde_json::to_vec(v).expect("recorded messages serialise")
}

/// All messages of one design as (channel index, log time, JSON bytes).
fn encode_design(d: &DesignEntry<'_>, problem: &Problem, s: &crate::params::SceneParams, opts: &RecordOptions) -> Vec<(usize, u64, Vec<u8>)> {
    let t0 = messages::window_start_ns(d.id);
    let mut out = vec![(0usize, t0, to_json(&messages::design(d, &problem.name)))];
    if let Some(tr) = d.trajectory {
        let design = Design::from_array(&d.parameters);
        let finger = Finger::new(&design, s).ok();
        let mut next_scene = 0.0;
        let mut first_scene = true;
        for k in opts.kept(tr.samples.len()) {
            let smp = &tr.samples[k];
            let tn = t0 + (smp.t * 1e9).round().min(999_999_999.0) as u64;
            out.push((1, tn, to_json(&messages::joints(d.id, smp))));
            out.push((2, tn, to_json(&messages::contacts(d.id, smp))));
            out.push((3, tn, to_json(&messages::energy(d.id, smp))));
            if opts.scene_dt > 0.0 && smp.t >= next_scene {
                if let Some(v) = finger.as_ref().and_then(|f| messages::scene(d.id, tn, &design, f, s, smp, first_scene)) {
                    out.push((4, tn, to_json(&v)));
                    first_scene = false;
                }
                next_scene = smp.t + opts.scene_dt;
            }
        }
    }
    out
}

/// Records each generation's evaluated designs into one shard of `RUN_DIR/recording/` and
/// keeps `index.jsonl` up to date (the run layer calls it from an optimiser observer).
pub struct Recorder {
    dir: PathBuf,
    problem: Problem,
    meta: BTreeMap<String, String>,
    opts: RecordOptions,
    index: Vec<ShardEntry>,
    /// Bytes written by this process.
    pub bytes: u64,
    /// Seconds spent recording in this process.
    pub seconds: f64,
}

impl Recorder {
    /// Open `RUN_DIR/recording`, dropping shards of generations after `completed` (left by a
    /// generation that was being recorded when the run stopped).
    pub fn open(run_dir: &Path, problem: Problem, meta: BTreeMap<String, String>, opts: RecordOptions, completed: u64) -> Result<Self> {
        let dir = run_dir.join("recording");
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, "cannot create the recording folder", e))?;
        let index = super::recover::recover(&dir, completed)?.index; // never deletes what the checkpoint covers
        write_index(&dir, &index)?;
        Ok(Recorder { dir, problem, meta, opts, index, bytes: 0, seconds: 0.0 })
    }

    /// Write generation `generation`'s evaluated designs (any order; written by id) as one
    /// shard, replacing a shard of the same generation, and update the index. Does nothing
    /// when recording is off or `designs` is empty.
    pub fn record_generation<R: Recordable>(&mut self, generation: u64, designs: &[&R]) -> Result<()> {
        if !self.opts.enabled || designs.is_empty() {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        let g = generation;
        let file = format!("gen-{g:05}.mcap");
        let mut designs: Vec<&R> = designs.to_vec();
        designs.sort_by_key(|d| d.entry().id);
        let mut meta = self.meta.clone();
        meta.insert("generation".into(), g.to_string());
        let bytes = write_shard(&self.dir.join(&file), &self.problem, &meta, &designs, &self.opts)?;
        self.index.retain(|e| e.generation != g);
        let (first_id, last_id) = (designs[0].entry().id, designs[designs.len() - 1].entry().id);
        self.index.push(ShardEntry { generation: g, file, first_id, last_id, designs: designs.len() as u64, bytes });
        write_index(&self.dir, &self.index)?;
        self.bytes += bytes;
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}
