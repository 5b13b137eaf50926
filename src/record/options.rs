//! What is recorded: [`RecordOptions`] (stated in run.json and hashed into checkpoints) and
//! [`TrajectoryKeep`].

use crate::sim::Sample;
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

/// How finely trajectories are recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Resolution {
    /// Default: a subset of the samples (see [`RecordOptions::kept_samples`]: the first and
    /// last, both samples around every contact onset and separation, every local peak of a
    /// contact or hand force, and one sample per [`COMPACT_DT`] of simulated time in
    /// between), each value stored to f32 precision (times exactly).
    #[default]
    Compact,
    /// Every kept sample (see `every`) with full f64 values (replay compares bitwise).
    Full,
}

/// Simulated-time spacing of the regular samples of a compact recording (s).
pub const COMPACT_DT: f64 = 1e-3;

/// Default interval of the 3D scene updates (s of simulated time).
pub const DEFAULT_SCENE_DT: f64 = 2e-3;

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
    /// Trajectory resolution (compact by default; `full` for every sample in f64).
    #[serde(default)]
    pub resolution: Resolution,
    /// Epoch of the recording's time axis, whole seconds since 1970 (the run's start time,
    /// set by the run layer when the run folder is created; 0 = 1970-01-01). Design k's
    /// time window starts at epoch + k s.
    #[serde(default)]
    pub epoch_s: u64,
}

impl Default for RecordOptions {
    fn default() -> Self {
        RecordOptions {
            enabled: true,
            trajectories: TrajectoryKeep::All,
            every: 1,
            scene_dt: DEFAULT_SCENE_DT,
            zstd_level: DEFAULT_ZSTD_LEVEL,
            zstd_threads: DEFAULT_ZSTD_THREADS,
            resolution: Resolution::Compact,
            epoch_s: 0,
        }
    }
}

impl RecordOptions {
    /// Nothing recorded.
    pub fn none() -> Self {
        RecordOptions {
            enabled: false,
            trajectories: TrajectoryKeep::None,
            every: 1,
            scene_dt: 0.0,
            zstd_level: DEFAULT_ZSTD_LEVEL,
            zstd_threads: DEFAULT_ZSTD_THREADS,
            resolution: Resolution::Compact,
            epoch_s: 0,
        }
    }
    /// Check the options a caller set (as flags are named: `--record-every`, `--scene-ms`,
    /// `--zstd-level`, `--zstd-threads`, `--record-full`): every ≥ 1 and only with a
    /// full-resolution recording of trajectories, full resolution only with trajectories,
    /// a finite scene interval ≥ 0, zstd levels 1 to 22, at most 256 zstd threads.
    pub fn validate(&self) -> crate::error::Result<()> {
        let bad = |field: &str, value: String, rule: &str| {
            Err(crate::error::Error::InvalidField {
                file: "command line".into(),
                field: field.into(),
                value,
                rule: rule.into(),
            })
        };
        if self.every == 0 {
            return bad("--record-every", "0".into(), "must be at least 1");
        }
        // flags that would be silently ignored: nothing to thin or keep in full
        let no_trajectories = !self.enabled || self.trajectories == TrajectoryKeep::None;
        if no_trajectories && self.every != 1 {
            return bad(
                "--record-every",
                self.every.to_string(),
                "no trajectory is recorded (--record none or designs)",
            );
        }
        if no_trajectories && self.resolution == Resolution::Full {
            return bad("--record-full", "given".into(), "no trajectory is recorded (--record none or designs)");
        }
        if self.every != 1 && self.resolution == Resolution::Compact {
            return bad(
                "--record-every",
                self.every.to_string(),
                "thins a full-resolution recording only: give --record-full too (the compact recording keeps its own subset of samples)",
            );
        }
        if !(self.scene_dt.is_finite() && self.scene_dt >= 0.0) {
            return bad("--scene-ms", format!("{}", self.scene_dt * 1e3), "must be a number >= 0");
        }
        if !(1..=22).contains(&self.zstd_level) {
            return bad("--zstd-level", self.zstd_level.to_string(), "zstd levels are 1 to 22");
        }
        if self.zstd_threads > 256 {
            return bad("--zstd-threads", self.zstd_threads.to_string(), "at most 256");
        }
        Ok(())
    }

    /// These options with the epoch set to the current time when it is still 0 (called
    /// once, where a run folder is created; the epoch is then stored in run.json).
    pub fn starting_now(self) -> Self {
        if self.epoch_s != 0 {
            return self;
        }
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        RecordOptions { epoch_s: now, ..self }
    }

    /// Epoch of the time axis in nanoseconds since 1970.
    pub fn epoch_ns(&self) -> u64 {
        self.epoch_s.saturating_mul(1_000_000_000)
    }

    /// Indices of the samples kept (every `every`-th, the last always).
    pub fn kept(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        let every = self.every.max(1) as usize;
        (0..n).filter(move |&i| i % every == 0 || i + 1 == n)
    }

    /// Indices of the samples recorded from a trajectory: [`RecordOptions::kept`] at full
    /// resolution; at compact resolution the first and last sample, both samples around
    /// every change of contact state (δ > 0) at either contact, every local maximum of
    /// |normal force| (either contact) and of |hand force|, and the first sample at least
    /// [`COMPACT_DT`] after the previously kept one.
    pub fn kept_samples(&self, samples: &[Sample]) -> Vec<usize> {
        let n = samples.len();
        if self.resolution == Resolution::Full {
            return self.kept(n).collect();
        }
        let mut keep = vec![false; n];
        if n == 0 {
            return vec![];
        }
        keep[0] = true;
        keep[n - 1] = true;
        // a local peak of |normal force 1|, |normal force 2| or |hand force|
        let v = |s: &Sample, c: usize| match c {
            0 => s.normal[0].abs(),
            1 => s.normal[1].abs(),
            _ => s.hand_fy.abs(),
        };
        for i in 1..n {
            let (a, b) = (&samples[i - 1], &samples[i]);
            if (0..2).any(|c| (a.delta[c] > 0.0) != (b.delta[c] > 0.0)) {
                keep[i - 1] = true;
                keep[i] = true;
            }
            if let Some(z) = samples.get(i + 1) {
                if (0..3).any(|c| v(b, c) > v(a, c) && v(b, c) >= v(z, c)) {
                    keep[i] = true;
                }
            }
        }
        let mut last_t = f64::NEG_INFINITY;
        for i in 0..n {
            if samples[i].t - last_t >= COMPACT_DT {
                keep[i] = true;
            }
            if keep[i] {
                last_t = samples[i].t;
            }
        }
        (0..n).filter(|&i| keep[i]).collect()
    }
}
