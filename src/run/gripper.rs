//! The gripper design problem: the staged pipeline as a [`MooProblem`] over
//! (l21, b, t22, r, p, ψ°) with objectives (−max_offset, α, −F̃, t_stab) (MODEL.md §10),
//! and how its individuals are handed to the recorder ([`Recordable`]).

use crate::eval::{
    evaluate_dynamics, evaluate_statics, fold, robust_record_ranked, robust_start, run_scenario, stage3_ends_at_once,
    EvalOptions, Evaluation, Record, RobustSetup, RobustStart,
};
use crate::optim::{CostHint, Evaluated, Individual, Infeasibility, MooProblem};
use crate::params::{Design, Problem};
use crate::record::{DesignEntry, KeptTrajectory, RecordOptions, Recordable};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub use crate::record::TrajectoryKeep;

/// What is kept of each evaluated design: its record, and (not deterministic) its timings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GripperInfo {
    /// The evaluation's record (every output of the design is derived from it), shared: an
    /// individual is copied into the population, the archive and the persister's hand-over
    /// of each generation, its record never (a record is ~1.5 KB; issue 23 item 3).
    #[serde(with = "shared_record")]
    pub record: Arc<Record>,
    /// Wall time per stage (s): [unused, stages 0–1, stage 2, stage 3]. Not deterministic.
    pub stage_seconds: [f64; 4],
    /// What the recording uses of the stage-3 trajectory, reduced right after the
    /// evaluation and kept only until the recorder has written it (never checkpointed).
    #[serde(skip)]
    pub trajectory: Option<Arc<KeptTrajectory>>,
}

/// Serde of the shared record: as the record itself.
mod shared_record {
    use super::{Arc, Record};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(r: &Arc<Record>, s: S) -> Result<S::Ok, S::Error> {
        r.as_ref().serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Arc<Record>, D::Error> {
        Record::deserialize(d).map(Arc::new)
    }
}

impl GripperInfo {
    /// From a pipeline evaluation.
    pub fn from_eval(ev: &Evaluation) -> Self {
        GripperInfo { record: Arc::new(Record::from_eval(ev)), stage_seconds: ev.stage_seconds, trajectory: None }
    }
}

impl Recordable for Individual<GripperInfo> {
    fn entry(&self) -> DesignEntry<'_> {
        let i = &self.eval.info;
        DesignEntry {
            id: self.id,
            generation: self.generation,
            parameters: self.x.as_slice().try_into().expect("six design variables"),
            record: &i.record,
            stage_seconds: i.stage_seconds,
            trajectory: i.trajectory.as_deref(),
        }
    }
}

/// The gripper problem for the optimiser.
#[derive(Debug, Clone)]
pub struct GripperProblem {
    /// The loaded problem file.
    pub problem: Problem,
    /// Pipeline options (stage 3 in pipeline mode).
    pub options: EvalOptions,
    /// The run's recording options: which trajectories to keep for the recorder
    /// (`trajectories`, when `enabled`), reduced to the samples these options record
    /// ([`KeptTrajectory`]). Nothing is kept by default ([`RecordOptions::none`]).
    pub recording: RecordOptions,
    /// A robust problem's objects and scenarios (None: one object, nominal inputs).
    pub robust: Option<std::sync::Arc<RobustSetup>>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl GripperProblem {
    /// Wrap a problem file.
    pub fn new(problem: Problem) -> Self {
        let options = EvalOptions::full(&problem);
        let (lo, hi) = (problem.bounds.lo.to_vec(), problem.bounds.hi.to_vec());
        let robust = RobustSetup::of(&problem).map(std::sync::Arc::new);
        GripperProblem { problem, options, recording: RecordOptions::none(), robust, lo, hi }
    }

    /// The evaluation of a robust design from its stages 0–2 and its scenarios.
    pub fn robust_evaluated(
        &self,
        setup: &RobustSetup,
        start: &RobustStart,
        scen: Vec<crate::eval::ScenarioRecord>,
    ) -> Evaluated<GripperInfo> {
        let mut seconds = start.base.stage_seconds;
        seconds[3] = 0.0;
        let (record, ranked_offset) = robust_record_ranked(setup, start, scen);
        let v = &record.verdict;
        let cv = match v.failed_stage {
            None => Infeasibility::FEASIBLE,
            Some(stage) => Infeasibility { stages_short: 4 - stage, violation: v.violation.unwrap_or(1e3) },
        };
        // the record's max_offset is None where not form closed; the ranking keeps −Δ_off
        let mut o = record.objectives();
        o[0] = ranked_offset;
        let ph = self.placeholders();
        let f = (0..4).map(|k| o[k].map(|v| if k == 0 || k == 2 { -v } else { v }).unwrap_or(ph[k])).collect();
        Evaluated { f, cv, info: GripperInfo { record: Arc::new(record), stage_seconds: seconds, trajectory: None } }
    }

    /// The finite placeholders of MODEL.md §10 for missing objectives (minimisation form).
    fn placeholders(&self) -> [f64; 4] {
        [self.problem.scene.criteria.offset_step, 1e6, 0.0, self.problem.scene.criteria.t_max]
    }

    /// Objectives used for ranking: feasible designs have all four; missing values are the
    /// finite placeholders of MODEL.md §10 (they are never compared: only feasible designs
    /// are ranked by objectives).
    pub fn minimisation_objectives(&self, ev: &Evaluation) -> Vec<f64> {
        let o = ev.objectives();
        let ph = self.placeholders();
        (0..4).map(|k| if o[k].is_finite() { o[k] } else { ph[k] }).collect()
    }

    /// Ideal and reference points for the progress hypervolume (minimisation form):
    /// max_offset ∈ [0, off_max], α ∈ [0, 1], F̃ ∈ [0, 2τ/l21_min], t_stab ∈ [0, t_max].
    pub fn hv_points(&self) -> (Vec<f64>, Vec<f64>) {
        let s = &self.problem.scene;
        let fmax = 2.0 * s.hand.tau / self.problem.bounds.lo[0];
        (vec![-s.criteria.offset_max, 0.0, -fmax, 0.0], vec![0.0, 1.0, 0.0, s.criteria.t_max])
    }
}

impl MooProblem for GripperProblem {
    type Info = GripperInfo;
    fn name(&self) -> String {
        self.problem.name.clone()
    }
    fn lower(&self) -> &[f64] {
        &self.lo
    }
    fn upper(&self) -> &[f64] {
        &self.hi
    }
    fn n_obj(&self) -> usize {
        4
    }
    /// Stages 0–2 (tens of µs): a design they discard, or whose stage 3 ends before its
    /// simulation, is cheap; one that is simulated (ms) is costly, described for the solver's
    /// cost model by its design vector, derived lengths l11, l12, l22 and the stage-2
    /// objectives (more stage-2 values, e.g. spring preload, contact angles and forces,
    /// ordered worse on the bottle problem: too many features for the few rows of the
    /// first generations).
    type Started = Started;
    fn start(&self, x: &[f64]) -> (Started, CostHint) {
        // stages 0–2 only (`--static-only`, Python's `static_only=True`): a robust problem's
        // reference object, as `gripopt evaluate --static-only` and `gripopt::evaluate`
        if let Some(setup) = self.robust.as_ref().filter(|_| self.options.dynamics) {
            let st = robust_start(&design_of(x), setup);
            let hint = robust_hint(x, &st);
            return (Started::Robust(st), hint);
        }
        let ev = evaluate_statics(&design_of(x), &self.problem.scene);
        let hint = match (&ev.kin, &ev.statics) {
            (Some(k), Some(st))
                if self.options.dynamics && !stage3_ends_at_once(st, &self.problem.scene, &self.options) =>
            {
                let f = &k.finger;
                let mut v = x.to_vec();
                v.extend([f.l11, f.l12, f.l22, st.alpha, st.mean_force, st.max_offset]);
                CostHint::Costly(v)
            }
            _ => CostHint::Cheap,
        };
        (Started::Nominal(ev), hint)
    }
    /// Stage 3 (the simulation in the problem's scene), keeping what the recorder uses of
    /// the trajectory as `recording` says.
    fn finish(&self, _x: &[f64], started: Started) -> Evaluated<GripperInfo> {
        let started = match (started, &self.robust) {
            (Started::Nominal(ev), _) => ev,
            (Started::Robust(st), Some(setup)) => {
                let scen = if st.passed() {
                    fold(setup, |o, k| run_scenario(&st, setup, o, k, &self.options, &mut ()).0)
                } else {
                    vec![]
                };
                return self.robust_evaluated(setup, &st, scen);
            }
            (Started::Robust(_), None) => unreachable!("a robust start comes from a robust problem"),
        };
        let (scene, opts) = (&self.problem.scene, &self.options);
        let keep = if self.recording.enabled { self.recording.trajectories } else { TrajectoryKeep::None };
        let (ev, traj) = match keep {
            _ if !opts.dynamics => (started, None),
            TrajectoryKeep::None => (evaluate_dynamics(started, scene, opts, &mut ()), None),
            keep => {
                let mut tr = crate::sim::Trajectory::default();
                let ev = evaluate_dynamics(started, scene, opts, &mut tr);
                let tr = if ev.dynamics.is_none() || (keep == TrajectoryKeep::Feasible && ev.discard.is_some()) {
                    None
                } else {
                    // the full trajectory is dropped here: only the recorded samples wait
                    Some(KeptTrajectory::of(&tr, &self.recording))
                };
                (ev, tr)
            }
        };
        let cv = match ev.discard {
            None => Infeasibility::FEASIBLE,
            Some(d) => Infeasibility { stages_short: 4 - d.stage, violation: d.violation },
        };
        let mut info = GripperInfo::from_eval(&ev);
        info.trajectory = traj.map(Arc::new);
        Evaluated { f: self.minimisation_objectives(&ev), cv, info }
    }
    /// The simulations' right-hand-side evaluations (deterministic; proportional to their
    /// time within a few per cent): the centred scene's, plus for a free-kind problem the
    /// free scene's weighted by `FREE_RHS_WEIGHT`.
    /// A member of the population keeps its record (shared) and timings, not the recording's
    /// trajectory: that waits in the generation's evaluated designs until its shard is written.
    fn member_info(&self, info: &GripperInfo) -> GripperInfo {
        GripperInfo { record: info.record.clone(), stage_seconds: info.stage_seconds, trajectory: None }
    }
    fn work(&self, e: &Evaluated<GripperInfo>) -> Option<f64> {
        let r = &e.info.record;
        if let Some(rb) = &r.robust {
            return (rb.scenarios_run > 0).then(|| rb.rhs_evals[0] as f64 + FREE_RHS_WEIGHT * rb.rhs_evals[1] as f64);
        }
        let centred = r.grasp.work.rhs_evals.map(|w| w as f64);
        let free = r.free_scene.as_ref().and_then(|f| f.work.rhs_evals).map(|w| FREE_RHS_WEIGHT * w as f64);
        match (centred, free) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0.0) + b.unwrap_or(0.0)),
        }
    }
}

/// What [`GripperProblem::start`] leaves for [`GripperProblem::finish`].
#[derive(Debug)]
pub enum Started {
    /// Stages 0–2 of a single-object problem.
    Nominal(Evaluation),
    /// Stages 0–2 on every object of a robust problem.
    Robust(RobustStart),
}

/// The cost hint of a robust design: costly (its design vector and derived lengths as
/// features) when its scenarios will run.
fn robust_hint(x: &[f64], st: &RobustStart) -> CostHint {
    match (&st.base.kin, st.passed()) {
        (Some(k), true) => {
            let f = &k.finger;
            let mut v = x.to_vec();
            v.extend([f.l11, f.l12, f.l22]);
            CostHint::Costly(v)
        }
        _ => CostHint::Cheap,
    }
}

/// Cost of one right-hand side of the free scene (21 states, both fingers and the object)
/// in centred-scene right-hand sides (6 states, one finger): `gripopt simulate
/// problems/bottle-1l.toml [--scene free] --json` gave 2.2 ms for 7 717 and 18.3 ms for
/// 9 881. Only weighs work for ordering it.
pub(crate) const FREE_RHS_WEIGHT: f64 = 6.5;

/// The design of a decision vector (the solver always passes six variables).
fn design_of(x: &[f64]) -> Design {
    let arr: [f64; 6] = x.try_into().expect("six design variables");
    Design::from_array(&arr)
}
