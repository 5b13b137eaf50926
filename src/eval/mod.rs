//! Evaluation (MODEL.md §10): a design through the staged pipeline — stage 0/1 kinematics
//! and singularities, stage 2 statics and form closure, stage 3 the grasp simulation —
//! with discards and violations, and the one flattening of an evaluation into its record.
//! Above `sim`, below `optim`/`record`/`run`.

mod free_stage;
mod record;
mod stages;

pub use free_stage::{FreeEnd, FreeMeasure, ObjectMotion};
pub use record::{DynamicsRecord, FreeRecord, Record};
pub use stages::{
    evaluate, evaluate_dynamics, evaluate_full, evaluate_into, evaluate_statics, stage3_ends_at_once, stage_kinematics,
    stage_statics, Discard, EvalOptions, Evaluation, KinematicsResult, Partial, PartialGrasp, Reason, StaticsResult,
    MISSING_POSE_VIOLATION,
};
