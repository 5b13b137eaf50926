//! gripopt: design optimisation of underactuated two-finger grippers for high-speed
//! grasping, after the model contract `shared/spec/MODEL.md`.
//!
//! Layers: [`problem`] (scene, design, bounds) → [`model`] (finger physics) →
//! [`pipeline`] (staged evaluation).
#![warn(missing_docs)]
// `!(x > 0.0)` is deliberate throughout: a NaN must fail every physical check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Index loops mirror the formulas of MODEL.md (rows, contacts, objectives).
#![allow(clippy::needless_range_loop)]

pub mod error;
pub mod math;
pub mod model;
pub mod optim;
pub mod pipeline;
pub mod params;
pub mod record;
pub mod sim;
pub mod sweep;
