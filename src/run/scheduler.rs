//! The batch evaluator of the gripper problem: a generation's designs expanded into
//! (design, scenario) tasks for list scheduling, so that a few designs with many scenarios
//! keep every thread busy (a single-object problem: one task per design). First every
//! design's stages 0–2 on every object, in parallel; then the scenarios round by round (every
//! design's first scenario of every object, then the second, …; within a round the designs
//! the cost model predicts to be slowest first), each worker taking the next task from a
//! shared counter. A task a design no longer needs (an earlier scenario already decided its
//! verdict) is skipped. Each design's result is then folded from its scenarios in their fixed
//! order, exactly as [`GripperProblem::finish`](crate::optim::MooProblem::finish) does one
//! after the other: the same bits whatever the thread count or the schedule.

use super::gripper::{GripperInfo, GripperProblem};
use crate::eval::{DesignStart, Evaluation, ScenarioRecord};
use crate::optim::{Batch, CostHint, CostModel, Evaluations, Evaluator, GenTiming, MooProblem};
use crate::record::KeptTrajectory;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

impl GripperProblem {
    /// The batch evaluator a run uses unless its caller gives one ([`StudyScheduled`]).
    pub fn default_evaluator(&self) -> Box<dyn Evaluator<GripperProblem>> {
        Box::new(StudyScheduled::default())
    }
}

/// The default evaluator of a gripper problem: (design, scenario) tasks by list scheduling.
#[derive(Debug, Default)]
pub struct StudyScheduled {
    model: CostModel,
    executed: AtomicU64,
    skipped: AtomicU64,
}

/// A design's scenarios while the batch runs: the records of those done (what the stopping
/// rule reads), their evaluations where the study keeps them and the recorder's trajectory,
/// and the last position it can still need.
struct Progress {
    records: Vec<Option<ScenarioRecord>>,
    kept: Vec<Option<(Option<Evaluation>, Option<KeptTrajectory>)>>,
    bound: usize,
    seconds: f64,
}

impl StudyScheduled {
    /// Scenario simulations this evaluator ran, and tasks it skipped because their design
    /// no longer needed them (both depend on the schedule; the results do not).
    pub fn tasks(&self) -> (u64, u64) {
        (self.executed.load(Ordering::Relaxed), self.skipped.load(Ordering::Relaxed))
    }

    /// Run the scenario tasks of `starts` (in `order` within each round) on the current pool.
    fn run_tasks(&self, p: &GripperProblem, starts: &[(DesignStart, CostHint, f64)], order: &[usize]) -> Vec<Progress> {
        let study = &p.study;
        let n = if p.options.dynamics { study.planned() } else { 0 };
        let tasks: Vec<(usize, usize)> =
            (0..n).flat_map(|j| order.iter().filter(|&&d| starts[d].0.passed()).map(move |&d| (d, j))).collect();
        let progress: Vec<Mutex<Progress>> = starts
            .iter()
            .map(|_| {
                let kept = (0..n).map(|_| None).collect();
                Mutex::new(Progress { records: vec![None; n], kept, bound: n, seconds: 0.0 })
            })
            .collect();
        let seq: Vec<(usize, usize)> = study.sequence().collect();
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
            let (rec, ev, tr) = p.run_scenario(&starts[d].0, o, k);
            self.executed.fetch_add(1, Ordering::Relaxed);
            let mut g = progress[d].lock().expect("progress");
            (g.records[j], g.kept[j]) = (Some(rec), Some((ev, tr)));
            g.seconds += clock.elapsed().as_secs_f64();
            let bound = study.needed_bound(&g.records);
            g.bound = g.bound.min(bound);
        });
        progress.into_iter().map(|m| m.into_inner().expect("progress")).collect()
    }
}

impl Evaluator<GripperProblem> for StudyScheduled {
    fn evaluate(&mut self, p: &GripperProblem, batch: &Batch<'_>) -> Evaluations<GripperInfo> {
        let t0 = Instant::now();
        let xs = batch.xs;
        let starts: Vec<(DesignStart, CostHint, f64)> = xs
            .par_iter()
            .map(|x| {
                let t = Instant::now();
                let (s, h) = p.start(x);
                (s, h, t.elapsed().as_secs_f64())
            })
            .collect();
        let hints: Vec<CostHint> = starts.iter().map(|s| s.1.clone()).collect();
        let order = self.model.order(&hints);
        let costly = hints.iter().filter(|h| matches!(h, CostHint::Costly(_))).count();
        let order_s = t0.elapsed().as_secs_f64();
        let progress = self.run_tasks(p, &starts, &order);
        let mut costs = Vec::with_capacity(xs.len());
        let mut start_costs = Vec::with_capacity(xs.len());
        let mut evaluated: Vec<_> = starts
            .iter()
            .zip(progress)
            .map(|((st, _, secs), mut prog)| {
                let mut kept = None;
                let scen = if st.passed() && p.options.dynamics {
                    let mut j = 0;
                    p.study.run_in_order(|_, _| {
                        let r = prog.records[j].take().expect("every needed scenario ran");
                        let (ev, tr) = prog.kept[j].take().expect("every needed scenario ran");
                        j += 1;
                        kept = kept.take().or(tr);
                        (r, ev)
                    })
                } else {
                    vec![]
                };
                costs.push(secs + prog.seconds);
                start_costs.push(*secs);
                p.evaluated(st, scen, kept)
            })
            .collect();
        // the recorder's deciding scenario of each robust design, re-simulated in parallel
        evaluated.par_iter_mut().zip(&starts).for_each(|(e, (st, _, _))| p.keep_deciding_scenario(st, e));
        for (h, e) in hints.iter().zip(&evaluated) {
            let runs = e.info.record.robust.as_ref().map_or(1, |r| r.scenarios_run);
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
