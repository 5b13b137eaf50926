//! Rigid statics with the object fixed (MODEL.md §6.1–6.5): closed pose on a cylinder,
//! spring preload, frictionless and friction-mobilised contact forces, hand force.

use super::dynamics::{gravity_tree, mass_matrix, reduce_tree_force};
use super::geometry::{Finger, GeomError, Pose};
use super::kinematics::Kin;
use crate::math::{angle, e, perp, V2};
use crate::params::SceneParams;
use nalgebra::{Matrix2, Vector2};
use std::f64::consts::PI;

/// Why a closed pose on a cylinder does not exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClosedPoseError {
    /// D ≤ R + w: the object overlaps the base joint.
    OverlapsBase,
    /// k1 < 0 or k1 > l21: no line contact on the proximal phalanx.
    ProximalOutOfRange,
    /// k2 > t22: the distal phalanx would touch with its tip.
    DistalBeyondTip,
    /// The distal tip cannot reach the object (singularity sweep, §7).
    DistalCannotReach,
    /// The leg-1 inverse model fails.
    Geometry(GeomError),
    /// Singular kinematics at the pose.
    Singular,
}

impl ClosedPoseError {
    /// Human-readable reason.
    pub fn reason(self) -> &'static str {
        match self {
            ClosedPoseError::OverlapsBase => "object overlaps base joint",
            ClosedPoseError::ProximalOutOfRange => "proximal contact outside the phalanx (k1 not in [0, l21])",
            ClosedPoseError::DistalBeyondTip => "distal contact beyond the tip (k2 > t22)",
            ClosedPoseError::DistalCannotReach => "distal cannot reach the object",
            ClosedPoseError::Geometry(g) => g.reason(),
            ClosedPoseError::Singular => "singular kinematics at the closed pose",
        }
    }
}

/// Tangent construction of §6.1: (θ1, k1, k2, θ2) for an object of radius `r` centred at
/// local `(x_c, r)`; k2 is not checked against t22.
pub fn tangent_angles(f: &Finger, r: f64, x_c: f64) -> Result<(f64, f64, f64, f64), ClosedPoseError> {
    let c = V2::new(x_c, r);
    let v = c - f.o21;
    let d = v.norm();
    let rw = r + f.w;
    if !(d > rw) {
        return Err(ClosedPoseError::OverlapsBase);
    }
    let k1 = (d * d - rw * rw).sqrt();
    let th1 = angle(v) - (rw / d).asin();
    let k2 = f.l21 - k1;
    if !(k1 >= 0.0 && k1 <= f.l21) {
        return Err(ClosedPoseError::ProximalOutOfRange);
    }
    let th2 = PI - 2.0 * rw.atan2(k2);
    Ok((th1, k1, k2, th2))
}

/// A closed configuration with line contacts on both phalanges (§6.1).
#[derive(Debug, Clone, Copy)]
pub struct ClosedPose {
    /// θ1 = q21.
    pub theta1: f64,
    /// θ2 = q22 + ψ.
    pub theta2: f64,
    /// Contact abscissa on the proximal phalanx.
    pub k1: f64,
    /// Contact abscissa on the distal phalanx (from O22).
    pub k2: f64,
    /// Linkage pose.
    pub pose: Pose,
    /// Kinematics at the pose.
    pub kin: Kin,
    /// Phalanx directions x1, x2.
    pub x: [V2; 2],
    /// Contact normals n_i = perp(x_i) (phalanx → object).
    pub n: [V2; 2],
    /// Contact points on the rod surfaces.
    pub p: [V2; 2],
    /// Contact rows a_i (δ̇_i = a_i q̇_a).
    pub a: [Vector2<f64>; 2],
    /// Tangential rows b_i (rate along x_i).
    pub b: [Vector2<f64>; 2],
}

/// Closed pose of finger `f` on a cylinder of radius `r` at local centre x_c (§6.1).
pub fn closed_pose(f: &Finger, r: f64, x_c: f64) -> Result<ClosedPose, ClosedPoseError> {
    let (theta1, k1, k2, theta2) = tangent_angles(f, r, x_c)?;
    if k2 > f.t22 {
        return Err(ClosedPoseError::DistalBeyondTip);
    }
    let pose = f.ik(theta1, theta2).map_err(ClosedPoseError::Geometry)?;
    let kin = Kin::new(f, &pose).ok_or(ClosedPoseError::Singular)?;
    let x = [e(theta1), e(theta1 + theta2)];
    let n = [perp(x[0]), perp(x[1])];
    let p = [f.o21 + k1 * x[0] + f.w * n[0], pose.o22 + k2 * x[1] + f.w * n[1]];
    let mut a = [Vector2::zeros(); 2];
    let mut b = [Vector2::zeros(); 2];
    for i in 0..2 {
        let jp = kin.point_jacobian(f, &pose, p[i], i == 1);
        a[i] = jp.transpose() * n[i];
        b[i] = jp.transpose() * x[i];
    }
    Ok(ClosedPose { theta1, theta2, k1, k2, pose, kin, x, n, p, a, b })
}

/// Minimal spring preload (§6.2): returns (τ_s^min, τ_s0 = max(0, τ_s^min)).
pub fn spring_preload(f: &Finger, s: &SceneParams) -> Option<(f64, f64)> {
    let kin = Kin::new(f, &f.open)?;
    let m = mass_matrix(f, &f.open, &kin);
    let minv = m.try_inverse()?;
    let j = kin.j_row();
    let num = j.dot(&(minv * Vector2::new(1.0, 0.0)));
    let den = j.dot(&(minv * j));
    let tmin = s.hand.tau * num / den;
    tmin.is_finite().then_some((tmin, tmin.max(0.0)))
}

/// Spring torque τ_s(θ2) = τ_s0 + k_s θ2.
#[inline]
pub fn spring_torque(tau_s0: f64, s: &SceneParams, theta2: f64) -> f64 {
    tau_s0 + s.hand.k_s * theta2
}

/// External generalised force at a static pose: Q_ext = (τ, 0) − τ_s(θ2)(J21, J22) + Wᵀ Q_t^grav.
pub fn external_force(f: &Finger, s: &SceneParams, pose: &Pose, kin: &Kin, tau_s0: f64) -> Vector2<f64> {
    let th2 = pose.q22 + f.psi;
    Vector2::new(s.hand.tau, 0.0) - spring_torque(tau_s0, s, th2) * kin.j_row()
        + reduce_tree_force(kin, gravity_tree(f, pose, s))
}

/// Static contact forces of one finger (§6.4), local frame.
#[derive(Debug, Clone, Copy)]
pub struct FingerForces {
    /// Frictionless normal forces f⁰.
    pub f0: [f64; 2],
    /// Friction-mobilised normal forces f^μ.
    pub fmu: [f64; 2],
    /// Force on the object from this finger, frictionless (local frame).
    pub force0: V2,
    /// Force on the object from this finger, friction mobilised (local frame).
    pub force_mu: V2,
}

/// Solve the two static force sets at a closed pose.
pub fn finger_forces(f: &Finger, s: &SceneParams, cp: &ClosedPose, tau_s0: f64) -> Option<FingerForces> {
    let q = external_force(f, s, &cp.pose, &cp.kin, tau_s0);
    let a0 = Matrix2::from_columns(&[cp.a[0], cp.a[1]]);
    let f0 = a0.try_inverse()? * q;
    let amu = Matrix2::from_columns(&[cp.a[0] - s.contact.mu_s * cp.b[0], cp.a[1] - s.contact.mu_s * cp.b[1]]);
    let fmu = amu.try_inverse()? * q;
    let force0 = f0[0] * cp.n[0] + f0[1] * cp.n[1];
    let force_mu = fmu[0] * (cp.n[0] - s.contact.mu_s * cp.x[0]) + fmu[1] * (cp.n[1] - s.contact.mu_s * cp.x[1]);
    let ok = f0.iter().chain(fmu.iter()).all(|v| v.is_finite());
    ok.then_some(FingerForces { f0: [f0[0], f0[1]], fmu: [fmu[0], fmu[1]], force0, force_mu })
}

/// Local → world for finger `j` (0 = right finger, 1 = mirrored left finger).
#[inline]
pub fn to_world(v: V2, finger: usize) -> V2 {
    if finger == 0 {
        v
    } else {
        V2::new(-v.x, v.y)
    }
}

/// Birglen-form check of §6.4 (O11 = O21 only): J_nᵀ f⁰ in phalanx coordinates, returns
/// the vector that must equal (τ, τ/J21 − τ_s).
pub fn birglen_residual(f: &Finger, cp: &ClosedPose, forces: &FingerForces) -> Vector2<f64> {
    let jn = Matrix2::new(cp.k1, 0.0, cp.k2 + f.l21 * cp.theta2.cos(), cp.k2);
    jn.transpose() * Vector2::new(forces.f0[0], forces.f0[1])
}

/// Force isotropy α and mean force F̃ of eq. 3.12 from a force pair (f⁰ or f^μ, §6.5, D22).
pub fn isotropy(f0: [f64; 2]) -> (f64, f64) {
    let mean = 0.5 * (f0[0] + f0[1]);
    let alpha = ((mean - f0[0]).powi(2) + (mean - f0[1]).powi(2)) / (f0[0] * f0[1]);
    (alpha, mean)
}
