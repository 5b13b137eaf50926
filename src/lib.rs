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
//! archive and history rows, a design's recorded record and trajectory, replay). The face is
//! the application layer ([`app`]): its requests and results, and these re-exports of it.
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
//! → [`sweep`] (beside run) → [`bench`](mod@bench) (above run) → [`app`] (the application
//! layer, the face); the CLI and the Python binding sit on top.
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

// The application layer, on top: what a user asks of gripopt, as typed requests and results;
// the CLI and the Python binding use it and nothing else.
pub mod app;

/// The row walker the CSV writers use, for the Python package's DataFrame columns (not a
/// user's API).
#[doc(hidden)]
pub use cells::{walk_row, CellError, Leaf, RowSink};
// The face: the names a library user needs most, from the application layer.
pub use app::{
    evaluate, evaluate_batch, evaluate_rows, pose_values, random_designs, replay, sample_values, simulate,
    trajectory_columns, trajectory_row, Batch, Bounds, Cause, Column, Controls, Design, DesignMessage,
    DesignParameters, DesignRow, Error, EvaluatedRow, EvaluationRecord, Evaluations, Evaluator, EventNote,
    FingerSample, GenerationReport, GripperProblem, HistoryRow, Infeasibility, Integration, Method, Mode, Optimiser,
    Point, PoseSample, Problem, Progress, Record, RecordOptions, Recorded, Replay, Resolution, Result, RunFolder,
    RunInfo, RunSummary, Sample, SceneChoice, SceneKind, SimulateRequest, Simulation, SimulationRecord, Sink, Stages,
    Trajectory, TrajectoryKeep, DESIGN_COLUMNS, DESIGN_NAMES, FINGER2_COLUMNS, HISTORY_COLUMNS, POSE_COLUMNS,
    SAMPLE_COLUMNS,
};
pub use fsutil::{
    check_new_file, check_output_file, run_folder_around, run_folder_file, set_aside, write_atomic, AtomicFile,
    SET_ASIDE_DIR,
};
