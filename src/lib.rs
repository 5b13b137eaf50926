//! gripopt: design optimisation of underactuated two-finger grippers for high-speed
//! grasping, after the model contract `shared/spec/MODEL.md`.
//!
//! Layers: [`problem`] (scene, design, bounds) → [`model`] (finger physics) →
//! [`pipeline`] (staged evaluation).
#![warn(missing_docs)]

pub mod math;
pub mod model;
pub mod optim;
pub mod pipeline;
pub mod problem;
pub mod record;
pub mod sim;
