//! Batch evaluation, the problem side's (argmin's `bulk_cost`, pymoo's `Evaluator`): the
//! optimiser hands each generation's new designs to an [`Evaluator`] and gets their
//! evaluations back in the same order. The default, [`Scheduled`](super::Scheduled),
//! evaluates them in the current rayon pool in two passes ordered by a learnt cost model;
//! another evaluator may run them elsewhere (a cluster, a Python caller) or expand each
//! design into several tasks (scenarios) and aggregate them — the optimiser does not know.

use super::{Evaluated, MooProblem};

/// One batch to evaluate: a generation's new decision vectors.
#[derive(Debug, Clone, Copy)]
pub struct Batch<'a> {
    /// The decision vectors, in the order their evaluations must come back.
    pub xs: &'a [Vec<f64>],
    /// The id of the first design (ids run on in order).
    pub first_id: u64,
    /// The generation the designs belong to (1 = the initial population).
    pub generation: u64,
}

/// What an evaluator gives back for a batch.
#[derive(Debug, Clone)]
pub struct Evaluations<I> {
    /// One evaluation per decision vector, in the batch's order.
    pub evaluated: Vec<Evaluated<I>>,
    /// Where the time went (for benchmarks; [`GenTiming::default`] with `eval_s` is enough).
    pub timing: GenTiming,
}

/// Evaluates batches of designs of a [`MooProblem`] for the optimiser.
///
/// Contract: the evaluations come back in the batch's order, each a deterministic function
/// of its decision vector alone, so that a run is fixed by its seed whatever the thread
/// count, the schedule or the machine that evaluated it.
pub trait Evaluator<P: MooProblem>: Send {
    /// Evaluate `batch` of problem `p`.
    fn evaluate(&mut self, p: &P, batch: &Batch<'_>) -> Evaluations<P::Info>;
}

impl<P: MooProblem, E: Evaluator<P> + ?Sized> Evaluator<P> for Box<E> {
    fn evaluate(&mut self, p: &P, batch: &Batch<'_>) -> Evaluations<P::Info> {
        (**self).evaluate(p, batch)
    }
}

/// Wall-clock accounting of one generation inside the solver (not deterministic).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GenTiming {
    /// Seconds evaluating (the parallel part, including waiting for its last design).
    pub eval_s: f64,
    /// Seconds of the first pass (every design's cheap start) and ordering; part of `eval_s`.
    pub order_s: f64,
    /// Seconds of the solver's own serial work (variation, survival, hypervolume).
    pub serial_s: f64,
    /// Of it, the exact hypervolume of the feasible front (history and progress).
    pub hv_s: f64,
    /// Wall seconds of each evaluation (start + finish), in the order of `last_evaluated`.
    pub costs: Vec<f64>,
    /// Of it, the cheap start (the first pass).
    pub start_costs: Vec<f64>,
    /// The order in which the designs were finished (indices into `last_evaluated`).
    pub order: Vec<usize>,
    /// How many designs their start called costly (the first ones of `order`).
    pub costly: usize,
}

impl GenTiming {
    /// A two-pass evaluation's timing, started at `t0`: the solver's serial parts are filled
    /// in by the solver.
    pub fn of_two_passes(
        t0: std::time::Instant,
        order_s: f64,
        (costs, start_costs): (Vec<f64>, Vec<f64>),
        order: Vec<usize>,
        costly: usize,
    ) -> GenTiming {
        let eval_s = t0.elapsed().as_secs_f64();
        GenTiming { eval_s, order_s, serial_s: 0.0, hv_s: 0.0, costs, start_costs, order, costly }
    }
}
