//! argmin observers of an NSGA-II run: progress (indicatif), checkpoints and recording
//! (after the initial population and after every generation), and a crash hook for tests.
//! Library errors pass through argmin's error unchanged and come back from
//! [`crate::optim::execute`] as they were.

use super::archive::Archive;
use super::gripper::GripperInfo;
use crate::optim::Individual;
use crate::optim::{Nsga2Settings, Nsga2State};
use crate::record::Recorder;
use argmin::core::observers::Observe;
use argmin::core::{Error, KV};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Progress: on a terminal an indicatif bar (generation, evaluations/s, feasible count,
/// hypervolume, ETA); otherwise (a log file, a pipe) one line per generation on stderr.
pub struct ProgressObserver {
    bar: indicatif::ProgressBar,
    start: Instant,
    evals_at_start: Option<u64>,
    gen_at_start: Option<u64>,
    first_shown: Option<Instant>,
    log_lines: bool,
}

impl ProgressObserver {
    /// Progress over `total` generations; nothing when `visible` is false, a bar when stderr
    /// is a terminal, else one log line per generation.
    pub fn new(total: u64, first: u64, visible: bool) -> Self {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let bar =
            if visible && terminal { indicatif::ProgressBar::new(total) } else { indicatif::ProgressBar::hidden() };
        bar.set_style(
            indicatif::ProgressStyle::with_template("{prefix} [{bar:25}] gen {pos}/{len} {msg}")
                .expect("template")
                .progress_chars("=> "),
        );
        bar.set_prefix("NSGA-II");
        bar.set_position(first.saturating_sub(1));
        ProgressObserver {
            bar,
            start: Instant::now(),
            evals_at_start: None,
            gen_at_start: None,
            first_shown: None,
            log_lines: visible && !terminal,
        }
    }
    fn show<I>(&mut self, s: &Nsga2State<I>) {
        // rate and ETA from the generations since the first one shown (measured between two
        // observations, so neither start-up nor the first generation's own set-up skew it)
        let now = Instant::now();
        let e0 = *self.evals_at_start.get_or_insert(s.evaluations);
        let g_first = *self.gen_at_start.get_or_insert(s.generation);
        let t_first = *self.first_shown.get_or_insert(now);
        let since = (now - t_first).as_secs_f64();
        let rate = if s.evaluations > e0 {
            (s.evaluations - e0) as f64 / since.max(1e-9)
        } else {
            s.population.len() as f64 / (now - self.start).as_secs_f64().max(1e-9)
        };
        let per_gen = if s.generation > g_first {
            since / (s.generation - g_first) as f64
        } else {
            (now - self.start).as_secs_f64()
        };
        let eta = per_gen * s.max_generations.saturating_sub(s.generation) as f64;
        let feas = s.feasible_history.last().copied().unwrap_or(0);
        let hv = s.hv_history.last().copied().unwrap_or(f64::NAN);
        self.bar.set_length(s.max_generations);
        self.bar.set_position(s.generation);
        self.bar.set_message(format!(
            "{rate:.0} evals/s, feasible {feas}/{}, HV {hv:.4}, ETA {eta:.0} s",
            s.population.len()
        ));
        if self.log_lines {
            eprintln!(
                "generation {}/{}  evaluations {}  feasible {feas}/{}  hypervolume {hv:.4}  {rate:.0} evaluations/s  ETA {eta:.0} s",
                s.generation, s.max_generations, s.evaluations, s.population.len()
            );
        }
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

/// Rewrites the archive and the result CSVs after every generation (before the checkpoint),
/// so that a running run can be watched; shared, so that the caller can use the archive.
#[derive(Clone)]
pub struct OutputsObserver {
    /// Run folder.
    pub out: PathBuf,
    /// Force model name (a column of the design CSVs).
    pub force_model: &'static str,
    /// Algorithm settings (hypervolume normalisation).
    pub settings: Nsga2Settings,
    /// The run's archive.
    pub archive: Arc<Mutex<Archive>>,
}

impl OutputsObserver {
    fn write(&self, st: &Nsga2State<GripperInfo>) -> Result<(), Error> {
        let bytes = self.update_archive(st)?;
        super::archive::save_bytes(&self.out, &bytes)?;
        self.write_views(st)?;
        Ok(())
    }

    /// Add `st`'s last generation to the archive; the archive's bytes for `archive.json`
    /// (written later, just before the generation's checkpoint).
    pub fn update_archive(&self, st: &Nsga2State<GripperInfo>) -> crate::Result<Vec<u8>> {
        let mut a = self.archive.lock().expect("archive lock");
        a.update(st, &self.settings);
        a.to_bytes(&self.out)
    }

    /// Rewrite the CSV views (pareto, population, archive, history) of `st` and the archive,
    /// the files in parallel in the current rayon pool; the seconds each file took.
    pub fn write_views(&self, st: &Nsga2State<GripperInfo>) -> crate::Result<[f64; 5]> {
        let a = self.archive.lock().expect("archive lock");
        super::outputs::write_tables_timed(&self.out, st, &a)
    }
}

impl Observe<Nsga2State<GripperInfo>> for OutputsObserver {
    fn observe_init(&mut self, _name: &str, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), Error> {
        self.write(st)
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> Result<(), Error> {
        self.write(st)
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
