//! Folding a design's scenarios into its result: the stopping rule (stop as soon as the
//! verdict is known), the fold itself (the 1 × 1 study's record is its one scenario's
//! evaluation; a chance-constrained study's is aggregated, `chance.rs`), and a design
//! evaluated one scenario after the other. Scenarios run in a fixed order — round k visits
//! every object's scenario k — so a result depends on that order only, never on which thread
//! ran what.

use super::chance::chance_record;
use super::objectives::minimised;
use super::record::Record;
use super::record_robust::ScenarioRecord;
use super::scenario::DesignStart;
use super::stages::{EvalOptions, Evaluation};
use super::stop::StopRule;
use super::study::Study;
use crate::params::Design;

/// The result of a design's scenarios, folded: its record, and its objectives as the
/// optimiser ranks them (minimisation form, MODEL.md §10's finite placeholders where one was
/// not computed; the raw max_offset −Δ_off of a design not form closed, which no output
/// reports).
#[derive(Debug, Clone)]
pub struct Folded {
    /// The design's record.
    pub record: Record,
    /// (−max_offset, α, −F̃, t_stab), finite.
    pub minimised: [f64; 4],
}

impl Study {
    /// The scenarios of a design in their order, each from `get(o, k)`, stopping after the one
    /// that decides the verdict ([`StopRule`]) when `early_stop` is set.
    pub fn run_in_order<T>(
        &self,
        mut get: impl FnMut(usize, usize) -> (ScenarioRecord, T),
    ) -> Vec<(ScenarioRecord, T)> {
        let mut rule = StopRule::new(self);
        let mut out = Vec::with_capacity(self.planned());
        for (o, k) in self.sequence() {
            let r = get(o, k);
            let decided = rule.push(&r.0).is_some();
            out.push(r);
            if decided && self.early_stop {
                break;
            }
        }
        out
    }

    /// The last position in the sequence a design can still need, knowing only some of its
    /// scenarios (`done[j]`: the record of position j once it has run): the first known
    /// position that [`StopRule`] stops at whatever the unknown positions before it hold — an
    /// aborted scenario, or one whose object already has more measured failures than allowed
    /// among the known positions up to it. The true stop can only be earlier (unknown
    /// positions before it may stop the rule too), so no position after this bound is needed.
    pub fn needed_bound(&self, done: &[Option<ScenarioRecord>]) -> usize {
        let last = self.planned().saturating_sub(1);
        if !self.early_stop {
            return last;
        }
        let fmax = self.failures_allowed();
        let mut fails = vec![0usize; self.objects()];
        for (j, (o, _)) in self.sequence().enumerate() {
            let Some(r) = done.get(j).and_then(Option::as_ref) else { continue };
            if r.aborted() {
                return j;
            }
            if !r.stays {
                fails[o] += 1;
                if fails[o] > fmax {
                    return j;
                }
            }
        }
        last
    }

    /// Fold a design's scenarios (`scen`, in their order; with each its evaluation, which
    /// the 1 × 1 study's record is) into its result.
    pub fn fold(&self, start: &DesignStart, scen: Vec<(ScenarioRecord, Option<Evaluation>)>) -> Folded {
        let c = &self.base.criteria;
        if self.is_single() {
            let ev = scen.into_iter().next().and_then(|s| s.1).unwrap_or(start.base);
            let minimised = minimised(ev.natural_objectives(), c);
            return Folded { record: Record::from_eval(&ev), minimised };
        }
        let (record, ranked_offset) = chance_record(self, start, scen.into_iter().map(|s| s.0).collect());
        let mut o = record.objectives();
        o[0] = ranked_offset;
        Folded { minimised: minimised(o, c), record }
    }

    /// Design `x` evaluated one scenario after the other (what a worker or the facade does;
    /// the batch evaluator gives the same result in parallel), with `sink` given every
    /// scenario's samples.
    pub fn evaluate_into<K: crate::sim::Sink + ?Sized>(&self, x: &Design, opts: &EvalOptions, sink: &mut K) -> Folded {
        let st = self.start(x);
        let keep = self.is_single();
        let scen = if st.passed() && opts.dynamics {
            self.run_in_order(|o, k| {
                let (r, ev) = self.run_scenario(&st, o, k, opts, sink);
                (r, keep.then_some(ev))
            })
        } else {
            vec![]
        };
        self.fold(&st, scen)
    }

    /// [`Study::evaluate_into`] without a sink.
    pub fn evaluate(&self, x: &Design, opts: &EvalOptions) -> Folded {
        self.evaluate_into(x, opts, &mut ())
    }
}
