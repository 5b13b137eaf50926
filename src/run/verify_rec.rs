//! `gripopt verify`'s MCAP recording: the verify rows and the free scene's poses handed to
//! the recorder ([`crate::record::write_verify`]) as `RUN_DIR/verify.mcap` (or
//! `verify_sample.mcap` for `--sample`), on the run's own time axis (its recording epoch
//! from run.json) in a band after the run's designs (band 1, `--sample` band 2; the band's
//! width from run.json's `evaluations`, [`crate::record::band_s`]), so the file depends only
//! on the run and the verified designs, and opened together with the shards no second holds
//! two designs.

use super::verify::{VerifyRow, VerifySource};
use crate::error::Result;
use crate::params::Problem;
use crate::record::{
    band_s, verify_parameters, write_verify, write_verify_layout, RunMetadata, ScenarioTag, VerifyEntry, VerifyRecord,
    VerifyRecordOptions, WindowStart, DEFAULT_SCENE_DT, DEFAULT_ZSTD_LEVEL,
};
use crate::sim::PoseSample;
use std::path::{Path, PathBuf};

/// The recording of the verify designs of a run.
pub const VERIFY_MCAP: &str = "verify.mcap";
/// The recording of a `--sample` study.
pub const VERIFY_SAMPLE_MCAP: &str = "verify_sample.mcap";

/// Where and how a verify run is recorded (prepared before the designs are simulated, so
/// a bad run.json is reported before the work).
pub(crate) struct VerifyRecording {
    path: PathBuf,
    dir: PathBuf,
    meta: RunMetadata,
    /// Recording settings.
    pub opts: VerifyRecordOptions,
}

impl VerifyRecording {
    /// For run folder `dir` and the designs of `source`: the epoch is the run's
    /// (`run.json` → `recording.epoch_s`; 0 = 1970 when the run has none).
    pub fn new(dir: &Path, source: &VerifySource) -> Result<Self> {
        let run = super::RunHeader::load(dir)?;
        let epoch_s = run.epoch_s();
        let designs = run.evaluations.unwrap_or(0);
        // the recording's last design id, should run.json's count be short of it
        let recorded =
            crate::record::read_index(&dir.join("recording")).ok().and_then(|i| i.last().map(|e| e.last_id + 1));
        let designs = designs.max(recorded.unwrap_or(0));
        let (file, src, band) = match source {
            VerifySource::Pareto => (VERIFY_MCAP, "pareto".to_string(), 1),
            VerifySource::All => (VERIFY_MCAP, "all".to_string(), 1),
            VerifySource::Sample { n, seed } => (VERIFY_SAMPLE_MCAP, format!("sample {n} seed {seed}"), 2),
        };
        let meta = RunMetadata {
            gripopt_version: Some(env!("CARGO_PKG_VERSION").into()),
            source: Some(src),
            problem_name: run.problem_name,
            problem_sha256: run.problem_sha256,
            ..RunMetadata::default()
        };
        let opts = VerifyRecordOptions {
            scene_dt: DEFAULT_SCENE_DT,
            epoch_s,
            window_base_s: band * band_s(designs),
            zstd_level: DEFAULT_ZSTD_LEVEL,
        };
        Ok(VerifyRecording { path: dir.join(file), dir: dir.to_path_buf(), meta, opts })
    }

    /// The recording of one robust scenario replayed (`gripopt replay --scenario`): the file
    /// `name` in the run folder, in its own `window` after the start of the run's band 3
    /// (bands 1 and 2 are verify's; [`crate::record::scenario_window`]), with the scenario's
    /// metadata `tag` (its `scenario_*` keys).
    pub fn for_scenario(dir: &Path, name: &str, what: String, window: u64, tag: ScenarioTag) -> Result<Self> {
        let mut r = Self::new(dir, &VerifySource::Pareto)?;
        r.opts.window_base_s = r.opts.window_base_s * 3 + window;
        r.path = dir.join(name);
        r.meta.source = Some(what);
        r.meta.scenario = Some(tag);
        Ok(r)
    }

    /// The recording of a single-object free-kind design's free scene (`gripopt replay
    /// RUN --design ID`, `free-ID.mcap`): its own second `ID` after the start of band 3,
    /// [`crate::record::free_window`], with `free_design` (the design id) and the `run_id`
    /// of the run that wrote it in its metadata (an existing file is replaced only then).
    pub fn for_free(dir: &Path, name: &str, id: u64, run_id: &str) -> Result<Self> {
        let mut r = Self::new(dir, &VerifySource::Pareto)?;
        r.opts.window_base_s = crate::record::free_window(r.opts.window_base_s, id);
        r.path = dir.join(name);
        r.meta.source = Some(format!("replay design {id} (free scene)"));
        r.meta.free_design = Some(id);
        r.meta.run_id = Some(run_id.to_string());
        Ok(r)
    }

    /// Write the rows (in order: row k is window k) with their poses, and the layout file;
    /// returns the recording's path.
    pub fn write(self, p: &Problem, rows: Vec<(VerifyRow, Vec<PoseSample>)>) -> Result<PathBuf> {
        let x_off = p.scene.setup.x_off;
        let meta = RunMetadata { free_scene_x_off: Some(x_off), ..self.meta };
        let entries: Vec<VerifyEntry> =
            rows.into_iter().map(|(r, poses)| VerifyEntry { record: record_of(&r, x_off), poses }).collect();
        write_verify(&self.path, p, &meta, &entries, &self.opts)?;
        let c = &p.scene.criteria;
        write_verify_layout(&self.dir, c.dx_max * 1e3, c.theta_max.to_degrees())?;
        Ok(self.path)
    }
}

/// The `/verify` message of a row (window fields are the writer's).
fn record_of(r: &VerifyRow, x_off: f64) -> VerifyRecord {
    VerifyRecord {
        window: 0,
        window_start: WindowStart { sec: 0, nsec: 0 },
        window_start_s: 0.0,
        epoch_s: 0,
        id: r.id,
        parameters: verify_parameters(&r.design),
        x_off,
        measure: r.measure(),
        t_end: r.t_end,
        poses: 0,
        scenario: None,
    }
}
