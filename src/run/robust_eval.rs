//! The batch evaluator of a robust problem: a generation's designs expanded into
//! (design, scenario) tasks for list scheduling, so that a few designs with many scenarios
//! keep every thread busy. First every design's stages 0–2 on every object, in parallel;
//! then the scenarios round by round (every design's first scenario of every object, then the
//! second, …; within a round the designs the cost model predicts to be slowest first), each
//! worker taking the next task from a shared counter. A task a design no longer needs (an
//! earlier scenario already made some object's constraint impossible) is skipped. Each
//! design's result is then folded from its scenarios in their fixed order, exactly as
//! [`GripperProblem::finish`](crate::optim::MooProblem::finish) does one after the other: the
//! same bits whatever the thread count or the schedule.

use super::gripper::{GripperInfo, GripperProblem, Started};
use crate::eval::{fold, needed_bound, run_scenario, RobustStart, ScenarioRecord};
use crate::optim::{Batch, CostHint, CostModel, Evaluations, Evaluator, GenTiming, MooProblem, Scheduled};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

impl GripperProblem {
    /// The batch evaluator a run uses unless its caller gives one: for a robust problem the
    /// one that spreads every design's scenarios over the threads ([`RobustScheduled`]),
    /// else [`Scheduled`].
    pub fn default_evaluator(&self) -> Box<dyn Evaluator<GripperProblem>> {
        match self.robust {
            Some(_) => Box::new(RobustScheduled::default()),
            None => Box::new(Scheduled::default()),
        }
    }
}

/// The default evaluator of a gripper problem: robust problems by (design, scenario) tasks,
/// others by [`Scheduled`].
#[derive(Debug, Default)]
pub struct RobustScheduled {
    inner: Scheduled,
    model: CostModel,
    executed: AtomicU64,
    skipped: AtomicU64,
}

/// A design's scenarios while the batch runs: those done, and the last position it can
/// still need.
struct Progress {
    done: Vec<Option<ScenarioRecord>>,
    bound: usize,
    seconds: f64,
}

impl RobustScheduled {
    /// Scenario simulations this evaluator ran, and tasks it skipped because their design
    /// no longer needed them (both depend on the schedule; the results do not).
    pub fn tasks(&self) -> (u64, u64) {
        (self.executed.load(Ordering::Relaxed), self.skipped.load(Ordering::Relaxed))
    }
}

impl Evaluator<GripperProblem> for RobustScheduled {
    fn evaluate(&mut self, p: &GripperProblem, batch: &Batch<'_>) -> Evaluations<GripperInfo> {
        let Some(setup) = p.robust.clone() else { return self.inner.evaluate(p, batch) };
        let t0 = Instant::now();
        let xs = batch.xs;
        let starts: Vec<(RobustStart, CostHint, f64)> = xs
            .par_iter()
            .map(|x| {
                let t = Instant::now();
                let (s, h) = p.start(x);
                let Started::Robust(s) = s else { unreachable!("a robust problem starts robust designs") };
                (s, h, t.elapsed().as_secs_f64())
            })
            .collect();
        let hints: Vec<CostHint> = starts.iter().map(|s| s.1.clone()).collect();
        let order = self.model.order(&hints);
        let costly = hints.iter().filter(|h| matches!(h, CostHint::Costly(_))).count();
        let seq: Vec<(usize, usize)> = setup.sequence().collect();
        let tasks: Vec<(usize, usize)> = (0..seq.len())
            .flat_map(|j| order.iter().filter(|&&d| starts[d].0.passed()).map(move |&d| (d, j)))
            .collect();
        let progress: Vec<Mutex<Progress>> = starts
            .iter()
            .map(|_| Mutex::new(Progress { done: vec![None; seq.len()], bound: seq.len(), seconds: 0.0 }))
            .collect();
        let order_s = t0.elapsed().as_secs_f64();
        let next = AtomicUsize::new(0);
        let workers = rayon::current_num_threads().min(tasks.len()).max(1);
        (0..workers).into_par_iter().with_max_len(1).for_each(|_| loop {
            let t = next.fetch_add(1, Ordering::Relaxed);
            let Some(&(d, j)) = tasks.get(t) else { break };
            if j > progress[d].lock().expect("progress").bound {
                self.skipped.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            let clock = Instant::now();
            let (o, k) = seq[j];
            let (rec, _) = run_scenario(&starts[d].0, &setup, o, k, &p.options, &mut ());
            self.executed.fetch_add(1, Ordering::Relaxed);
            let mut g = progress[d].lock().expect("progress");
            g.done[j] = Some(rec);
            g.seconds += clock.elapsed().as_secs_f64();
            let bound = needed_bound(&setup, &g.done);
            g.bound = g.bound.min(bound);
        });
        let mut costs = Vec::with_capacity(xs.len());
        let mut start_costs = Vec::with_capacity(xs.len());
        let evaluated: Vec<_> = starts
            .iter()
            .zip(progress)
            .map(|((st, _, secs), prog)| {
                let mut prog = prog.into_inner().expect("progress");
                let scen = if st.passed() {
                    let mut j = 0;
                    fold(&setup, |_, _| {
                        let r = prog.done[j].take().expect("every needed scenario ran");
                        j += 1;
                        r
                    })
                } else {
                    vec![]
                };
                costs.push(secs + prog.seconds);
                start_costs.push(*secs);
                p.robust_evaluated(&setup, st, scen)
            })
            .collect();
        for (h, e) in hints.iter().zip(&evaluated) {
            let runs = e.info.record.robust.as_ref().map_or(0, |r| r.scenarios_run);
            if let (CostHint::Costly(f), Some(w)) = (h, p.work(e)) {
                if runs > 0 {
                    self.model.add(f, w / runs as f64);
                }
            }
        }
        self.model.refit();
        let timing = GenTiming::of_two_passes(t0, order_s, (costs, start_costs), order, costly);
        Evaluations { evaluated, timing }
    }
}
