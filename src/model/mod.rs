//! The finger model: geometry, kinematics, mass, statics, form closure, constraints,
//! dynamics and contact (MODEL.md §3–§8).

pub mod closure;
pub mod constraints;
pub mod contact;
pub mod dynamics;
pub mod geometry;
pub mod kinematics;
pub mod statics;

pub use geometry::{Finger, GeomError, Pose};
pub use kinematics::Kin;
