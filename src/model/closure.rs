//! First-order form closure (MODEL.md §6.6) and objective 1, the largest object offset
//! with an admissible grasp (§6.7).

use super::geometry::Finger;
use super::statics::{closed_pose, finger_forces, to_world, ClosedPose, ClosedPoseError, FingerForces};
use crate::math::V2;
use crate::params::SceneParams;
use nalgebra::{SMatrix, SVector};

/// Number of unilateral rows of M_c (4 contacts + palm); rows 5 and 6 are bilateral.
pub const N_UNILATERAL: usize = 5;

/// The 7×6 first-order closure matrix.
pub type ClosureMatrix = SMatrix<f64, 7, 6>;

/// Result of the kernel-sign form-closure test.
#[derive(Debug, Clone, Copy)]
pub struct FormClosure {
    /// Form closed.
    pub closed: bool,
    /// σ_6/σ_1 of M_c (rank indicator).
    pub rank_ratio: f64,
    /// Left-kernel vector, scaled so that the largest unilateral component is +1.
    pub y: SVector<f64, 7>,
}

/// Rows of M_c for a grasp with the two closed poses (finger 1 at `cp[0]`, finger 2 at `cp[1]`).
pub fn closure_matrix(f: &Finger, cp: &[ClosedPose; 2]) -> ClosureMatrix {
    let mut m = ClosureMatrix::zeros();
    for (j, c) in cp.iter().enumerate() {
        let jn = [[c.k1, 0.0], [c.k2 + f.l21 * c.theta2.cos(), c.k2]];
        for i in 0..2 {
            let row = 2 * j + i;
            let nw = to_world(c.n[i], j);
            m[(row, 0)] = nw.x;
            m[(row, 1)] = nw.y;
            m[(row, 2 + 2 * j)] = -jn[i][0];
            m[(row, 3 + 2 * j)] = -jn[i][1];
        }
        let (j21, j22) = (c.kin.j21(), c.kin.j22());
        m[(5 + j, 2 + 2 * j)] = -j22 / j21;
        m[(5 + j, 3 + 2 * j)] = 1.0 / j21;
    }
    m[(4, 1)] = 1.0;
    m
}

/// Kernel-sign test of §6.6 on a closure matrix whose first `N_UNILATERAL` rows are unilateral.
pub fn form_closure_test(mc: &ClosureMatrix) -> FormClosure {
    let mut a = SMatrix::<f64, 7, 7>::zeros();
    for r in 0..7 {
        let row = mc.row(r);
        let nrm = row.norm();
        let scale = if nrm > 0.0 { 1.0 / nrm } else { 0.0 };
        for c in 0..6 {
            a[(r, c)] = row[c] * scale;
        }
    }
    // Padding with a zero column: the singular values are those of M_c plus one zero, and the
    // left singular vector of the zero singular value spans the left kernel of M_c.
    let svd = a.svd(true, false);
    let sv = svd.singular_values;
    let u = svd.u.expect("u requested");
    let mut idx: [usize; 7] = [0, 1, 2, 3, 4, 5, 6];
    idx.sort_by(|&i, &j| sv[j].total_cmp(&sv[i]));
    let rank_ratio = if sv[idx[0]] > 0.0 { sv[idx[5]] / sv[idx[0]] } else { 0.0 };
    let mut y: SVector<f64, 7> = u.column(idx[6]).into_owned();
    let mut imax = 0;
    for k in 1..N_UNILATERAL {
        if y[k].abs() > y[imax].abs() {
            imax = k;
        }
    }
    if y[imax] != 0.0 {
        y /= y[imax];
        if y[imax] < 0.0 {
            y = -y;
        }
    }
    let closed = rank_ratio > 1e-9 && (0..N_UNILATERAL).all(|k| y[k] > 1e-9);
    FormClosure { closed, rank_ratio, y }
}

/// Why a grasp at an offset is not admissible (§6.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OffsetFailure {
    /// No closed pose for finger j (0 or 1).
    NoClosedPose(usize, ClosedPoseError),
    /// Singular static force system.
    SingularForces,
    /// A force of f⁰ or f^μ is ≤ 0; the value is the most negative force.
    ForceNotPositive(f64),
    /// F^μ_hand,y ≥ 0; the value is F^μ_hand,y.
    PalmForceNotPositive(f64),
    /// Not form closed.
    NotFormClosed,
}

impl OffsetFailure {
    /// Human-readable reason.
    pub fn reason(&self) -> String {
        match self {
            OffsetFailure::NoClosedPose(j, e) => format!("finger {}: {}", j + 1, e.reason()),
            OffsetFailure::SingularForces => "singular static force system".into(),
            OffsetFailure::ForceNotPositive(v) => format!("force positiveness violated (min force {v:.4} N)"),
            OffsetFailure::PalmForceNotPositive(v) => format!("palm force positiveness violated (F_y = {v:.4} N)"),
            OffsetFailure::NotFormClosed => "not form closed".into(),
        }
    }
}

/// A grasp of the centred or offset object by both fingers.
#[derive(Debug, Clone, Copy)]
pub struct Grasp {
    /// Offset of the object along x (world).
    pub x_off: f64,
    /// Closed poses of finger 1 and finger 2 (local frames).
    pub cp: [ClosedPose; 2],
    /// Static forces of both fingers.
    pub forces: [FingerForces; 2],
    /// F⁰_hand (world).
    pub hand0: V2,
    /// F^μ_hand (world).
    pub hand_mu: V2,
}

impl Grasp {
    /// Smallest of the eight normal forces f⁰ and f^μ.
    pub fn min_force(&self) -> f64 {
        self.forces.iter().flat_map(|f| f.f0.iter().chain(f.fmu.iter())).copied().fold(f64::INFINITY, f64::min)
    }
}

/// Closed poses and static forces of both fingers at world offset `x_off`.
pub fn grasp_at(f: &Finger, s: &SceneParams, tau_s0: f64, x_off: f64) -> Result<Grasp, OffsetFailure> {
    let cp0 = closed_pose(f, s.object.radius, x_off).map_err(|e| OffsetFailure::NoClosedPose(0, e))?;
    let cp1 = if x_off == 0.0 {
        cp0
    } else {
        closed_pose(f, s.object.radius, -x_off).map_err(|e| OffsetFailure::NoClosedPose(1, e))?
    };
    let f0 = finger_forces(f, s, &cp0, tau_s0).ok_or(OffsetFailure::SingularForces)?;
    let f1 = if x_off == 0.0 { f0 } else { finger_forces(f, s, &cp1, tau_s0).ok_or(OffsetFailure::SingularForces)? };
    let hand0 = to_world(f0.force0, 0) + to_world(f1.force0, 1);
    let hand_mu = to_world(f0.force_mu, 0) + to_world(f1.force_mu, 1);
    Ok(Grasp { x_off, cp: [cp0, cp1], forces: [f0, f1], hand0, hand_mu })
}

/// Check the force conditions of an admissible grasp (positiveness, palm force).
pub fn check_forces(g: &Grasp) -> Result<(), OffsetFailure> {
    let fmin = g.min_force();
    if !(fmin > 0.0) {
        return Err(OffsetFailure::ForceNotPositive(fmin));
    }
    if !(g.hand_mu.y < 0.0) {
        return Err(OffsetFailure::PalmForceNotPositive(g.hand_mu.y));
    }
    Ok(())
}

/// Full admissibility test at one offset (§6.7).
pub fn admissible(f: &Finger, s: &SceneParams, tau_s0: f64, x_off: f64) -> Result<Grasp, OffsetFailure> {
    let g = grasp_at(f, s, tau_s0, x_off)?;
    check_forces(&g)?;
    if !form_closure_test(&closure_matrix(f, &g.cp)).closed {
        return Err(OffsetFailure::NotFormClosed);
    }
    Ok(g)
}

/// Result of the offset scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetScan {
    /// max_offset (m); −Δ_off if x_off = 0 is not form closed.
    pub max_offset: f64,
    /// What ended the scan at the next offset (`None` when off_max was reached).
    pub ended_by: Option<OffsetFailure>,
}

/// Objective 1 (§6.7): scan x_off = kΔ_off for k = 0..=off_max/Δ_off.
pub fn max_offset(f: &Finger, s: &SceneParams, tau_s0: f64) -> OffsetScan {
    let n = (s.criteria.offset_max / s.criteria.offset_step + 1e-9).floor() as usize;
    let mut last = None;
    for k in 0..=n {
        let x = k as f64 * s.criteria.offset_step;
        match admissible(f, s, tau_s0, x) {
            Ok(_) => last = Some(x),
            Err(e) => {
                let max_offset = last.unwrap_or(-s.criteria.offset_step);
                return OffsetScan { max_offset, ended_by: Some(e) };
            }
        }
    }
    OffsetScan { max_offset: last.unwrap_or(-s.criteria.offset_step), ended_by: None }
}
