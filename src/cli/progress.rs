//! The run's progress as the CLI shows it (the library reports it, [`gripopt::app::Progress`]):
//! on a terminal an indicatif bar (generation, evaluations/s, feasible count, hypervolume,
//! ETA); otherwise (a log file, a pipe) one line per generation on stderr. Notes and
//! warnings go to stderr. The first ctrl-c — or SIGTERM (a batch scheduler's walltime) or
//! SIGHUP (a closed terminal) — sets the run's stop flag and says so on stderr (the run
//! stops after the current generation's checkpoint); a second one ends the process at once
//! (exit 130; the last checkpoint resumes it). Nothing written to stderr ends the run when
//! stderr is gone (a closed terminal): those writes are never checked.

use gripopt::app::{GenerationReport, Progress};
use std::io::Write as _;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Progress on stderr.
pub struct Bar {
    bar: indicatif::ProgressBar,
    start: Instant,
    evals_at_start: Option<u64>,
    gen_at_start: Option<u64>,
    first_shown: Option<Instant>,
    log_lines: bool,
}

impl Bar {
    /// A bar when stderr is a terminal, else one log line per generation.
    pub fn new() -> Self {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let bar = if terminal { indicatif::ProgressBar::new(1) } else { indicatif::ProgressBar::hidden() };
        bar.set_style(
            indicatif::ProgressStyle::with_template("{prefix} [{bar:25}] gen {pos}/{len} {msg}")
                .expect("template")
                .progress_chars("=> "),
        );
        bar.set_prefix("NSGA-II");
        Bar {
            bar,
            start: Instant::now(),
            evals_at_start: None,
            gen_at_start: None,
            first_shown: None,
            log_lines: !terminal,
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

impl Progress for Bar {
    fn generation(&mut self, s: &GenerationReport) -> Result<(), String> {
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
            s.population as f64 / (now - self.start).as_secs_f64().max(1e-9)
        };
        let per_gen = if s.generation > g_first {
            since / (s.generation - g_first) as f64
        } else {
            (now - self.start).as_secs_f64()
        };
        let eta = per_gen * s.max_generations.saturating_sub(s.generation) as f64;
        let (feas, hv, pop) = (s.feasible, s.hypervolume, s.population);
        self.bar.set_length(s.max_generations);
        self.bar.set_position(s.generation);
        self.bar.set_message(format!("{rate:.0} evals/s, feasible {feas}/{pop}, HV {hv:.4}, ETA {eta:.0} s"));
        if self.log_lines {
            let _ = writeln!(
                std::io::stderr(),
                "generation {}/{}  evaluations {}  feasible {feas}/{pop}  hypervolume {hv:.4}  {rate:.0} evaluations/s  ETA {eta:.0} s",
                s.generation,
                s.max_generations,
                s.evaluations
            );
        }
        Ok(())
    }
    fn note(&mut self, message: &str) {
        self.bar.suspend(|| {
            let _ = writeln!(std::io::stderr(), "{message}");
        });
    }
}

/// A stop flag set by ctrl-c, SIGTERM or SIGHUP (the `ctrlc` crate's `termination`
/// feature): the run stops after the current generation's checkpoint, which a line on
/// stderr acknowledges; a second signal ends the process at once (exit 130).
pub fn ctrl_c_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // a second handler cannot be installed; the first one (this process's only run) stands
    let _ = ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            let _ = writeln!(
                std::io::stderr(),
                "\nctrl-c (or TERM/HUP) again: stopped now (the last checkpoint resumes the run)"
            );
            std::process::exit(130);
        }
        let _ = writeln!(
            std::io::stderr(),
            "\nctrl-c (or TERM/HUP): stopping after this generation's checkpoint (again to stop now; the last checkpoint resumes the run)"
        );
    });
    flag
}
