//! What stage 2 gives a design: its statics on the centred object, the values a grasp
//! simulation starts from (computed from `statics` and `closure`).

use super::closure::{Grasp, OffsetFailure};

/// Finger 1's grasp of the centred object (the values stage 2 reports, whether it then
/// passed the design or discarded it for a force that was not positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentredGrasp {
    /// θ1, θ2 of the closed pose.
    pub theta: [f64; 2],
    /// k1, k2.
    pub k: [f64; 2],
    /// f⁰ (finger 1).
    pub f0: [f64; 2],
    /// f^μ (finger 1).
    pub fmu: [f64; 2],
    /// F⁰_hand (world).
    pub hand0: [f64; 2],
    /// F^μ_hand (world).
    pub hand_mu: [f64; 2],
}

impl CentredGrasp {
    /// Finger 1's values of the grasp `g`.
    pub fn of(g: &Grasp) -> Self {
        let (cp, ff) = (&g.cp[0], &g.forces[0]);
        CentredGrasp {
            theta: [cp.theta1, cp.theta2],
            k: [cp.k1, cp.k2],
            f0: ff.f0,
            fmu: ff.fmu,
            hand0: [g.hand0.x, g.hand0.y],
            hand_mu: [g.hand_mu.x, g.hand_mu.y],
        }
    }
}

/// Stage-2 values of a design (centred object): the statics a grasp simulation starts from.
#[derive(Debug, Clone, Copy)]
pub struct StaticsResult {
    /// τ_s^min before clipping.
    pub tau_s_min: f64,
    /// Spring preload τ_s0.
    pub tau_s0: f64,
    /// Finger 1's centred grasp: closed pose, static forces, hand forces.
    pub grasp: CentredGrasp,
    /// Form closed at x_off = 0.
    pub form_closed_0: bool,
    /// Objective 1 (m).
    pub max_offset: f64,
    /// What ended the offset scan.
    pub offset_ended_by: Option<OffsetFailure>,
    /// Objective 2: α of the problem's force model (D22).
    pub alpha: f64,
    /// Objective 3 (N): F̃ of the problem's force model (D22).
    pub mean_force: f64,
    /// α from f^μ (always computed, §6.5).
    pub alpha_mu: f64,
    /// F̃ from f^μ (N).
    pub mean_force_mu: f64,
    /// α from f⁰.
    pub alpha_0: f64,
    /// F̃ from f⁰ (N).
    pub mean_force_0: f64,
    /// The force model that chose `alpha` and `mean_force`.
    pub force_model: crate::params::ForceModel,
}
