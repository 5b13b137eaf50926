//! Benchmarks: the speed figures of docs/benchmarks.md (not tests). `gripopt bench …` calls
//! them; the diffsol comparison (`crates/diffsol-bench`, a cargo bench) reuses the
//! work-precision reference, error measures and table writers from here. Each benchmark
//! writes its figures as text to the writer it is given (the CLI's stdout, or stderr with
//! `--json`), returns them as a JSON summary, and writes its tables into the folder it is
//! given. What they tell while they run goes to the caller's [`BenchProgress`].
//!
//! The top layer of the library: it may use everything below it.

mod accuracy;
mod accuracy_table;
mod ensemble;
mod free;
mod nsga;
mod order;
mod replay;
mod scaling;
mod static_eval;
mod table;
mod work_precision;

pub use accuracy::{accuracy, AccuracyBench, Candidate, KITCHEN_FRONT_DESIGN, REFERENCE_ATOL, REFERENCE_RTOL};
pub use accuracy_table::{
    CandidateSummary, GraspOutcome, Kind, Outcomes, Quantity, RobustOutcome, ScenarioOutcome, RULE_MAX, RULE_P90,
};
pub use ensemble::{ensemble_cases, work_precision_ensemble, Case, EnsembleBench};
pub use free::{free_scene, FreeBench, FreeRow, FREE_REFERENCE_RTOL, FREE_RTOLS};
pub use nsga::nsga;
pub use order::{radau_order, simulate_order, Order};
pub use replay::{replay, ReplayBench};
pub use scaling::{scaling, ScalingBench};
pub use static_eval::static_pipeline;
pub use table::Row;
pub use table::{plot, print_table, print_targets, write_csv};
pub use work_precision::{check_atol, work_precision, Measured, Reference, WorkPrecision, RTOLS};

/// Where a benchmark writes its text report.
pub type Out<'a> = &'a mut dyn std::io::Write;

use std::time::Instant;

/// Write one line of a benchmark's text report to `out` (a library `Error` on failure, so a
/// closed pipe ends the CLI quietly).
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {
        writeln!($out, $($arg)*).map_err(|e| crate::Error::io("<benchmark report>", "cannot write the report", e))?
    };
}
pub(crate) use say;

/// Run `f` until `max_reps` runs, stopping earlier once `budget_s` seconds are spent and
/// at least three (or `max_reps`, if fewer) ran: the last result and the minimum and median
/// times in seconds. `max_reps` ≥ 1 is honoured as a maximum (`--reps 1` runs once).
pub fn time_it<T, F: FnMut() -> T>(mut f: F, budget_s: f64, max_reps: usize) -> (T, f64, f64) {
    let mut ts = vec![];
    let start = Instant::now();
    let mut last = None;
    let at_least = max_reps.clamp(1, 3);
    while ts.len() < at_least || (start.elapsed().as_secs_f64() < budget_s && ts.len() < max_reps) {
        let t0 = Instant::now();
        let r = f();
        ts.push(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    let (min, med) = min_med(ts);
    (last.expect("ran"), min, med)
}

/// What a bench says after `wrote A and B`: that it replaced earlier files there, if any
/// existed before it wrote (`existed`). A bench's files are regenerated figures, rewritten by
/// every run (`make bench` included), so they need no `--force`; the overwrite is said,
/// never silent (docs/benchmarks.md).
pub(crate) fn replaced_note(existed: bool) -> &'static str {
    if existed {
        " (replacing the earlier files of that name)"
    } else {
        ""
    }
}

/// The median of the non-NaN values of `v`, the conventional one: the middle value, or
/// for an even count the mean of the two middle values; NaN if none.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| !x.is_nan());
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Minimum and (conventional) median of a non-empty list.
pub(crate) fn min_med(v: Vec<f64>) -> (f64, f64) {
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    (min, median(v))
}

/// What a benchmark tells its caller as it goes, for a progress display: the library never
/// draws or prints (the CLI shows an indicatif bar on stderr). Phases follow one another, each
/// begun, stepped and ended. Every method does nothing by default; `()` shows nothing.
pub trait BenchProgress: Sync {
    /// A phase of `len` steps begins: `label` names it (`"bench free"`), `unit` says what it
    /// counts (`"shards"`; may be empty) until a [`message`](Self::message) says more.
    fn begin(&self, _label: &str, _len: u64, _unit: &str) {}
    /// What the current step is (a method and its tolerance).
    fn message(&self, _m: &str) {}
    /// One step of the phase done.
    fn step(&self) {}
    /// The phase is over.
    fn end(&self) {}
}

/// No progress shown.
impl BenchProgress for () {}
