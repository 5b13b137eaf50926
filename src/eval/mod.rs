//! Evaluation (MODEL.md §10): a design through the staged pipeline — stage 0/1 kinematics
//! and singularities, stage 2 statics and form closure, stage 3 the simulation in the
//! problem's scene — with discards and violations; the one way to simulate a design in a
//! scene; and the one typed record of an evaluation. Above `sim`, below `optim`/`record`/`run`.
//!
//! Files: `stages` (stages 0–2, [`Evaluation`], [`Reason`], [`Cause`]) ← `stage3` (stage
//! 3, [`evaluate`], [`simulate`]); `record` ([`Record`]) ← `scene_record` (its stage-3
//! parts), `objectives` ([`Objectives`], as every output reports them).

mod binomial;
mod objectives;
mod record;
mod record_robust;
mod robust;
mod robust_result;
mod scene_record;
mod stage3;
mod stages;

pub use binomial::{binomial_cdf, clopper_pearson};
pub use objectives::Objectives;
pub use record::{
    Derived, EvaluationRecord, KinematicsRecord, OffsetEnd, Record, SimulationRecord, StaticsRecord, Verdict,
};
pub use record_robust::{robust_summary, ObjectRecord, RobustRecord, ScenarioInputs, ScenarioRecord, SolverAbort};
pub use robust::{
    decided, evaluate_sequential, fold, needed_bound, run_scenario, simulate_object, start as robust_start, Decided,
    RobustSetup, RobustStart, StopRule,
};
pub use robust_result::{evaluate_record, robust_record, robust_record_ranked};
pub use scene_record::{FreeSceneRecord, GraspRecord, ImpactRecord, OffsetSceneRecord, Phalanx, WorkRecord};
pub use stage3::{
    barely_moves, evaluate, evaluate_dynamics, evaluate_full, evaluate_into, simulate, stage3_ends_at_once,
};
pub use stages::{
    evaluate_kinematics, evaluate_statics, stage_kinematics, stage_statics, Cause, Discard, EvalOptions, Evaluation,
    KinematicsResult, ObjectMotion, Partial, Reason, StaticsResult, MISSING_POSE_VIOLATION,
};
