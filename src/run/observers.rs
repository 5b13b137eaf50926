//! argmin observers of an NSGA-II run: progress (indicatif), checkpoints and recording
//! (after the initial population and after every generation), and a crash hook for tests.
//! Library errors pass through argmin's error unchanged and come back from
//! [`crate::optim::execute`] as they were.

use super::checkpoint::Checkpoint;
use super::gripper::GripperInfo;
use crate::optim::{Nsga2Settings, Nsga2State};
use crate::optim::Individual;
use crate::record::Recorder;
use argmin::core::observers::Observe;
use argmin::core::{Error, KV};
use serde::{de::DeserializeOwned, Serialize};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// indicatif progress: generation, evaluations/s, feasible count, hypervolume, ETA.
pub struct ProgressObserver {
    bar: indicatif::ProgressBar,
    start: Instant,
    evals_at_start: Option<u64>,
}

impl ProgressObserver {
    /// A progress bar over `total` generations (hidden when `visible` is false).
    pub fn new(total: u64, first: u64, visible: bool) -> Self {
        let bar = if visible { indicatif::ProgressBar::new(total) } else { indicatif::ProgressBar::hidden() };
        bar.set_style(
            indicatif::ProgressStyle::with_template("{prefix} [{bar:25}] gen {pos}/{len} {msg} ETA {eta}")
                .expect("template")
                .progress_chars("=> "),
        );
        bar.set_prefix("NSGA-II");
        bar.set_position(first.saturating_sub(1));
        ProgressObserver { bar, start: Instant::now(), evals_at_start: None }
    }
    fn show<I>(&mut self, s: &Nsga2State<I>) {
        let e0 = *self.evals_at_start.get_or_insert(s.evaluations.saturating_sub(s.population.len() as u64));
        let rate = (s.evaluations - e0) as f64 / self.start.elapsed().as_secs_f64().max(1e-9);
        let feas = s.feasible_history.last().copied().unwrap_or(0);
        let hv = s.hv_history.last().copied().unwrap_or(f64::NAN);
        self.bar.set_length(s.max_generations);
        self.bar.set_position(s.generation);
        self.bar.set_message(format!("{rate:.0} evals/s, feasible {feas}/{}, HV {hv:.4}", s.population.len()));
    }
    /// Finish and clear the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Shared handle, so that the caller can finish the bar after the run.
#[derive(Clone)]
pub struct SharedProgress(pub Arc<Mutex<ProgressObserver>>);

impl<I> Observe<Nsga2State<I>> for SharedProgress {
    fn observe_init(&mut self, _name: &str, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.0.lock().expect("progress lock").show(state);
        Ok(())
    }
    fn observe_iter(&mut self, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.0.lock().expect("progress lock").show(state);
        Ok(())
    }
}

/// Writes a checkpoint after the initial population and after every generation.
pub struct CheckpointObserver {
    /// Checkpoint path.
    pub path: PathBuf,
    /// SHA-256 of the problem file.
    pub problem_hash: String,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// Run options that change results.
    pub options: serde_json::Value,
    /// Wall seconds before this process started.
    pub wall_before: f64,
    /// Start of this process's run.
    pub start: Instant,
}

impl CheckpointObserver {
    fn save<I: Serialize + DeserializeOwned + Clone>(&self, state: &Nsga2State<I>) -> Result<(), Error> {
        let wall_s = self.wall_before + self.start.elapsed().as_secs_f64();
        let cp = Checkpoint::new(self.problem_hash.clone(), self.settings.clone(), self.options.clone(), state.clone(), wall_s);
        Ok(cp.save(&self.path)?)
    }
}

impl<I: Serialize + DeserializeOwned + Clone> Observe<Nsga2State<I>> for CheckpointObserver {
    fn observe_init(&mut self, _name: &str, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.save(state)
    }
    fn observe_iter(&mut self, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.save(state)
    }
}

/// Records each generation's evaluated designs into one shard (shared, so that the caller
/// can read the recorder's counters after the run).
#[derive(Clone)]
pub struct RecordingObserver(pub Arc<Mutex<Recorder>>);

impl RecordingObserver {
    fn record(&self, st: &Nsga2State<GripperInfo>) -> Result<(), Error> {
        let designs: Vec<&Individual<GripperInfo>> = st.last_evaluated.iter().collect();
        Ok(self.0.lock().expect("recorder lock").record_generation(st.generation, &designs)?)
    }
}

impl Observe<Nsga2State<GripperInfo>> for RecordingObserver {
    fn observe_init(&mut self, _name: &str, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), Error> {
        self.record(st)
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), Error> {
        self.record(st)
    }
}

/// Test hook: fails once generation `.0` is complete (after the observers added before it
/// ran, so its checkpoint is written), as a crash would.
pub struct CrashAfter(pub u64);

impl<I> Observe<Nsga2State<I>> for CrashAfter {
    fn observe_iter(&mut self, s: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        if s.generation >= self.0 {
            return Err(Error::msg(format!("simulated crash after generation {}", s.generation)));
        }
        Ok(())
    }
    fn observe_init(&mut self, _n: &str, s: &Nsga2State<I>, kv: &KV) -> Result<(), Error> {
        self.observe_iter(s, kv)
    }
}
