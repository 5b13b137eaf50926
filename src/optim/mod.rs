//! Multi-objective optimisation: a generational evolutionary algorithm with constrained
//! domination (NSGA-II, or by default hypervolume survival with differential evolution), in
//! the Problem / Algorithm / Termination vocabulary of pymoo and run by argmin's `Executor`.
//!
//! - [`MooProblem`]: what is optimised (bounds, objectives in minimisation form, staged
//!   infeasibility, per-design info kept for reports);
//! - `nsga2`: the algorithm (argmin `Solver`) and its state (argmin `State`);
//! - `survival`: which of parents and offspring survive ([`Survival`]: crowding or
//!   hypervolume contribution); `variation`: how offspring are made ([`Variation`]: SBX or
//!   differential evolution);
//! - `sort`: non-dominated sorting and crowding; `operators`: SBX, polynomial mutation;
//! - `evaluator`: batch evaluation, the problem side's ([`Evaluator`]); `schedule`: its
//!   default ([`Scheduled`]: two passes ordered by cost hints and a learnt cost model);
//! - `hv`: exact hypervolume and IGD; `hvc`: exclusive hypervolume contributions, greedy
//!   least-contributor removal and greedy hypervolume subset selection;
//! - `testproblems`: ZDT, DTLZ2, BNH, TNK, OSY, C2-DTLZ2;
//! - `serde_f64`: exact (bit-preserving) serialisation of floats, so a state can be saved
//!   and restored.
//!
//! This layer is pure: no files, no recording, no gripper. Runs with run folders,
//! checkpoints, observers and the gripper problem live in the run layer above it.

mod evaluator;
mod hv;
mod hvc;
mod nsga2;
mod operators;
mod schedule;
mod serde_f64;
mod sort;
mod survival;
mod testproblems;
mod variation;

use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::cmp::Ordering;

/// How infeasible a solution is: the number of pipeline stages it fell short of, then the
/// violation at the failing stage. `(0, 0)` is feasible. Lexicographic order: smaller is better.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Infeasibility {
    /// Stages not reached (0 = all passed).
    pub stages_short: u8,
    /// Non-negative violation at the failing stage (sum of violations for plain problems).
    pub violation: f64,
}

impl Infeasibility {
    /// The feasible value.
    pub const FEASIBLE: Infeasibility = Infeasibility { stages_short: 0, violation: 0.0 };

    /// From a sum of constraint violations (test problems).
    pub fn from_violation(v: f64) -> Self {
        if v > 0.0 {
            Infeasibility { stages_short: 1, violation: v }
        } else {
            Self::FEASIBLE
        }
    }
    /// True when feasible.
    pub fn is_feasible(&self) -> bool {
        self.stages_short == 0
    }
    /// Lexicographic comparison (smaller = better).
    pub fn cmp_key(&self, o: &Self) -> Ordering {
        self.stages_short.cmp(&o.stages_short).then(self.violation.total_cmp(&o.violation))
    }
}

/// The result of evaluating one decision vector.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluated<I> {
    /// Objectives in minimisation form (only used when feasible).
    #[serde(with = "serde_f64")]
    pub f: Vec<f64>,
    /// Infeasibility.
    pub cv: Infeasibility,
    /// Problem-specific information kept for reports.
    pub info: I,
}

/// A multi-objective problem with box bounds.
pub trait MooProblem: Sync {
    /// Per-design information kept with each individual (reports, CSV rows).
    type Info: Clone + Send + Sync + Serialize + DeserializeOwned + std::fmt::Debug;
    /// Name.
    fn name(&self) -> String;
    /// Lower bounds.
    fn lower(&self) -> &[f64];
    /// Upper bounds.
    fn upper(&self) -> &[f64];
    /// Number of objectives.
    fn n_obj(&self) -> usize;
    /// What the cheap first part of an evaluation leaves for [`MooProblem::finish`].
    type Started: Send;
    /// Evaluate one decision vector (must be deterministic: results may not depend on the
    /// thread that runs it). The default is [`MooProblem::start`] then [`MooProblem::finish`].
    fn evaluate(&self, x: &[f64]) -> Evaluated<Self::Info> {
        let (s, _) = self.start(x);
        self.finish(x, s)
    }
    /// The cheap first part of evaluating `x`, and what it says of the rest's cost. The
    /// solver starts every design of a generation, then finishes them longest first; the
    /// hint only orders the work, results never depend on it.
    fn start(&self, x: &[f64]) -> (Self::Started, CostHint);
    /// The rest of the evaluation of `x` after [`MooProblem::start`].
    fn finish(&self, x: &[f64], started: Self::Started) -> Evaluated<Self::Info>;
    /// A deterministic measure of the work an evaluation took (e.g. right-hand-side
    /// evaluations of a simulation), which the solver's [`CostModel`] learns to predict from
    /// the hints' features; `None` (the default) when there is none.
    fn work(&self, _e: &Evaluated<Self::Info>) -> Option<f64> {
        None
    }
    /// What a member of the population keeps of its evaluation's info: the population
    /// outlives the generation that evaluated it, and what only that generation's observers
    /// use (a recording's trajectory) need not live as long. The default keeps all of it.
    fn member_info(&self, info: &Self::Info) -> Self::Info {
        info.clone()
    }
    /// Number of variables.
    fn n_var(&self) -> usize {
        self.lower().len()
    }
}

/// One member of a population.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound = "I: Serialize + DeserializeOwned")]
pub struct Individual<I> {
    /// Unique id within a run (0, 1, 2, … in order of creation).
    pub id: u64,
    /// Generation in which it was created (1 = initial population).
    pub generation: u64,
    /// Decision vector.
    #[serde(with = "serde_f64")]
    pub x: Vec<f64>,
    /// Evaluation.
    pub eval: Evaluated<I>,
}

/// Constrained domination (Deb): does `a` dominate `b`?
pub fn constrained_dominates(af: &[f64], acv: &Infeasibility, bf: &[f64], bcv: &Infeasibility) -> bool {
    match (acv.is_feasible(), bcv.is_feasible()) {
        (true, false) => true,
        (false, true) => false,
        (false, false) => acv.cmp_key(bcv) == Ordering::Less,
        (true, true) => dominates(af, bf),
    }
}

/// Pareto domination for minimisation.
#[inline]
pub fn dominates(a: &[f64], b: &[f64]) -> bool {
    let mut strictly = false;
    for (x, y) in a.iter().zip(b) {
        if x > y {
            return false;
        }
        if x < y {
            strictly = true;
        }
    }
    strictly
}

pub use evaluator::{Batch, Evaluations, Evaluator, GenTiming};
pub use hv::{hypervolume, igd, nondominated_below};
pub use hvc::{contributions, greedy_subset, least_contributor_selection};
pub use nsga2::{execute, observe, Nsga2, Nsga2Settings, Nsga2State};
pub use operators::{polynomial_mutation, sbx, Operators};
pub use schedule::{CostHint, CostModel, Scheduled};
pub use serde_f64::{deserialize, serialize};
pub use sort::{constrained_ranks, crowding, pareto_ranks, rank_and_crowding, survivors, survivors_with_attributes};
pub use survival::{survive, Normalisation, Survival, SURVIVAL_REFERENCE};
pub use testproblems::{c2_constraint, reference_settings, run_test, run_test_with, Test, TestProblem, TestRun};
pub use variation::Variation;
