//! The robust sub-record of an evaluation record (`robust`): the aggregated objectives, per
//! object its static objectives, its scenarios' P(stay) with a Clopper–Pearson interval and
//! aggregates, and per scenario a compact record (which scenario, its drawn inputs, the
//! outcome) — enough to replay a failing scenario.

use super::objectives::Objectives;
use super::scene_record::fin;
use super::stages::{Cause, Evaluation};
use crate::params::{input_slot, Scenario, INPUTS, N_INPUTS};
use serde::{Deserialize, Serialize};

/// The drawn inputs of a scenario (nominal where not uncertain), one value per row of
/// [`INPUTS`], written as an object keyed by the rows' names in their order.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ScenarioInputs(pub [f64; N_INPUTS]);

impl ScenarioInputs {
    /// From a scenario's values.
    pub fn of(v: &[f64; N_INPUTS]) -> Self {
        ScenarioInputs(*v)
    }
    /// The value of input `name` (a row of [`INPUTS`]).
    pub fn get(&self, name: &str) -> Option<f64> {
        input_slot(name).map(|i| self.0[i])
    }
    /// The inputs as `gripopt replay --scenario` shows them, comma-separated.
    pub fn shown(&self) -> String {
        INPUTS.iter().zip(self.0).map(|(row, v)| (row.shown)(v)).collect::<Vec<_>>().join(", ")
    }
}

impl Serialize for ScenarioInputs {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(N_INPUTS))?;
        for (row, v) in INPUTS.iter().zip(self.0) {
            m.serialize_entry(row.name, &v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for ScenarioInputs {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let m = std::collections::BTreeMap::<String, f64>::deserialize(d)?;
        let mut v = [0.0; N_INPUTS];
        for (slot, row) in v.iter_mut().zip(INPUTS.iter()) {
            *slot = *m.get(row.name).ok_or_else(|| serde::de::Error::missing_field(row.name))?;
        }
        Ok(ScenarioInputs(v))
    }
}

/// One scenario of a design: which, its inputs, what happened.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioRecord {
    /// Object index.
    pub object: usize,
    /// Scenario index within the object.
    pub k: usize,
    /// The drawn inputs.
    pub inputs: ScenarioInputs,
    /// The grasp held the object in place: the centred grasp met the finger's criteria and
    /// the free object barely moved (MODEL.md §14.4).
    pub stays: bool,
    /// What failed (null when it stayed).
    pub cause: Option<Cause>,
    /// Time to stability of the centred grasp (s; null when it did not stabilise).
    pub t_stab: Option<f64>,
    /// The free object's largest horizontal displacement (m; null: the free scene did not run).
    pub max_displacement: Option<f64>,
    /// Its largest tilt (°).
    pub max_tilt_deg: Option<f64>,
    /// Right-hand-side evaluations of the centred grasp and of the free scene.
    pub rhs_evals: [u64; 2],
    /// Accepted steps of both.
    pub steps: [u64; 2],
    /// The solver's own account when it aborted the scenario's simulation (cause `aborted` or
    /// `free_scene_aborted`): what the design's discard quotes. Not written: the record's
    /// `cause` gives the class, the design's reason the text.
    #[serde(skip)]
    pub abort: Option<SolverAbort>,
}

/// A scenario whose simulation the solver aborted (step budget, step size, events; a free
/// scene that ended before t_obs): the object's motion was never measured.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverAbort {
    /// The solver's message (as the single-object discard's reason words it).
    pub message: String,
    /// The single-object discard's violation of the same failure.
    pub violation: f64,
}

impl ScenarioRecord {
    /// The record of scenario `sc` evaluated as `ev`.
    pub fn of(sc: &Scenario, ev: &Evaluation) -> Self {
        let d = ev.dynamics.as_ref();
        // a free scene that never started (an open finger in the object at t = 0) measured nothing
        let f = ev.free.as_ref().filter(|f| f.end.ran());
        ScenarioRecord {
            object: sc.object,
            k: sc.k,
            inputs: ScenarioInputs::of(&sc.values),
            stays: ev.discard.is_none(),
            cause: ev.discard.and_then(|d| d.reason.cause()),
            t_stab: d.and_then(|d| d.t_stab),
            max_displacement: f.and_then(|f| fin(f.object_max_displacement)),
            max_tilt_deg: f.and_then(|f| fin(f.object_max_tilt_deg)),
            rhs_evals: [d.map_or(0, |d| d.rhs_evals), f.map_or(0, |f| f.rhs_evals)],
            steps: [d.map_or(0, |d| d.stats.steps), f.map_or(0, |f| f.stats.steps)],
            abort: ev
                .discard
                .filter(|d| is_abort(d.reason.cause()))
                .map(|d| SolverAbort { message: d.reason.to_string(), violation: d.violation }),
        }
    }

    /// The solver aborted this scenario's simulation: it says nothing of whether the object
    /// stays.
    pub fn aborted(&self) -> bool {
        is_abort(self.cause)
    }

    /// This record as a recording reads it back: without the solver's account (`abort`,
    /// not written; its class is `cause`, its text the design's reason). What a replay
    /// compares a re-evaluation with the recording as.
    pub fn as_written(&self) -> Self {
        ScenarioRecord { abort: None, ..self.clone() }
    }
}

/// A cause that means the simulation was aborted, not a measured outcome.
fn is_abort(c: Option<Cause>) -> bool {
    matches!(c, Some(Cause::Aborted | Cause::FreeSceneAborted))
}

/// One object of a robust design.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ObjectRecord {
    /// Its name.
    pub name: String,
    /// The objectives on this object: max_offset, α and F̃ of stage 2 at its nominal
    /// inputs (max_offset None if not form closed at 0), t_stab aggregated over its
    /// scenarios (the problem's aggregation).
    #[serde(flatten)]
    pub objectives: Objectives,
    /// Scenarios run.
    pub scenarios: usize,
    /// Of them, those in which the object stayed.
    pub stays: usize,
    /// P̂(stay) = stays / scenarios.
    pub p_stay: Option<f64>,
    /// Lower end of its Clopper–Pearson interval.
    pub p_stay_lo: Option<f64>,
    /// Upper end.
    pub p_stay_hi: Option<f64>,
    /// P(stay) ≥ p_min holds (null: the design's scenarios stopped before this was known).
    pub meets_p_min: Option<bool>,
    /// The worst displacement of the free object over its scenarios (m).
    pub max_displacement: Option<f64>,
}

/// The robust sub-record.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RobustRecord {
    /// The objectives aggregated over the objects (t_stab over every scenario run): what
    /// the optimiser ranks; max_offset None where the aggregate is negative (an object not
    /// form closed at 0, which the optimiser ranks at −Δ_off, MODEL.md §6.7).
    pub objectives: Objectives,
    /// Per object.
    pub objects: Vec<ObjectRecord>,
    /// Scenarios the design would run without early stop.
    pub scenarios_planned: usize,
    /// Scenarios it ran.
    pub scenarios_run: usize,
    /// Scenarios early stop saved (planned − run; 0 when stage 2 discarded the design).
    pub scenarios_saved: usize,
    /// Right-hand-side evaluations of all its simulations (centred, free).
    pub rhs_evals: [u64; 2],
    /// Their accepted steps.
    pub steps: [u64; 2],
    /// Every scenario run, in the order run.
    pub scenarios: Vec<ScenarioRecord>,
}

impl RobustRecord {
    /// This record with max_offset None wherever it is negative: an older gripopt wrote the
    /// −Δ_off placeholder of a design not form closed here (aggregated and per object).
    pub fn without_offset_placeholder(&self) -> Self {
        let mut r = self.clone();
        r.objectives = r.objectives.reported();
        for o in &mut r.objects {
            o.objectives = o.objectives.reported();
        }
        r
    }

    /// This record as a recording reads it back: every scenario [`ScenarioRecord::as_written`].
    pub fn as_written(&self) -> Self {
        RobustRecord { scenarios: self.scenarios.iter().map(ScenarioRecord::as_written).collect(), ..self.clone() }
    }

    /// The object that decided a discard at `stage` with `cause`, read from the typed
    /// sub-record (never from the reason's words): at stage 2 the first object whose statics
    /// failed (its objectives unknown); at stage 3 the first aborted scenario's object for a
    /// solver failure, else the first object that fails P(stay) ≥ p_min. None at stages 0–1
    /// (the hand itself failed) and for a feasible design.
    pub fn failed_object(&self, stage: Option<u8>, cause: Option<Cause>) -> Option<usize> {
        match stage? {
            2 => self.objects.iter().position(|o| o.objectives.mean_force.is_none()),
            3 if matches!(cause, Some(Cause::Aborted | Cause::FreeSceneAborted)) => {
                self.scenarios.iter().find(|s| s.aborted()).map(|s| s.object)
            }
            3 => self.objects.iter().position(|o| o.meets_p_min == Some(false)),
            _ => None,
        }
    }
}

/// Why a scenario is the one that explains a robust design's verdict (the one its recording
/// draws, [`RobustRecord::deciding`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Decides {
    /// A feasible design: the scenario in which the free object moved most (its worst).
    WorstDisplacement,
    /// A feasible design none of whose scenarios measured a displacement: its first.
    FirstScenario,
    /// A P(stay) failure: the first scenario, in the order run, in which the failing object
    /// did not stay.
    FirstFailure,
    /// A solver failure: the scenario the solver aborted.
    Aborted,
}

impl Decides {
    /// The words shown (label, `/designs`).
    pub fn as_str(self) -> &'static str {
        match self {
            Decides::WorstDisplacement => "worst displacement",
            Decides::FirstScenario => "first scenario",
            Decides::FirstFailure => "first failure",
            Decides::Aborted => "aborted",
        }
    }
}

impl RobustRecord {
    /// The scenario that explains the verdict of a design that reached its scenarios (its
    /// position in `scenarios`, and why): a feasible design's worst by the free object's
    /// largest displacement (the first of equals), a P(stay) failure's first scenario, in the
    /// order run, in which the object that fails its constraint ([`RobustRecord::failed_object`])
    /// did not stay, a solver failure's aborted scenario. None when no scenario ran or the
    /// verdict is not a scenario's (stages 0–2).
    pub fn deciding(&self, stage: Option<u8>, cause: Option<Cause>) -> Option<(usize, Decides)> {
        if self.scenarios.is_empty() {
            return None;
        }
        match stage {
            None => {
                let worst = self.scenarios.iter().enumerate().filter_map(|(j, s)| s.max_displacement.map(|d| (j, d)));
                let worst = worst.fold(None, |a: Option<(usize, f64)>, (j, d)| match a {
                    Some((_, m)) if m >= d => a,
                    _ => Some((j, d)),
                });
                Some(worst.map_or((0, Decides::FirstScenario), |(j, _)| (j, Decides::WorstDisplacement)))
            }
            Some(3) if is_abort(cause) => {
                self.scenarios.iter().position(|s| s.aborted()).map(|j| (j, Decides::Aborted))
            }
            Some(3) => {
                let o = self.failed_object(stage, cause)?;
                self.scenarios.iter().position(|s| s.object == o && !s.stays).map(|j| (j, Decides::FirstFailure))
            }
            _ => None,
        }
    }
}

/// The robust part of `gripopt evaluate`'s report: per object its static objectives,
/// P(stay) with its interval and the scenarios run.
pub fn robust_summary(r: &RobustRecord) -> String {
    let o = |v: Option<f64>, s: f64, p: usize| v.map_or("—".to_string(), |v| format!("{:.*}", p, v * s));
    let mut out = format!(
        "robust     {} scenarios run of {} ({} saved by early stop)\n",
        r.scenarios_run, r.scenarios_planned, r.scenarios_saved
    );
    for ob in &r.objects {
        out.push_str(&format!(
            "  {:<14} P(stay) {} ({} of {}; CI [{}, {}])  max displacement {} mm  max_offset {} mm  alpha {}  mean force {} N  t_stab {} ms\n",
            ob.name,
            o(ob.p_stay, 1.0, 3),
            ob.stays,
            ob.scenarios,
            o(ob.p_stay_lo, 1.0, 3),
            o(ob.p_stay_hi, 1.0, 3),
            o(ob.max_displacement, 1e3, 3),
            o(ob.objectives.max_offset, 1e3, 2),
            o(ob.objectives.alpha, 1.0, 4),
            o(ob.objectives.mean_force, 1.0, 3),
            o(ob.objectives.t_stab, 1e3, 3)
        ));
    }
    let a = &r.objectives;
    out.push_str(&format!(
        "  aggregated     max_offset {} mm  alpha {}  mean force {} N  t_stab {} ms\n",
        o(a.max_offset, 1e3, 2),
        o(a.alpha, 1.0, 4),
        o(a.mean_force, 1.0, 3),
        o(a.t_stab, 1e3, 3)
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(object: usize, k: usize, stays: bool, disp: Option<f64>, cause: Option<Cause>) -> ScenarioRecord {
        ScenarioRecord {
            object,
            k,
            inputs: ScenarioInputs::default(),
            stays,
            cause,
            t_stab: None,
            max_displacement: disp,
            max_tilt_deg: None,
            rhs_evals: [0; 2],
            steps: [0; 2],
            abort: None,
        }
    }

    fn record(scenarios: Vec<ScenarioRecord>, meets: [Option<bool>; 2]) -> RobustRecord {
        let objects = meets.iter().map(|m| ObjectRecord { meets_p_min: *m, ..ObjectRecord::default() }).collect();
        RobustRecord { objects, scenarios, ..RobustRecord::default() }
    }

    /// The scenario drawn of a robust design, by hand: a feasible design's largest
    /// displacement (the first of two equal ones), the failing object's first failure (not an
    /// earlier failure of an object that meets p_min), the aborted scenario; none before the
    /// scenarios or without any.
    #[test]
    fn the_deciding_scenario_is_the_worst_the_first_failure_or_the_abort() {
        let moved = Some(Cause::ObjectMoved);
        let runs = vec![
            run(0, 0, true, Some(1e-4), None),
            run(1, 0, true, Some(3e-4), None),
            run(0, 1, false, Some(2e-3), moved),
            run(1, 1, false, Some(2e-3), moved),
            run(1, 2, false, None, Some(Cause::Fold)),
        ];
        let feasible = record(runs.clone(), [Some(true), Some(true)]);
        assert_eq!(feasible.deciding(None, None), Some((2, Decides::WorstDisplacement)));
        let failing = record(runs.clone(), [Some(true), Some(false)]);
        assert_eq!(failing.deciding(Some(3), Some(Cause::PStay)), Some((3, Decides::FirstFailure)));
        let mut aborted = runs.clone();
        aborted[4].cause = Some(Cause::Aborted);
        let aborted = record(aborted, [Some(true), Some(false)]);
        assert_eq!(aborted.deciding(Some(3), Some(Cause::Aborted)), Some((4, Decides::Aborted)));
        let unmeasured = record(vec![run(1, 0, false, None, Some(Cause::Fold))], [None, None]);
        assert_eq!(unmeasured.deciding(None, None), Some((0, Decides::FirstScenario)));
        assert_eq!(feasible.deciding(Some(2), None), None);
        assert_eq!(record(vec![], [None, None]).deciding(None, None), None);
    }
}
