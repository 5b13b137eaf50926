//! gripopt: design optimisation of underactuated two-finger grippers for high-speed
//! grasping, after the model contract `shared/spec/MODEL.md`.
//!
//! Layers, each importing only those before it: [`params`] (the problem file as typed
//! values) → [`model`] (finger geometry, kinematics, statics, closure) → [`sim`]
//! (integrators, events, the driver, scenes) → [`eval`] (the staged pipeline and its
//! record) → [`optim`] (pure NSGA-II) → [`record`] (MCAP) → [`run`] (run folders,
//! checkpoints, observers, the gripper problem) → [`bench`](mod@bench) (speed figures); the `gripopt`
//! binary's CLI sits on top. See docs/architecture.md.
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: a NaN must fail every physical check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Index loops mirror the formulas of MODEL.md (rows, contacts, objectives).
#![allow(clippy::needless_range_loop)]

// The layers, lowest first (docs/architecture.md). Each is a namespace whose own modules
// are private: what the CLI, tests and benches need is re-exported flat from the layer
// (`gripopt::sim::Radau5`, `gripopt::model::closed_pose`).
pub mod bench;
pub mod eval;
pub mod model;
pub mod optim;
pub mod params;
pub mod record;
pub mod run;
pub mod sim;
pub mod sweep;

// Shared below every layer.
mod cells;
mod error;
mod fsutil;
pub mod math;

pub use error::{Error, Result};
