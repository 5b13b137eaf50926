//! Running NSGA-II in argmin's `Executor`, with observers for progress (indicatif) and
//! checkpoints (after the initial population and after every generation).

use super::checkpoint::{settings_hash, Checkpoint};
use super::nsga2::{Nsga2, Nsga2Settings, Nsga2State};
use super::MooProblem;
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Error, Executor, KV};
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
        let cp = Checkpoint {
            format: super::checkpoint::FORMAT.into(),
            version: super::checkpoint::VERSION,
            problem_hash: self.problem_hash.clone(),
            settings_hash: settings_hash(&self.settings, &self.options),
            settings: self.settings.clone(),
            options: self.options.clone(),
            state: state.clone(),
            wall_s: self.wall_before + self.start.elapsed().as_secs_f64(),
        };
        cp.save(&self.path).map_err(|e| Error::msg(e.to_string()))
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

/// Run NSGA-II from `state` (a fresh `Nsga2State::new()` or a loaded checkpoint state)
/// until `state.max_generations`, with the given observers. Returns the problem and the
/// final state; a ctrl-c stops after the current generation (its checkpoint is written).
pub fn execute<P, O>(problem: P, settings: Nsga2Settings, state: Nsga2State<P::Info>, observers: O, ctrlc: bool) -> Result<(P, Nsga2State<P::Info>), Error>
where
    P: MooProblem + 'static,
    P::Info: 'static,
    O: FnOnce(Executor<P, Nsga2, Nsga2State<P::Info>>) -> Executor<P, Nsga2, Nsga2State<P::Info>>,
{
    let exec = Executor::new(problem, Nsga2::new(settings)).configure(|_| state).ctrlc(ctrlc).timer(false);
    let exec = observers(exec);
    let mut res = exec.run()?;
    let p = res.problem.take_problem().ok_or_else(|| Error::msg("problem lost"))?;
    Ok((p, res.state))
}

/// Add an observer to an executor that is called every generation.
pub fn observe<P, OBS>(exec: Executor<P, Nsga2, Nsga2State<P::Info>>, obs: OBS) -> Executor<P, Nsga2, Nsga2State<P::Info>>
where
    P: MooProblem,
    OBS: Observe<Nsga2State<P::Info>> + 'static,
{
    exec.add_observer(obs, ObserverMode::Always)
}
