//! The finger model: geometry, kinematics, mass, statics, form closure, constraints,
//! dynamics and contact (MODEL.md §3–§8).

mod closure;
mod constraints;
mod contact;
mod dynamics;
mod geometry;
mod kinematics;
mod statics;

pub use closure::{ClosureMatrix, FormClosure, Grasp, N_UNILATERAL, OffsetFailure, OffsetScan, admissible, check_forces, closure_matrix, form_closure_test, grasp_at, max_offset};
pub use constraints::{MarginAngle, Sweep, SweepFailure, closing_angle, singularity_sweep};
pub use contact::{CapsuleGeom, CapsulePart, FrictionLaw, adams_step, capsule, flores_normal};
pub use dynamics::{Reduced, gravity_potential, gravity_tree, kinetic_energy_bodies, mass_matrix, reduce_tree_force, reduced};
pub use geometry::{Finger, GeomError, MassProps, Pose};
pub use kinematics::Kin;
pub use statics::{ClosedPose, ClosedPoseError, FingerForces, StaticsResult, birglen_residual, closed_pose, external_force, finger_forces, isotropy, spring_preload, spring_torque, tangent_angles, to_world};
