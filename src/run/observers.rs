//! What a run tells its caller ([`Progress`]: a generation done, a note), and the argmin
//! observer that passes the generations on; the outputs a persister writes per generation
//! ([`OutputsObserver`]). The library never prints: a progress bar, a log line or a stop
//! button is the caller's (the CLI draws an indicatif bar, the Python package calls back).

use super::archive::Archive;
use super::gripper::GripperInfo;
use crate::optim::{Nsga2Settings, Nsga2State};
use argmin::core::observers::Observe;
use argmin::core::{Error, KV};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// One generation of a run, as it is reported.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenerationReport {
    /// Completed generations (1 = the initial population).
    pub generation: u64,
    /// Total generations of the run.
    pub max_generations: u64,
    /// Designs evaluated so far.
    pub evaluations: u64,
    /// Population size.
    pub population: usize,
    /// Feasible members of the population.
    pub feasible: usize,
    /// Normalised hypervolume of the population's feasible front.
    pub hypervolume: f64,
}

/// What a run reports to its caller as it goes. Every method does nothing by default.
pub trait Progress: Send {
    /// Generation `g` is done and handed to the persister (its checkpoint follows). An
    /// error ends the run as a failure would: the checkpoint of this generation is still
    /// written, and the run can be resumed. (A clean stop is the run's stop flag.)
    fn generation(&mut self, _g: &GenerationReport) -> Result<(), String> {
        Ok(())
    }
    /// A message for the user: a warning, a note on the thread count.
    fn note(&mut self, _message: &str) {}
}

/// No progress reported.
impl Progress for () {}

/// The argmin observer that reports each generation to the caller's [`Progress`].
#[derive(Clone)]
pub(crate) struct ProgressObserver(pub Arc<Mutex<Box<dyn Progress>>>);

impl ProgressObserver {
    fn report<I>(&self, s: &Nsga2State<I>) -> Result<(), Error> {
        let g = GenerationReport {
            generation: s.generation,
            max_generations: s.max_generations,
            evaluations: s.evaluations,
            population: s.population.len(),
            feasible: s.feasible_history.last().copied().unwrap_or(0),
            hypervolume: s.hv_history.last().copied().unwrap_or(f64::NAN),
        };
        let r = self.0.lock().expect("progress lock").generation(&g);
        r.map_err(|m| Error::from(crate::Error::Optimiser(format!("stopped by the progress observer: {m}"))))
    }
}

impl<I> Observe<Nsga2State<I>> for ProgressObserver {
    fn observe_init(&mut self, _name: &str, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.report(state)
    }
    fn observe_iter(&mut self, state: &Nsga2State<I>, _kv: &KV) -> Result<(), Error> {
        self.report(state)
    }
}

/// The archive and the result CSVs of a run, updated after every generation (before the
/// checkpoint) so that a running run can be watched; shared, so that the caller can use
/// the archive.
#[derive(Clone)]
pub struct OutputsObserver {
    /// Run folder.
    pub out: PathBuf,
    /// Algorithm settings (hypervolume normalisation).
    pub settings: Nsga2Settings,
    /// The run's archive.
    pub archive: Arc<Mutex<Archive>>,
}

impl OutputsObserver {
    /// Add `st`'s last generation to the archive; a copy of the archive after it (for the
    /// generation's checkpoint).
    pub fn update_archive(&self, st: &Nsga2State<GripperInfo>) -> Archive {
        let mut a = self.archive.lock().expect("archive lock");
        a.update(st, &self.settings);
        a.clone()
    }

    /// Rewrite the CSV views (pareto, population, archive, history) of `st` and the archive,
    /// the files in parallel in the current rayon pool; the seconds each file took.
    pub fn write_views(&self, st: &Nsga2State<GripperInfo>) -> crate::Result<[f64; 5]> {
        let a = self.archive.lock().expect("archive lock");
        super::outputs::write_tables_timed(&self.out, st, &a)
    }
}
