//! Stage-1 constraints: mountability and the serial/parallel singularity sweep (MODEL.md §7).

use super::geometry::{Finger, GeomError};
use super::statics::{tangent_angles, ClosedPoseError};
use crate::math::{angle, dist_to_singular, wrap, V2};
use crate::params::SceneParams;

/// Which linkage angle sets the margin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MarginAngle {
    /// Serial singularity of leg 1.
    Q12,
    /// Serial singularity of leg 2.
    Q22,
    /// Parallel singularity.
    Q13,
}

/// Result of a successful sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sweep {
    /// Smallest distance to a singularity over the sweep (rad).
    pub min_margin: f64,
    /// The angle attaining it.
    pub which: MarginAngle,
    /// θ2 at which it is attained (rad).
    pub at_theta2: f64,
    /// Largest θ2_c over R_sing (rad).
    pub theta2_max: f64,
}

/// Why the sweep failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SweepFailure {
    /// No closed pose on radius R.
    ClosedPose(f64, ClosedPoseError),
    /// The linkage cannot be posed at θ2.
    Pose(f64, GeomError),
    /// A margin is below the limit (the sweep result at the worst point).
    Margin(Sweep),
}

impl SweepFailure {
    /// Human-readable reason.
    pub fn reason(&self) -> String {
        match self {
            SweepFailure::ClosedPose(r, e) => format!("closed pose on R = {:.1} mm missing: {}", r * 1e3, e.reason()),
            SweepFailure::Pose(t, e) => format!("at theta2 = {:.2} deg: {}", t.to_degrees(), e.reason()),
            SweepFailure::Margin(s) => format!(
                "singularity margin {:.3} deg < limit ({:?} at theta2 = {:.2} deg)",
                s.min_margin.to_degrees(),
                s.which,
                s.at_theta2.to_degrees()
            ),
        }
    }
    /// Violation magnitude in degrees (§10: limit − margin, or 90° if a pose is missing).
    pub fn violation_deg(&self, limit: f64) -> f64 {
        match self {
            SweepFailure::Margin(s) => (limit - s.min_margin).to_degrees().max(0.0),
            _ => 90.0,
        }
    }
}

/// Closing angle θ2_c(R) of §7 item 2 (line contact, or tip sphere if k2 > t22).
pub fn closing_angle(f: &Finger, r: f64) -> Result<f64, ClosedPoseError> {
    let (th1, _k1, k2, th2) = tangent_angles(f, r, 0.0)?;
    if k2 <= f.t22 {
        return Ok(th2);
    }
    let o22 = f.o21 + f.l21 * crate::math::e(th1);
    let v = V2::new(0.0, r) - o22;
    let c = (f.t22 * f.t22 + k2 * k2) / (2.0 * f.t22 * v.norm());
    if c > 1.0 {
        return Err(ClosedPoseError::DistalCannotReach);
    }
    Ok(wrap(angle(v) - c.acos() - th1))
}

/// Run the singularity sweep of §7 on all radii of `s.r_sing`.
pub fn singularity_sweep(f: &Finger, s: &SceneParams) -> Result<Sweep, SweepFailure> {
    let mut th_max = 0.0f64;
    let mut closing = [0.0f64; 16];
    let nr = s.criteria.r_sing.len().min(16);
    for (i, &r) in s.criteria.r_sing.iter().take(16).enumerate() {
        closing[i] = closing_angle(f, r).map_err(|e| SweepFailure::ClosedPose(r, e))?;
        th_max = th_max.max(closing[i]);
    }
    let mut best = Sweep { min_margin: f64::INFINITY, which: MarginAngle::Q13, at_theta2: 0.0, theta2_max: th_max };
    let mut visit = |th2: f64| -> Result<(), SweepFailure> {
        let p = f.ik(f.open.q21, th2).map_err(|e| SweepFailure::Pose(th2, e))?;
        for (a, which) in [(p.q12, MarginAngle::Q12), (p.q22, MarginAngle::Q22), (p.q13, MarginAngle::Q13)] {
            let d = dist_to_singular(a);
            if d < best.min_margin {
                best.min_margin = d;
                best.which = which;
                best.at_theta2 = th2;
            }
        }
        Ok(())
    };
    visit(0.0)?;
    for &c in &closing[..nr] {
        visit(c)?;
    }
    let mut k = 1;
    while (k as f64) * s.criteria.sweep_step < th_max {
        visit(k as f64 * s.criteria.sweep_step)?;
        k += 1;
    }
    if best.min_margin < s.criteria.margin_sing {
        return Err(SweepFailure::Margin(best));
    }
    Ok(best)
}
