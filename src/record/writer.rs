//! Shard writer and the per-generation [`Recorder`] (shard files and `index.jsonl`).

use super::entry::{DesignEntry, Recordable};
use super::index::{write_index, ShardEntry};
use super::mcapfile::{add_channels, add_foxglove_schema, add_json_schema, write_designs};
use super::metadata::{RunMetadata, RUN_METADATA};
use super::scenario_scene::SceneMessage;
use super::scenario_series::{scenario_series_descriptor, ScenarioSeries, SCENARIO_SERIES_NAME};
use super::{messages, proto, schema, RecordOptions};
use crate::error::{Error, Result};
use crate::model::Finger;
use crate::params::{Design, Problem};
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Encode;
use mcap::records::Metadata;
use prost::Message;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Channels of a shard, in the order of [`Ch`]: a robust run's shards have the sixth.
const TOPICS: [&str; 6] = ["/designs", "/grasp/series", "/tf", "/scene/static", "/scene", "/scenario/series"];

/// Channel index into [`TOPICS`].
#[derive(Clone, Copy)]
enum Ch {
    Designs = 0,
    Series = 1,
    Tf = 2,
    Static = 3,
    Scene = 4,
    Scenario = 5,
}

fn fx<T: Encode>(m: &T) -> Vec<u8> {
    let mut b = Vec::with_capacity(m.encoded_len().unwrap_or(256));
    // encoding into a growable Vec cannot run out of space
    m.encode(&mut b).expect("protobuf encoding into a Vec");
    b
}

/// Write one shard with the given designs (in the order given; one zstd chunk per design)
/// to a temporary file renamed to `path` when complete. Returns the file size in bytes.
///
/// Besides `meta`, the shard's `gripopt.run` metadata record holds `generation` (unless
/// given: the first design's), `first_id`, `last_id`, `designs`, `epoch_s`, `resolution`
/// and `time_convention`, so a lost `index.jsonl` can be rebuilt from the shards.
pub fn write_shard<R: Recordable>(
    path: &Path,
    problem: &Problem,
    meta: &RunMetadata,
    designs: &[&R],
    opts: &RecordOptions,
) -> Result<u64> {
    let tmp = super::mcapfile::temporary(path);
    let mc = super::mcapfile::error(&tmp);
    // the shard is framed in memory and written with one call
    let mut w = super::mcapfile::open(&tmp, opts.zstd_level, opts.zstd_threads)?;
    let mut meta = meta.clone();
    let ids: Vec<u64> = designs.iter().map(|d| d.entry().id).collect();
    if let (Some(first), Some(last)) = (ids.iter().min(), ids.iter().max()) {
        meta.generation = meta.generation.or(Some(designs[0].entry().generation));
        meta.first_id = Some(Some(*first));
        meta.last_id = Some(Some(*last));
    }
    meta.designs = Some(designs.len() as u64);
    // the scene of stage 3 (absent: centred, as in every recording before session 36); a
    // free-kind run's shards draw the centred diagnostic grasp, the label its free verdict
    let setup = &problem.scene.setup;
    if let Some(drawn) = setup.kind.drawn_in_recordings() {
        meta.scene_kind = Some(setup.kind);
        meta.x_off = Some(setup.x_off);
        meta.scene_drawn = Some(drawn.into());
    }
    if problem.robust.is_some() {
        meta.scene_drawn = Some(ROBUST_DRAWN.into());
    }
    meta.epoch_s = Some(opts.epoch_s);
    meta.resolution = Some(opts.resolution);
    meta.time_convention = Some(
        "design k: log_time in [epoch_s + k s, epoch_s + k s + 1 s); simulated time t at epoch_s + k s + t".into(),
    );
    // metadata before any channel: no empty chunk
    w.write_metadata(&Metadata { name: RUN_METADATA.into(), metadata: meta.to_map() }).map_err(mc)?;
    // finger 2's own angles are columns of the offset scene's series only
    let finger2 = has_finger2(problem);
    let design_schema = add_json_schema(&mut w, "gripopt.Design", &schema::design(problem.solver.method), &tmp)?;
    let series_schema = w.add_schema(proto::SERIES_NAME, "protobuf", &proto::series_descriptor(finger2)).map_err(mc)?;
    let tf_schema = add_foxglove_schema(&mut w, FrameTransforms::get_schema(), &tmp)?;
    let scene_schema = add_foxglove_schema(&mut w, SceneUpdate::get_schema(), &tmp)?;
    let scenario_schema = if problem.robust.is_some() {
        w.add_schema(SCENARIO_SERIES_NAME, "protobuf", &scenario_series_descriptor()).map_err(mc)?
    } else {
        0
    };
    let schema_of = [
        (design_schema, "json"),
        (series_schema, "protobuf"),
        (tf_schema, "protobuf"),
        (scene_schema, "protobuf"),
        (scene_schema, "protobuf"),
        (scenario_schema, "protobuf"),
    ];
    // without scene frames, no channels for them; `/scenario/series` in robust shards only
    // (a channel not added keeps id 0: it has no messages)
    let wanted = |c: usize| match c {
        2..=4 => opts.scene_dt > 0.0,
        5 => problem.robust.is_some(),
        _ => true,
    };
    let used: Vec<usize> = (0..TOPICS.len()).filter(|&c| wanted(c)).collect();
    let topics: Vec<&str> = used.iter().map(|&c| TOPICS[c]).collect();
    let schemas: Vec<(u16, &str)> = used.iter().map(|&c| schema_of[c]).collect();
    let added = add_channels(&mut w, &topics, &schemas, &tmp)?;
    let mut chans = vec![0; TOPICS.len()];
    for (&c, id) in used.iter().zip(added) {
        chans[c] = id;
    }
    // encode every design's messages in parallel, then write them in order
    let encoded: Vec<Vec<(Ch, u64, Vec<u8>)>> =
        designs.par_iter().map(|d| encode_design(&d.entry(), problem, opts)).collect();
    let designs = encoded.into_iter().map(|m| m.into_iter().map(|(k, t_ns, data)| (k as usize, t_ns, data)));
    write_designs(&mut w, &chans, designs, &tmp)?;
    super::mcapfile::finish(w, &tmp, path)
}

/// Whether the problem's shards carry finger 2's own angles (the offset scene, where finger 2
/// is not finger 1's mirror image).
fn has_finger2(problem: &Problem) -> bool {
    problem.scene.setup.kind.has_finger2()
}

/// All messages of one design as (channel, log time, bytes), in time order: at the window
/// start the record, the series, the frames, the static scene and the first finger pose
/// (without a trajectory: the open and failing poses); then the fingers every `scene_dt` of
/// simulated time and at the last sample (t_stab or the discard time); at the window's last
/// nanosecond the frames again (the drawing is `scene`'s, see docs/recording.md).
fn encode_design(d: &DesignEntry<'_>, problem: &Problem, opts: &RecordOptions) -> Vec<(Ch, u64, Vec<u8>)> {
    let t0 = messages::window_start_ns(opts.epoch_ns(), d.id);
    let sc = &problem.scene;
    let (samples, kept, drawn, simulated) = match d.trajectory {
        Some(t) => (&t.samples[..], &t.series[..], &t.scene[..], t.simulated),
        None => (&[][..], &[][..], &[][..], 0),
    };
    let record = messages::design(d, &problem.name, t0, opts.epoch_s).to_json();
    let series = messages::series(d, samples, kept, simulated, opts, has_finger2(problem)).encode_to_vec();
    let mut out = vec![(Ch::Designs, t0, record), (Ch::Series, t0, series)];
    if problem.robust.is_some() {
        let s = d.scenario.map_or_else(|| placeholder_scenario(d.id), |s| s.series(d, opts.resolution));
        out.push((Ch::Scenario, t0, s.encode_to_vec()));
    }
    if opts.scene_dt <= 0.0 {
        return out;
    }
    if let Some(s) = d.scenario {
        out.extend(s.scene_messages(d, t0).into_iter().map(|m| match m {
            SceneMessage::Tf(t, m) => (Ch::Tf, t, fx(&m)),
            SceneMessage::Static(t, m) => (Ch::Static, t, fx(&m)),
            SceneMessage::Scene(t, m) => (Ch::Scene, t, fx(&m)),
        }));
        return out;
    }
    let design = Design::from_array(&d.parameters);
    let finger = d.record.lengths().and_then(|_| Finger::new(&design, sc).ok());
    out.push((Ch::Tf, t0, fx(&messages::frames(t0, sc))));
    // the object drawn: a robust design's stage-2 discard shows the object it failed on
    let shown = messages::drawn_scene(problem, d);
    out.push((Ch::Static, t0, fx(&messages::static_scene(t0, d, &shown))));
    let end = messages::window_end_ns(t0);
    if samples.is_empty() {
        let failed = d.record.verdict.failed_stage;
        out.push((Ch::Scene, t0, fx(&messages::discarded_scene(t0, d.id, &design, failed, sc, &shown))));
        out.push((Ch::Tf, end, fx(&messages::frames(end, sc))));
        return out;
    }
    // the samples drawn: the first, one every `scene_dt` and the last (`scene_samples`)
    for (j, &k) in drawn.iter().enumerate() {
        let (s, first) = (&samples[k], j == 0);
        let tn = if first { t0 } else { messages::log_time(t0, s.t) };
        if let Some(m) = messages::scene(d.id, tn, finger.as_ref(), Some(s), first) {
            out.push((Ch::Scene, tn, fx(&m)));
        }
    }
    out.push((Ch::Tf, end, fx(&messages::frames(end, sc))));
    out
}

/// What a robust run's shards draw (their `scene_drawn` metadata).
const ROBUST_DRAWN: &str = "a design that reached its scenarios: the scenario that decided its verdict (/designs shown_scenario), its free scene or, where that did not run, its centred grasp; other designs: the reference object's pictures";

/// `/scenario/series` of a robust design without a drawn scenario: one placeholder sample
/// (t = 0, NaN), so a Plot panel redraws empty.
fn placeholder_scenario(id: u64) -> ScenarioSeries {
    let mut m = ScenarioSeries { design_id: id, ..Default::default() };
    m.push(0.0, [f64::NAN; 14]);
    m
}

/// Records each generation's evaluated designs into one shard of `RUN_DIR/recording/` and
/// keeps `index.jsonl` up to date (the run layer calls it from an optimiser observer).
///
/// Writing a shard and entering it in the index are separate steps ([`Recorder::task`],
/// [`ShardTask::write`], [`Recorder::commit`]), so that several generations' shards can be
/// encoded and compressed at once while the index stays in generation order.
pub struct Recorder {
    dir: PathBuf,
    problem: Arc<Problem>,
    meta: RunMetadata,
    opts: RecordOptions,
    index: Vec<ShardEntry>,
    /// Bytes written by this process.
    pub bytes: u64,
    /// Seconds spent recording in this process (summed over shards written at once).
    pub seconds: f64,
    /// Warnings of the recovery at [`Recorder::open`] (generations the checkpoint covers
    /// without a shard, see [`super::Recovery::warnings`]); the caller shows them.
    pub warnings: Vec<String>,
}

/// One generation's shard, detached from its [`Recorder`]: write it on any thread, then
/// hand the entry to [`Recorder::commit`].
#[derive(Clone)]
pub struct ShardTask {
    path: PathBuf,
    file: String,
    generation: u64,
    problem: Arc<Problem>,
    meta: RunMetadata,
    opts: RecordOptions,
}

impl ShardTask {
    /// Write the shard of `designs` (any order; written by id) durably, replacing a shard of
    /// the same generation; its index entry, or None when `designs` is empty.
    pub fn write<R: Recordable>(&self, designs: &[&R]) -> Result<Option<(ShardEntry, f64)>> {
        if designs.is_empty() {
            return Ok(None);
        }
        let t0 = std::time::Instant::now();
        let mut designs: Vec<&R> = designs.to_vec();
        designs.sort_by_key(|d| d.entry().id);
        let bytes = write_shard(&self.path, &self.problem, &self.meta, &designs, &self.opts)?;
        let (first_id, last_id) = (designs[0].entry().id, designs[designs.len() - 1].entry().id);
        let e = ShardEntry {
            generation: self.generation,
            file: self.file.clone(),
            first_id,
            last_id,
            designs: designs.len() as u64,
            bytes,
            run_id: self.meta.run_id.clone(),
            problem_sha256: self.meta.problem_sha256.clone(),
        };
        Ok(Some((e, t0.elapsed().as_secs_f64())))
    }
}

impl Recorder {
    /// Open `RUN_DIR/recording`, dropping this run's shards of generations after `completed`
    /// (left by a generation that was being recorded when the run stopped); an error when a
    /// covered shard cannot be re-indexed or was written by another run (see `recover_run`;
    /// the run is `meta`'s `run_id`, which every shard and index line then carries, with
    /// `meta`'s `problem_sha256`).
    pub fn open(
        run_dir: &Path,
        problem: Problem,
        meta: RunMetadata,
        opts: RecordOptions,
        completed: u64,
    ) -> Result<Self> {
        let dir = run_dir.join("recording");
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, "cannot create the recording folder", e))?;
        // never deletes what the checkpoint covers; refuses (touching nothing) when a covered
        // shard must be re-indexed but cannot be read
        let recovery = super::recover::recover_run(&dir, completed, meta.run_id.as_deref())?;
        let warnings = recovery.warnings(&dir);
        write_index(&dir, &recovery.index)?;
        Ok(Recorder {
            dir,
            problem: Arc::new(problem),
            meta,
            opts,
            index: recovery.index,
            bytes: 0,
            seconds: 0.0,
            warnings,
        })
    }

    /// The shard of generation `generation`, to be written by [`ShardTask::write`]; None
    /// when recording is off.
    pub fn task(&self, generation: u64) -> Option<ShardTask> {
        if !self.opts.enabled {
            return None;
        }
        let file = format!("gen-{generation:05}.mcap");
        let mut meta = self.meta.clone();
        meta.generation = Some(generation);
        Some(ShardTask {
            path: self.dir.join(&file),
            file,
            generation,
            problem: self.problem.clone(),
            meta,
            opts: self.opts,
        })
    }

    /// Enter a written shard in `index.jsonl` (replacing an entry of the same generation;
    /// entries stay in generation order) and count its bytes and seconds.
    pub fn commit(&mut self, entry: ShardEntry, seconds: f64) -> Result<()> {
        self.index.retain(|e| e.generation != entry.generation);
        self.bytes += entry.bytes;
        self.seconds += seconds;
        let at = self.index.partition_point(|e| e.generation < entry.generation);
        self.index.insert(at, entry);
        write_index(&self.dir, &self.index)
    }
}
