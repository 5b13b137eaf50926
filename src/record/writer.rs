//! Shard writer and the recorder observer.

use super::{messages, schema};
use crate::model::Finger;
use crate::optim::checkpoint::write_atomic;
use crate::optim::gripper::{GripperInfo, TrajectoryKeep};
use crate::optim::nsga2::Nsga2State;
use crate::optim::Individual;
use crate::params::{Design, Problem};
use argmin::core::observers::Observe;
use argmin::core::{Error as ArgminError, KV};
use mcap::records::{MessageHeader, Metadata};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::BufWriter;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// What is recorded (stated in run.json; part of the run's settings hash).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RecordOptions {
    /// Record anything at all (the `/designs` channel).
    pub enabled: bool,
    /// Trajectories of which designs.
    pub trajectories: TrajectoryKeep,
    /// Keep every n-th trajectory sample (1 = every accepted step and event); the last
    /// sample is always kept.
    pub every: u32,
    /// Interval of the 3D scene updates in simulated seconds (0 = none).
    pub scene_dt: f64,
}

impl Default for RecordOptions {
    fn default() -> Self {
        RecordOptions { enabled: true, trajectories: TrajectoryKeep::All, every: 1, scene_dt: 0.5e-3 }
    }
}

impl RecordOptions {
    /// Nothing recorded.
    pub fn none() -> Self {
        RecordOptions { enabled: false, trajectories: TrajectoryKeep::None, every: 1, scene_dt: 0.0 }
    }
    /// Indices of the samples kept.
    pub fn kept(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        let every = self.every.max(1) as usize;
        (0..n).filter(move |&i| i % every == 0 || i + 1 == n)
    }
}

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

/// Read `index.jsonl` (errors name the file and line).
pub fn read_index(dir: &Path) -> anyhow::Result<Vec<ShardEntry>> {
    let p = dir.join("index.jsonl");
    let text = std::fs::read_to_string(&p).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| serde_json::from_str(l).map_err(|e| anyhow::anyhow!("{}: line {}: {e}", p.display(), k + 1)))
        .collect()
}

fn write_index(dir: &Path, entries: &[ShardEntry]) -> anyhow::Result<()> {
    let mut s = String::new();
    for e in entries {
        s.push_str(&serde_json::to_string(e)?);
        s.push('\n');
    }
    write_atomic(&dir.join("index.jsonl"), s.as_bytes())?;
    Ok(())
}

struct Channels {
    designs: u16,
    joints: u16,
    contacts: u16,
    energy: u16,
    scene: u16,
}

/// Write one shard with the given designs.
pub fn write_shard(path: &Path, problem: &Problem, meta: &BTreeMap<String, String>, designs: &[&Individual<GripperInfo>], opts: &RecordOptions) -> anyhow::Result<u64> {
    let io = |e: std::io::Error| anyhow::anyhow!("{}: {e}", path.display());
    let mc = |e: mcap::McapError| anyhow::anyhow!("{}: {e}", path.display());
    let tmp = path.with_extension("mcap.tmp");
    let file = std::fs::File::create(&tmp).map_err(io)?;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(std::env::var("GRIPOPT_ZSTD_THREADS").ok().and_then(|v| v.parse().ok()).unwrap_or(0))
        .compression_level(std::env::var("GRIPOPT_ZSTD_LEVEL").ok().and_then(|v| v.parse().ok()).unwrap_or(1))
        .chunk_size(Some(64 << 20))
        .profile("")
        .library(format!("gripopt {}", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))
        .map_err(mc)?;
    // metadata before any channel: no empty chunk
    w.write_metadata(&Metadata { name: "gripopt.run".into(), metadata: meta.clone() }).map_err(mc)?;
    let none = BTreeMap::new();
    let mut add = |name: &str, s: serde_json::Value, topic: &str| -> anyhow::Result<u16> {
        let sid = w.add_schema(name, "jsonschema", serde_json::to_string(&s)?.as_bytes()).map_err(mc)?;
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
    let encoded: Vec<anyhow::Result<Vec<(usize, u64, Vec<u8>)>>> = designs.par_iter().map(|ind| encode_design(ind, problem, s, opts)).collect();
    let chans = [ch.designs, ch.joints, ch.contacts, ch.energy, ch.scene];
    let mut seq = [0u32; 5];
    for msgs in encoded {
        for (k, t_ns, data) in msgs? {
            seq[k] += 1;
            w.write_to_known_channel(&MessageHeader { channel_id: chans[k], sequence: seq[k], log_time: t_ns, publish_time: t_ns }, &data).map_err(mc)?;
        }
        w.flush().map_err(mc)?; // one chunk per design
    }
    w.finish().map_err(mc)?;
    let inner = w.into_inner();
    let f = inner.into_inner().map_err(|e| io(e.into_error()))?;
    f.sync_all().map_err(io)?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(io)?;
    Ok(std::fs::metadata(path).map_err(io)?.len())
}

/// All messages of one design as (channel index, log time, JSON bytes).
fn encode_design(ind: &Individual<GripperInfo>, problem: &Problem, s: &crate::params::SceneParams, opts: &RecordOptions) -> anyhow::Result<Vec<(usize, u64, Vec<u8>)>> {
    let t0 = messages::window_start_ns(ind.id);
    let mut out = vec![(0usize, t0, serde_json::to_vec(&messages::design(ind, &problem.name))?)];
    if let Some(tr) = &ind.eval.info.trajectory {
        let arr: [f64; 6] = ind.x.clone().try_into().map_err(|_| anyhow::anyhow!("design {} has not 6 variables", ind.id))?;
        let design = Design::from_array(&arr);
        let finger = Finger::new(&design, s).ok();
        let mut next_scene = 0.0;
        let mut first_scene = true;
        for k in opts.kept(tr.samples.len()) {
            let smp = &tr.samples[k];
            let tn = t0 + (smp.t * 1e9).round().min(999_999_999.0) as u64;
            out.push((1, tn, serde_json::to_vec(&messages::joints(ind.id, smp))?));
            out.push((2, tn, serde_json::to_vec(&messages::contacts(ind.id, smp))?));
            out.push((3, tn, serde_json::to_vec(&messages::energy(ind.id, smp))?));
            if opts.scene_dt > 0.0 && smp.t >= next_scene {
                if let Some(v) = finger.as_ref().and_then(|f| messages::scene(ind.id, tn, &design, f, s, smp, first_scene)) {
                    out.push((4, tn, serde_json::to_vec(&v)?));
                    first_scene = false;
                }
                next_scene = smp.t + opts.scene_dt;
            }
        }
    }
    Ok(out)
}

/// Observer that records each generation's evaluated designs into one shard.
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
    pub fn open(run_dir: &Path, problem: Problem, meta: BTreeMap<String, String>, opts: RecordOptions, completed: u64) -> anyhow::Result<Self> {
        let dir = run_dir.join("recording");
        std::fs::create_dir_all(&dir).map_err(|e| anyhow::anyhow!("{}: {e}", dir.display()))?;
        let mut index = if dir.join("index.jsonl").exists() { read_index(&dir)? } else { vec![] };
        for e in index.iter().filter(|e| e.generation > completed) {
            let _ = std::fs::remove_file(dir.join(&e.file));
        }
        index.retain(|e| e.generation <= completed);
        if let Ok(rd) = std::fs::read_dir(&dir) {
            for f in rd.flatten() {
                let n = f.file_name().to_string_lossy().to_string();
                let orphan = n.ends_with(".tmp") || (n.starts_with("gen-") && !index.iter().any(|e| e.file == n));
                if orphan {
                    let _ = std::fs::remove_file(f.path());
                }
            }
        }
        write_index(&dir, &index)?;
        Ok(Recorder { dir, problem, meta, opts, index, bytes: 0, seconds: 0.0 })
    }

    fn record(&mut self, st: &Nsga2State<GripperInfo>) -> anyhow::Result<()> {
        if !self.opts.enabled || st.last_evaluated.is_empty() {
            return Ok(());
        }
        let t0 = std::time::Instant::now();
        let g = st.generation;
        let file = format!("gen-{g:05}.mcap");
        let mut designs: Vec<&Individual<GripperInfo>> = st.last_evaluated.iter().collect();
        designs.sort_by_key(|d| d.id);
        let mut meta = self.meta.clone();
        meta.insert("generation".into(), g.to_string());
        let bytes = write_shard(&self.dir.join(&file), &self.problem, &meta, &designs, &self.opts)?;
        self.index.retain(|e| e.generation != g);
        self.index.push(ShardEntry { generation: g, file, first_id: designs[0].id, last_id: designs[designs.len() - 1].id, designs: designs.len() as u64, bytes });
        write_index(&self.dir, &self.index)?;
        self.bytes += bytes;
        self.seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Shared handle so the caller can read the counters after the run.
#[derive(Clone)]
pub struct SharedRecorder(pub std::sync::Arc<std::sync::Mutex<Recorder>>);

impl Observe<Nsga2State<GripperInfo>> for SharedRecorder {
    fn observe_init(&mut self, _n: &str, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), ArgminError> {
        self.0.lock().expect("recorder").record(st).map_err(|e| ArgminError::msg(e.to_string()))
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), ArgminError> {
        self.0.lock().expect("recorder").record(st).map_err(|e| ArgminError::msg(e.to_string()))
    }
}
