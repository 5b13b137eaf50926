//! Stage 3 when the problem's scene is `free` (MODEL.md §14, an extension of §10 documented
//! in docs/scenes.md): the thesis's impact (§9.1) and force (§9.3) criteria *predict*
//! whether the object moves; with a free object the pipeline *measures* it instead. So the
//! centred scene runs as always (t_stab is the objective; E_cyl/E_lim and the force margins
//! stay in the record as information) but its impact and force criteria discard nothing;
//! the free scene at the problem's x_off then discards the design iff the object does not
//! "barely move" (§14.4: moved, toppled or escaped). The finger's own criteria (fold,
//! stability, singular or aborted grasps) discard as in the centred scene.

use super::stages::{Discard, Reason, StaticsResult};
use crate::model::Finger;
use crate::params::SceneParams;
pub use crate::sim::FreeEnd;
use crate::sim::{simulate, Controls, DynOutcome, DynamicsResult, FreeResult, Integration, SceneSpec, Sink};
use std::fmt;

/// What the free scene measured in stage 3 (the §14.4 outputs; allocation-free).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeMeasure {
    /// Object offset x_off of the run (m).
    pub x_off: f64,
    /// Largest horizontal displacement of G (m).
    pub max_displacement: f64,
    /// Largest |Δx| of G (m).
    pub max_dx: f64,
    /// Largest |Δy| of G (m).
    pub max_dy: f64,
    /// Largest tilt (°).
    pub max_tilt_deg: f64,
    /// Horizontal displacement at the end (m).
    pub final_displacement: f64,
    /// Tilt at the end (°).
    pub final_tilt_deg: f64,
    /// Peak translational kinetic energy of the object during the first contact (J).
    pub peak_e_trans: f64,
    /// Peak rotational kinetic energy of the object during the first contact (J).
    pub peak_e_rot: f64,
    /// §14.4's verdict: max displacement > Δx_max or max tilt > θ_max.
    pub moved: bool,
    /// Tilt above 45° at some time.
    pub toppled: bool,
    /// No phalanx in contact at the end.
    pub escaped: bool,
    /// A loaded phalanx met the object's rim or a face.
    pub rim_contact: bool,
    /// How the run ended.
    pub end: FreeEnd,
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations (including event location).
    pub rhs_evals: u64,
    /// Wall seconds.
    pub cpu_s: f64,
}

impl FreeMeasure {
    /// From the free scene's result at offset `x_off`.
    pub fn from_result(r: &FreeResult, x_off: f64) -> Self {
        FreeMeasure {
            x_off,
            max_displacement: r.object_max_displacement,
            max_dx: r.object_max_dx,
            max_dy: r.object_max_dy,
            max_tilt_deg: r.object_max_tilt_deg,
            final_displacement: r.object_final_displacement,
            final_tilt_deg: r.object_final_tilt_deg,
            peak_e_trans: r.object_peak_e_trans,
            peak_e_rot: r.object_peak_e_rot,
            moved: r.moved,
            toppled: r.toppled,
            escaped: r.escaped,
            rim_contact: r.rim_contact,
            end: r.end,
            steps: r.stats.steps,
            rhs_evals: r.rhs_evals,
            cpu_s: r.cpu_s,
        }
    }

    /// The object "barely moves" (§14.4) and the run observed it to the end.
    pub fn barely_moves(&self) -> bool {
        self.end == FreeEnd::Observed && !(self.moved || self.toppled || self.escaped)
    }

    /// The discard this measurement gives, if any (stage 3; violation in stage units:
    /// max(displacement/Δx_max, tilt/θ_max) − 1, plus 1 when the object escaped; 1e3 when
    /// the run ended early, as for an aborted grasp).
    pub fn discard(&self, s: &SceneParams) -> Option<Discard> {
        if !self.end.observed() {
            return Some(Discard { stage: 3, reason: Reason::FreeSceneEnded(self.end), violation: 1e3 });
        }
        if self.barely_moves() {
            return None;
        }
        let c = &s.criteria;
        let m = ObjectMotion {
            displacement: self.max_displacement,
            tilt_deg: self.max_tilt_deg,
            dx_max: c.dx_max,
            theta_max_deg: c.theta_max.to_degrees(),
            toppled: self.toppled,
            escaped: self.escaped,
        };
        let ratio = (m.displacement / m.dx_max).max(m.tilt_deg / m.theta_max_deg) - 1.0;
        let v = ratio.max(0.0) + if m.escaped { 1.0 } else { 0.0 };
        Some(Discard { stage: 3, reason: Reason::ObjectMoved(m), violation: if v.is_finite() { v } else { 1e3 } })
    }
}

/// Why the free scene discarded a design: the object did not barely move (§14.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectMotion {
    /// Largest horizontal displacement of G (m).
    pub displacement: f64,
    /// Largest tilt (°).
    pub tilt_deg: f64,
    /// Δx_max (m).
    pub dx_max: f64,
    /// θ_max (°).
    pub theta_max_deg: f64,
    /// Tilt above 45°.
    pub toppled: bool,
    /// No phalanx in contact at t_obs.
    pub escaped: bool,
}

impl fmt::Display for ObjectMotion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "free scene: the object does not barely move (max displacement {:.3} mm, limit {:.3} mm; max tilt {:.3}°, limit {:.3}°)",
            self.displacement * 1e3,
            self.dx_max * 1e3,
            self.tilt_deg,
            self.theta_max_deg
        )?;
        if self.toppled {
            write!(f, "; toppled")?;
        }
        if self.escaped {
            write!(f, "; escaped: no phalanx holds it at t_obs")?;
        }
        Ok(())
    }
}

/// The discard the centred scene gives in a free-kind stage 3: only the finger's own
/// criteria (fold, stability, singular or aborted grasps); the impact and force criteria
/// are the measurement's to decide.
fn finger_discard(c: &DynamicsResult) -> Option<Discard> {
    use DynOutcome as D;
    let fail = match c.outcome {
        D::Stable | D::ImpactEnergy | D::ForceCriterion | D::StaticForceLimit | D::Fold | D::NoStability => {
            if c.fold_ok == Some(false) {
                D::Fold
            } else if c.t_stab.is_none() {
                D::NoStability
            } else {
                return None;
            }
        }
        other => other,
    };
    let v = DynamicsResult { outcome: fail, ..*c }.discard_violation().unwrap_or(1e3);
    Some(Discard { stage: 3, reason: Reason::Dynamics(fail), violation: v })
}

/// Stage 3 of a free-kind problem: the centred scene in diagnostic mode (to t_stab; the
/// trajectory into `traj`), then, unless the finger's own criteria discard the design, the
/// free scene at the problem's x_off. Returns the centred result, the measurement (None
/// when the free scene did not run) and the discard.
pub(crate) fn stage3_free<K: Sink + ?Sized>(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    integ: &Integration,
    sink: &mut K,
) -> (DynamicsResult, Option<FreeMeasure>, Option<Discard>) {
    let c = *simulate(f, s, st, &SceneSpec::Centred, integ, &Controls::DIAGNOSTIC, sink).grasp().expect("a grasp");
    if let Some(d) = finger_discard(&c) {
        return (c, None, Some(d));
    }
    let x_off = s.setup.x_off;
    let spec = SceneSpec::free(x_off);
    let r = *simulate(f, s, st, &spec, integ, &Controls::DIAGNOSTIC, &mut ()).free().expect("the free scene");
    let m = FreeMeasure::from_result(&r, x_off);
    (c, Some(m), m.discard(s))
}
