//! The gripper design problem: the staged pipeline as a [`MooProblem`] over
//! (l21, b, t22, r, p, ψ°) with objectives (−max_offset, α, −F̃, t_stab) (MODEL.md §10),
//! and how its individuals are handed to the recorder ([`Recordable`]).

use crate::eval::{stage3_ends_at_once, DesignStart, EvalOptions, Evaluation, Folded, Record, ScenarioRecord, Study};
use crate::optim::{CostHint, Evaluated, Individual, Infeasibility, MooProblem};
use crate::params::{Design, Problem};
use crate::record::{DesignEntry, KeptTrajectory, RecordOptions, Recordable, ScenarioMotion, ScenarioScene};
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
    /// A robust design's deciding scenario as the recording draws it, re-simulated after its
    /// verdict and kept only until the recorder has written it (never checkpointed).
    #[serde(skip)]
    pub scenario: Option<Arc<ScenarioScene>>,
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
        GripperInfo {
            record: Arc::new(Record::from_eval(ev)),
            stage_seconds: ev.stage_seconds,
            trajectory: None,
            scenario: None,
        }
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
            scenario: i.scenario.as_deref(),
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
    /// What every design is evaluated on: the problem's objects and scenarios (a
    /// single-object problem's one object in its scene; for stages 0–2 alone, a robust
    /// problem's reference object).
    pub study: Arc<Study>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl GripperProblem {
    /// Wrap a problem file (all four stages, the problem's solver settings).
    pub fn new(problem: Problem) -> Self {
        let options = EvalOptions::full(&problem);
        Self::with_options(problem, options)
    }

    /// Wrap a problem file evaluated through `options`' stages.
    pub fn with_options(problem: Problem, options: EvalOptions) -> Self {
        let (lo, hi) = (problem.bounds.lo.to_vec(), problem.bounds.hi.to_vec());
        let study = Arc::new(Study::of(&problem, &options));
        GripperProblem { problem, options, recording: RecordOptions::none(), study, lo, hi }
    }

    /// The evaluation of a design from its stages 0–2 and its scenarios (in their order, each
    /// with its evaluation where the study keeps it), with the recorder's trajectory.
    pub fn evaluated(
        &self,
        start: &DesignStart,
        scen: Vec<(ScenarioRecord, Option<Evaluation>)>,
        trajectory: Option<KeptTrajectory>,
    ) -> Evaluated<GripperInfo> {
        let seconds = scen.first().and_then(|s| s.1.as_ref()).map_or_else(
            || {
                let mut s = start.base.stage_seconds;
                s[3] = 0.0;
                s
            },
            |ev| ev.stage_seconds,
        );
        let Folded { record, minimised } = self.study.fold(start, scen);
        let v = &record.verdict;
        let cv = match v.failed_stage {
            None => Infeasibility::FEASIBLE,
            Some(stage) => Infeasibility { stages_short: 4 - stage, violation: v.violation.unwrap_or(1e3) },
        };
        let info = GripperInfo {
            record: Arc::new(record),
            stage_seconds: seconds,
            trajectory: trajectory.map(Arc::new),
            scenario: None,
        };
        Evaluated { f: minimised.to_vec(), cv, info }
    }

    /// Keep for the recorder the scenario that decided the verdict of `e` (a robust design
    /// that reached its scenarios, started as `start`; [`crate::eval::RobustRecord::deciding`]),
    /// re-simulated, where the run records trajectories of such a design (`--record all`, or
    /// `feasible` and the design is feasible). Re-running a scenario gives the bits the
    /// evaluation gave, so nothing of the verdict changes.
    pub fn keep_deciding_scenario(&self, start: &DesignStart, e: &mut Evaluated<GripperInfo>) {
        let r = &self.recording;
        let wanted = match r.trajectories {
            TrajectoryKeep::All => true,
            TrajectoryKeep::Feasible => e.info.record.verdict.failed_stage.is_none(),
            TrajectoryKeep::None => false,
        };
        if !(r.enabled && wanted && self.options.dynamics && !self.study.is_single() && start.passed()) {
            return;
        }
        let rec = &e.info.record;
        let Some((j, decides)) =
            rec.robust.as_ref().and_then(|rb| rb.deciding(rec.verdict.failed_stage, rec.verdict.cause))
        else {
            return;
        };
        let ran = &rec.robust.as_ref().expect("a robust record").scenarios[j];
        let (o, k) = (ran.object, ran.k);
        let mut sink = (crate::sim::Trajectory::default(), Vec::<crate::sim::PoseSample>::new());
        let (again, ev) = self.study.run_scenario(start, o, k, &self.options, &mut sink);
        debug_assert_eq!(again.as_written(), ran.as_written(), "a scenario re-run gives the same record");
        let motion = if ev.free.is_some() {
            ScenarioMotion::free(&sink.1, r)
        } else {
            ScenarioMotion::Centred(KeptTrajectory::of(&sink.0, r))
        };
        let sc = self.study.scenario(o, k);
        e.info.scenario = Some(Arc::new(ScenarioScene {
            object: o,
            name: self.study.object_name(o).unwrap_or_default().to_string(),
            k,
            decides,
            scene: sc.scene.clone(),
            height_offset: sc.scenario.value("height_offset").unwrap_or(0.0),
            study: (self.study.objects(), self.study.k),
            motion,
        }));
    }

    /// Which trajectory the recorder keeps of a design, if any.
    pub fn keeps_trajectory(&self) -> TrajectoryKeep {
        if self.recording.enabled && self.study.is_single() && self.options.dynamics {
            self.recording.trajectories
        } else {
            TrajectoryKeep::None
        }
    }

    /// Scenario k of object o of a started design, its samples kept for the recorder as
    /// [`GripperProblem::keeps_trajectory`] says: its record, its evaluation where the study
    /// keeps it (the 1 × 1 study's), and the kept trajectory.
    pub fn run_scenario(
        &self,
        start: &DesignStart,
        o: usize,
        k: usize,
    ) -> (ScenarioRecord, Option<Evaluation>, Option<KeptTrajectory>) {
        let keep = self.keeps_trajectory();
        let mut tr = crate::sim::Trajectory::default();
        let (rec, ev) = match keep {
            TrajectoryKeep::None => self.study.run_scenario(start, o, k, &self.options, &mut ()),
            _ => self.study.run_scenario(start, o, k, &self.options, &mut tr),
        };
        let kept = match keep {
            TrajectoryKeep::None => None,
            _ if ev.dynamics.is_none() || (keep == TrajectoryKeep::Feasible && ev.discard.is_some()) => None,
            // the full trajectory is dropped here: only the recorded samples wait
            _ => Some(KeptTrajectory::of(&tr, &self.recording)),
        };
        (rec, self.study.is_single().then_some(ev), kept)
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
    type Started = DesignStart;
    fn start(&self, x: &[f64]) -> (DesignStart, CostHint) {
        let st = self.study.start(&design_of(x));
        let hint = self.cost_hint(x, &st);
        (st, hint)
    }
    /// Stage 3: the design's scenarios in their order (a single-object problem's one
    /// simulation in its scene), keeping what the recorder uses of the trajectory as
    /// `recording` says.
    fn finish(&self, _x: &[f64], started: DesignStart) -> Evaluated<GripperInfo> {
        let mut kept = None;
        let scen = if started.passed() && self.options.dynamics {
            self.study.run_in_order(|o, k| {
                let (rec, ev, tr) = self.run_scenario(&started, o, k);
                kept = kept.take().or(tr);
                (rec, ev)
            })
        } else {
            vec![]
        };
        let mut e = self.evaluated(&started, scen, kept);
        self.keep_deciding_scenario(&started, &mut e);
        e
    }
    /// The simulations' right-hand-side evaluations (deterministic; proportional to their
    /// time within a few per cent): the centred scene's, plus for a free-kind problem the
    /// free scene's weighted by `FREE_RHS_WEIGHT`.
    /// A member of the population keeps its record (shared) and timings, not the recording's
    /// trajectory: that waits in the generation's evaluated designs until its shard is written.
    fn member_info(&self, info: &GripperInfo) -> GripperInfo {
        GripperInfo { record: info.record.clone(), stage_seconds: info.stage_seconds, trajectory: None, scenario: None }
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

impl GripperProblem {
    /// The cost hint of a started design. In a single-object problem stages 0–2 (tens of µs)
    /// tell a design they discard, or whose stage 3 ends before its simulation, cheap; one
    /// that is simulated (ms) is costly, described for the solver's cost model by its design
    /// vector, derived lengths l11, l12, l22 and the stage-2 objectives (more stage-2 values,
    /// e.g. spring preload, contact angles and forces, ordered worse on the bottle problem:
    /// too many features for the few rows of the first generations). A design on drawn
    /// scenarios is costly when its scenarios will run, described by its design vector and
    /// derived lengths (the cost model learns the work per scenario).
    fn cost_hint(&self, x: &[f64], st: &DesignStart) -> CostHint {
        let (Some(k), true, true) = (&st.base.kin, st.passed(), self.options.dynamics) else { return CostHint::Cheap };
        let f = &k.finger;
        let mut v = x.to_vec();
        v.extend([f.l11, f.l12, f.l22]);
        if !self.study.is_single() {
            return CostHint::Costly(v);
        }
        match &st.base.statics {
            Some(s) if !stage3_ends_at_once(s, &self.problem.scene, &self.options) => {
                v.extend([s.alpha, s.mean_force, s.max_offset]);
                CostHint::Costly(v)
            }
            _ => CostHint::Cheap,
        }
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
