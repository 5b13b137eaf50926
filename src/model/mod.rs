//! The finger model: geometry, kinematics, mass, statics, form closure, constraints,
//! dynamics and contact (MODEL.md §3–§8).

mod closure;
mod constraints;
mod contact;
mod dynamics;
mod geometry;
mod kinematics;
mod stage2;
mod statics;

pub use closure::{
    admissible, check_forces, closure_matrix, form_closure_test, grasp_at, max_offset, ClosureMatrix, FormClosure,
    Grasp, OffsetFailure, OffsetScan, N_UNILATERAL,
};
pub use constraints::{closing_angle, singularity_sweep, MarginAngle, Sweep, SweepFailure};
pub use contact::{adams_step, capsule, flores_normal, CapsuleGeom, CapsulePart, FrictionLaw};
pub use dynamics::{
    gravity_potential, gravity_tree, kinetic_energy_bodies, mass_matrix, reduce_tree_force, reduced, Reduced,
};
pub use geometry::{Finger, GeomError, MassProps, Pose};
pub use kinematics::Kin;
pub use stage2::{CentredGrasp, StaticsResult};
pub use statics::{
    birglen_residual, closed_pose, external_force, finger_forces, isotropy, spring_preload, spring_torque,
    tangent_angles, to_world, ClosedPose, ClosedPoseError, FingerForces,
};
