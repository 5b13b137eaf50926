//! What is recorded: [`RecordOptions`] (stated in run.json and hashed into checkpoints) and
//! [`TrajectoryKeep`].

use serde::{Deserialize, Serialize};

/// Which stage-3 trajectories are kept for recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TrajectoryKeep {
    /// None (no recorder, or designs only).
    None,
    /// Only of feasible designs.
    Feasible,
    /// Of every design that reached stage 3.
    All,
}

/// Default zstd level of the shards.
pub const DEFAULT_ZSTD_LEVEL: u32 = 1;
/// Default zstd worker threads (0 = compress on the writing thread).
pub const DEFAULT_ZSTD_THREADS: u32 = 0;

fn default_zstd_level() -> u32 {
    DEFAULT_ZSTD_LEVEL
}
fn is_default_zstd_level(v: &u32) -> bool {
    *v == DEFAULT_ZSTD_LEVEL
}
fn is_default_zstd_threads(v: &u32) -> bool {
    *v == DEFAULT_ZSTD_THREADS
}

/// What is recorded (stated in run.json; part of the run's settings hash).
///
/// The zstd settings change only the compressed bytes, never the recorded content; they
/// are written to run.json only when not at their defaults, so run folders and recordings
/// made before these fields existed read (and resume) unchanged.
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
    /// zstd compression level of the chunks (default 1).
    #[serde(default = "default_zstd_level", skip_serializing_if = "is_default_zstd_level")]
    pub zstd_level: u32,
    /// zstd worker threads per shard writer (default 0: compress on the writing thread).
    #[serde(default, skip_serializing_if = "is_default_zstd_threads")]
    pub zstd_threads: u32,
}

impl Default for RecordOptions {
    fn default() -> Self {
        RecordOptions { enabled: true, trajectories: TrajectoryKeep::All, every: 1, scene_dt: 0.5e-3, zstd_level: DEFAULT_ZSTD_LEVEL, zstd_threads: DEFAULT_ZSTD_THREADS }
    }
}

impl RecordOptions {
    /// Nothing recorded.
    pub fn none() -> Self {
        RecordOptions { enabled: false, trajectories: TrajectoryKeep::None, every: 1, scene_dt: 0.0, zstd_level: DEFAULT_ZSTD_LEVEL, zstd_threads: DEFAULT_ZSTD_THREADS }
    }
    /// Indices of the samples kept.
    pub fn kept(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        let every = self.every.max(1) as usize;
        (0..n).filter(move |&i| i % every == 0 || i + 1 == n)
    }
}
