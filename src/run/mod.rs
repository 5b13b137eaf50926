//! Optimisation runs: the gripper design problem as a [`crate::optim::MooProblem`]
//! ([`gripper`]), run folders with exact resume ([`rundir`]), checkpoint files
//! ([`checkpoint`]), the argmin observers that report progress, write checkpoints and
//! record designs ([`observers`]), the result CSVs ([`outputs`]) and plots ([`plots`]).
//!
//! This layer sits on top: it uses the pure optimiser ([`crate::optim`]) and the recorder
//! ([`crate::record`]); neither of them names it.

pub mod checkpoint;
pub mod gripper;
pub mod observers;
pub mod outputs;
pub mod plots;
pub mod rundir;

pub use rundir::{optimise, resume, RunInfo, RunSpec, RunStatus, RunSummary};
