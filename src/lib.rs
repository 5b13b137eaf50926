//! gripopt: design optimisation of underactuated two-finger grippers for high-speed
//! grasping, after the model contract `shared/spec/MODEL.md`.
//!
//! # Using the library
//!
//! The crate root is the library's face: load a [`Problem`]
//! (a file, or TOML text with [`Problem::from_toml_str`]; its `bounds` and `nominal`),
//! [`evaluate`] a design or [`evaluate_batch`] many into typed [`Record`]s, [`simulate`] a
//! design in a scene with its trajectory, run or resume an optimisation with the
//! [`Optimiser`] builder (a [`Progress`] callback, a stop flag, another batch
//! [`Evaluator`]), and read a run folder back with [`RunFolder`] (its front, population,
//! archive and history rows, a design's recorded record and trajectory, replay).
//!
//! ```no_run
//! let p = gripopt::Problem::load("problems/bottle-1l.toml")?;
//! let r = gripopt::evaluate(&p, &p.nominal, gripopt::Stages::All);
//! println!("{:?} {:?}", r.verdict.feasible, r.grasp.t_stab);
//! let s = gripopt::Optimiser::new("problems/bottle-1l.toml", "results/run").pop(24).generations(6).run()?;
//! let front = gripopt::RunFolder::open(&s.out)?.front()?;
//! # Ok::<(), gripopt::Error>(())
//! ```
//!
//! # Internals
//!
//! The layers below are public for the `gripopt` binary, the integration tests and the
//! benchmarks only, hidden from the documentation and without a stability promise
//! (docs/architecture.md): [`params`] (the problem file as typed values) → [`model`]
//! (finger geometry, kinematics, statics, closure) → [`sim`] (integrators, events, the
//! driver, scenes) → [`eval`] (the staged pipeline and its record) → [`optim`] (pure
//! NSGA-II) → [`record`] (MCAP) → [`run`] (run folders, checkpoints, the gripper problem)
//! → [`sweep`] (beside run) → [`bench`](mod@bench) (above run); the CLI sits on top.
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: a NaN must fail every physical check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Index loops mirror the formulas of MODEL.md (rows, contacts, objectives).
#![allow(clippy::needless_range_loop)]

// The layers, lowest first (docs/architecture.md): internals, each a namespace whose own
// modules are private; what the CLI, tests and benches need is re-exported flat from the
// layer (`gripopt::sim::Radau5`, `gripopt::model::closed_pose`).
#[doc(hidden)]
pub mod bench;
#[doc(hidden)]
pub mod eval;
#[doc(hidden)]
pub mod export;
#[doc(hidden)]
pub mod model;
#[doc(hidden)]
pub mod optim;
#[doc(hidden)]
pub mod params;
#[doc(hidden)]
pub mod record;
#[doc(hidden)]
pub mod run;
#[doc(hidden)]
pub mod sim;
#[doc(hidden)]
pub mod sweep;

// Shared below every layer.
mod cells;
mod error;
mod fsutil;
#[doc(hidden)]
pub mod math;

// The face: the few names a library user needs.
mod facade;

/// The row walker the CSV writers use, for the Python package's DataFrame columns (not a
/// user's API).
#[doc(hidden)]
pub use cells::{walk_row, CellError, Leaf, RowSink};
pub use error::{Error, Result};
pub use eval::{Cause, EvaluationRecord, Record, SimulationRecord};
pub use facade::{
    evaluate, evaluate_batch, evaluate_rows, parse_scene, pose_values, random_designs, sample_values, simulate,
    trajectory_columns, trajectory_row, EvaluatedRow, Optimiser, Simulation, Stages, FINGER2_COLUMNS, POSE_COLUMNS,
    SAMPLE_COLUMNS,
};
pub use fsutil::{
    check_new_file, check_output_file, run_folder_around, run_folder_file, set_aside, write_atomic, AtomicFile,
    SET_ASIDE_DIR,
};
pub use optim::{Batch, Evaluations, Evaluator, Infeasibility};
pub use params::{Bounds, Design, DesignParameters, Problem, SceneKind, DESIGN_NAMES};
pub use record::{DesignMessage, RecordOptions, Recorded, Replay, Resolution, TrajectoryKeep};
pub use run::{
    Column, DesignRow, GenerationReport, GripperProblem, HistoryRow, Progress, RunFolder, RunInfo, RunSummary,
    DESIGN_COLUMNS, HISTORY_COLUMNS,
};
pub use sim::{
    Controls, EventNote, FingerSample, Integration, Method, Mode, Point, PoseSample, Sample, Sink, Trajectory,
};
