//! Evaluation (MODEL.md §10): a design through the staged pipeline — stage 0/1 kinematics
//! and singularities, stage 2 statics and form closure, stage 3 the simulation in the
//! problem's scene — with discards and violations; the one way to simulate a design in a
//! scene; and the one typed record of an evaluation. Above `sim`, below `optim`/`record`/`run`.
//!
//! Files: `stages` (stages 0–2, [`Evaluation`], [`Reason`], [`Cause`]) ← `stage3` (stage
//! 3, [`evaluate`], [`simulate`]); `study` ([`Study`]: what a problem asks of every design,
//! its objects and scenarios) ← `scenario` (a design's start on every object, one scenario's
//! stage 3) ← `fold` (the stopping rule, a design's scenarios folded into its [`Record`];
//! `chance`: the chance constraint's record); `record` ([`Record`]) ← `scene_record` (its
//! stage-3 parts), `record_robust` (the scenarios' sub-record), `objectives` ([`Objectives`],
//! as every output reports them).

mod binomial;
mod certify;
mod chance;
mod fold;
mod objectives;
mod record;
mod record_robust;
mod scenario;
mod scene_record;
mod stage3;
mod stages;
mod stop;
mod study;

pub use binomial::{binomial_cdf, clopper_pearson};
pub use certify::{CertificationRecord, CertifyPlan, CertifyRule, ObjectCertification, ObjectDecision};
pub use fold::Folded;
pub use objectives::{minimised, objective_names, Objective, Objectives, Sense, OBJECTIVES};
pub use record::{
    Derived, EvaluationRecord, KinematicsRecord, OffsetEnd, Record, SimulationRecord, StaticsRecord, Verdict,
};
pub use record_robust::{
    robust_summary, Decides, ObjectRecord, RobustRecord, ScenarioInputs, ScenarioRecord, SolverAbort,
};
pub use scenario::{DesignStart, StartDiscard};
pub use scene_record::{FreeSceneRecord, GraspRecord, ImpactRecord, OffsetSceneRecord, Phalanx, WorkRecord};
pub use stage3::{
    barely_moves, evaluate, evaluate_dynamics, evaluate_full, evaluate_into, simulate, stage3_ends_at_once,
};
pub use stages::{
    evaluate_kinematics, evaluate_statics, stage_kinematics, stage_statics, Cause, Discard, EvalOptions, Evaluation,
    KinematicsResult, ObjectMotion, Partial, Reason, StaticsResult, MISSING_POSE_VIOLATION,
};
pub use stop::{decided, Decided, StopRule};
pub use study::{Constraint, Study, StudyObject, StudyScenario};

/// The record of design `x` of problem `p` through `opts`' stages, on the problem's study
/// ([`Study::of`]: a robust problem's scenarios, or its one object in its scene).
pub fn evaluate_record(p: &crate::params::Problem, x: &crate::params::Design, opts: &EvalOptions) -> Record {
    Study::of(p, opts).evaluate(x, opts).record
}
