//! What stage 2 gives a design: its statics on the centred object, the values a grasp
//! simulation starts from (computed from `statics` and `closure`).

use super::closure::OffsetFailure;

/// Stage-2 values of a design (centred object): the statics a grasp simulation starts from.
#[derive(Debug, Clone, Copy)]
pub struct StaticsResult {
    /// τ_s^min before clipping.
    pub tau_s_min: f64,
    /// Spring preload τ_s0.
    pub tau_s0: f64,
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
