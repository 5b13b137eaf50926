//! Stages 0–2 of MODEL.md §10 and what an evaluation is: each stage returns its values or
//! a [`Discard`] with the stage, a typed [`Reason`] and a non-negative violation (0 =
//! satisfied), so an optimiser can rank infeasible designs. No heap allocation per
//! evaluation. Stage 3 (a scene's simulation) is `stage3`.

use crate::model::isotropy;
use crate::model::spring_preload;
use crate::model::{closure_matrix, form_closure_test, grasp_at, max_offset, OffsetFailure};
use crate::model::{singularity_sweep, Sweep, SweepFailure};
pub use crate::model::{CentredGrasp, StaticsResult};
use crate::model::{Finger, GeomError};
use crate::params::{Design, Problem, SceneKind, SceneParams};
use crate::sim::{Controls, DynOutcome, DynamicsResult, FreeEnd, FreeResult, Integration, OffsetResult};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Why a design was discarded (allocation-free; `Display` gives the text).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reason {
    /// Stage 0: a length ≤ 0 or NaN.
    InvalidDesign,
    /// Stage 1: the finger cannot be built (open pose, mountability).
    Geometry(GeomError),
    /// Stage 1: the singularity sweep failed.
    Sweep(SweepFailure),
    /// Stage 2: the spring preload cannot be computed (singular open pose).
    SpringUndefined,
    /// Stage 2: the grasp of the centred object is not admissible (other than form closure).
    Grasp(OffsetFailure),
    /// Stage 3: a dynamic criterion or the simulation itself failed.
    Dynamics(DynOutcome),
    /// Stage 3 of an offset-kind problem: no static grasp of the object at x_off (m), so
    /// the scene could not start (why).
    OffsetGrasp(f64, OffsetFailure),
    /// Stage 3 of a free-kind problem: the free object did not barely move (§14.4).
    ObjectMoved(ObjectMotion),
    /// Stage 3 of a free-kind problem: the free scene ended before t_obs (why).
    FreeSceneEnded(FreeEnd),
}

/// What discarded a design, as a short snake_case word (the record's `cause`, a sweep's
/// verdict class).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// A length ≤ 0 or NaN.
    Invalid,
    /// No open pose.
    NoOpenPose,
    /// The assembly mode changes (open pose or closing).
    ModeChange,
    /// The linkage cannot be mounted.
    NotMountable,
    /// No closed pose in the singularity sweep.
    NoClosedPose,
    /// Singular at the open pose.
    SingularOpen,
    /// Singular while closing.
    SingularClosing,
    /// Spring preload undefined.
    Spring,
    /// No closed pose of the centred grasp.
    NoGraspPose,
    /// Singular static force system.
    SingularForces,
    /// A contact force not positive.
    ForcePositiveness,
    /// The palm force not positive.
    PalmForce,
    /// Not form closed.
    NoFormClosure,
    /// Impact criterion.
    Impact,
    /// Distal fold at the first contact.
    Fold,
    /// Filtered force criterion.
    Force,
    /// Static force criterion.
    StaticForce,
    /// No stability by t_max.
    NoStability,
    /// Singular or not mountable during the grasp.
    SingularDynamic,
    /// The simulation was aborted (events, step budget, step size).
    Aborted,
    /// The open finger penetrates the object at t = 0 (offset or free scene).
    InitialPenetration,
    /// No compliant equilibrium.
    NoEquilibrium,
    /// The free object did not barely move.
    ObjectMoved,
    /// The free scene ended before t_obs.
    FreeSceneAborted,
    /// A robust design: the object barely moves in too few scenarios (P(stay) < p_min).
    PStay,
    /// Offset scene: no static grasp of the object at its offset.
    NoOffsetGrasp,
}

impl Cause {
    /// The snake_case word.
    pub fn as_str(self) -> &'static str {
        CAUSE_WORDS[self as usize]
    }
}

/// [`Cause`]'s words in variant order (checked against serde's by a test).
const CAUSE_WORDS: [&str; 26] = [
    "invalid",
    "no_open_pose",
    "mode_change",
    "not_mountable",
    "no_closed_pose",
    "singular_open",
    "singular_closing",
    "spring",
    "no_grasp_pose",
    "singular_forces",
    "force_positiveness",
    "palm_force",
    "no_form_closure",
    "impact",
    "fold",
    "force",
    "static_force",
    "no_stability",
    "singular_dynamic",
    "aborted",
    "initial_penetration",
    "no_equilibrium",
    "object_moved",
    "free_scene_aborted",
    "p_stay",
    "no_offset_grasp",
];

impl Reason {
    /// The class of this reason; `None` for a stable grasp (not a discard).
    pub fn cause(&self) -> Option<Cause> {
        use crate::model::GeomError as G;
        use crate::model::OffsetFailure as O;
        use crate::model::SweepFailure as S;
        use DynOutcome as D;
        Some(match self {
            Reason::InvalidDesign => Cause::Invalid,
            Reason::Geometry(G::NoOpenPose) => Cause::NoOpenPose,
            Reason::Geometry(G::AssemblyModeChange) | Reason::Sweep(S::Pose(_, G::AssemblyModeChange)) => {
                Cause::ModeChange
            }
            Reason::Geometry(_) | Reason::Sweep(S::Pose(..)) => Cause::NotMountable,
            Reason::Sweep(S::ClosedPose(..)) => Cause::NoClosedPose,
            Reason::Sweep(S::Margin(s)) if s.at_theta2 == 0.0 => Cause::SingularOpen,
            Reason::Sweep(S::Margin(_)) => Cause::SingularClosing,
            Reason::SpringUndefined => Cause::Spring,
            Reason::Grasp(O::NoClosedPose(..)) => Cause::NoGraspPose,
            Reason::Grasp(O::SingularForces) => Cause::SingularForces,
            Reason::Grasp(O::ForceNotPositive(_)) => Cause::ForcePositiveness,
            Reason::Grasp(O::PalmForceNotPositive(_)) => Cause::PalmForce,
            Reason::Grasp(O::NotFormClosed) => Cause::NoFormClosure,
            Reason::Dynamics(o) => match o {
                D::Stable => return None,
                D::ImpactEnergy => Cause::Impact,
                D::Fold => Cause::Fold,
                D::ForceCriterion => Cause::Force,
                D::StaticForceLimit => Cause::StaticForce,
                D::NoStability => Cause::NoStability,
                D::Singular | D::DgmFailure => Cause::SingularDynamic,
                D::Aborted | D::StepBudget | D::StepTooSmall => Cause::Aborted,
                D::InitialPenetration => Cause::InitialPenetration,
                D::NoEquilibrium => Cause::NoEquilibrium,
                D::NoOffsetGrasp => Cause::NoOffsetGrasp,
            },
            Reason::OffsetGrasp(..) => Cause::NoOffsetGrasp,
            Reason::ObjectMoved(_) => Cause::ObjectMoved,
            // the open finger in the object at t = 0 is geometry, not a solver failure: the
            // hand cannot be placed around the object there (as in the offset scene)
            Reason::FreeSceneEnded(FreeEnd::InitialPenetration) => Cause::InitialPenetration,
            Reason::FreeSceneEnded(_) => Cause::FreeSceneAborted,
        })
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
    /// No finger touched the object by t_obs (t_obs shorter than the fingers' approach).
    pub untouched: bool,
}

impl fmt::Display for ObjectMotion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.untouched {
            return write!(
                f,
                "free scene: no finger reached the object by t_obs, so nothing held it (scene.t_obs is shorter than the fingers' approach)"
            );
        }
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

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::InvalidDesign => write!(f, "invalid design: a length is not positive or a value is not finite"),
            Reason::Geometry(g) => write!(f, "{}", g.reason()),
            Reason::Sweep(s) => write!(f, "{}", s.reason()),
            Reason::SpringUndefined => write!(f, "spring preload undefined (singular open pose)"),
            Reason::Grasp(g) => write!(f, "{}", g.reason()),
            Reason::Dynamics(d) => write!(f, "{d}"),
            Reason::OffsetGrasp(x_off, why) => {
                write!(f, "{} (x_off = {:.3} mm): {}", DynOutcome::NoOffsetGrasp, x_off * 1e3, why.reason())
            }
            Reason::ObjectMoved(m) => write!(f, "{m}"),
            Reason::FreeSceneEnded(why) => write!(f, "free scene: {why}"),
        }
    }
}

/// A discarded design: the stage that discarded it, why, and by how much.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Discard {
    /// Failing stage, 0..=3.
    pub stage: u8,
    /// Why.
    pub reason: Reason,
    /// Non-negative violation magnitude (§10 units; larger = worse).
    pub violation: f64,
}

/// Violation given to a stage-2 design whose centred grasp has no closed pose
/// (§10 gives no formula; larger than any force-based violation seen in practice).
pub const MISSING_POSE_VIOLATION: f64 = 1e3;

/// Stage 1 values.
#[derive(Debug, Clone, Copy)]
pub struct KinematicsResult {
    /// The finger (derived lengths, open pose, masses).
    pub finger: Finger,
    /// Singularity sweep.
    pub sweep: Sweep,
}

/// Everything known about one evaluated design.
#[derive(Debug, Clone, Copy)]
pub struct Evaluation {
    /// The design.
    pub design: Design,
    /// Stage 1 values, if stage 1 ran to its end.
    pub kin: Option<KinematicsResult>,
    /// Stage 2 values, if stage 2 passed.
    pub statics: Option<StaticsResult>,
    /// Stage 3's grasp, if it ran (also when it discarded the design): the problem's
    /// scene's (centred or offset); for a free-kind problem the centred scene's (in
    /// diagnostic mode), the prediction.
    pub dynamics: Option<DynamicsResult>,
    /// The offset scene's hand forces, when stage 3 ran in it (its `dynamics` are
    /// [`Evaluation::dynamics`]).
    pub offset: Option<OffsetResult>,
    /// For a free-kind problem: the free scene's measurement, if it ran (MODEL.md §14.4).
    pub free: Option<FreeResult>,
    /// The scene stage 3 ran in (None: it did not run).
    pub scene: Option<SceneKind>,
    /// The object offset of that scene (m; 0 in the centred scene).
    pub x_off: f64,
    /// `None` = feasible.
    pub discard: Option<Discard>,
    /// Values a discarding stage computed before it discarded the design (MODEL.md §10:
    /// every value computed before a discard is reported).
    pub partial: Partial,
    /// Wall time per stage (s): 0–1 together in index 1, then 2, 3.
    pub stage_seconds: [f64; 4],
}

/// What a stage computed before it discarded the design.
#[derive(Debug, Clone, Copy, Default)]
pub struct Partial {
    /// The finger (open pose, l12, Γ, σ, masses) when stage 1's singularity sweep discarded it.
    pub finger: Option<Finger>,
    /// τ_s^min and τ_s0, when stage 2 discarded the design after computing them.
    pub spring: Option<[f64; 2]>,
    /// The centred grasp (closed pose θ, k; f⁰, f^μ; F⁰_hand, F^μ_hand) when stage 2's force
    /// positiveness discarded it.
    pub grasp: Option<CentredGrasp>,
}

impl Evaluation {
    /// A design not evaluated yet.
    pub fn new(design: Design) -> Self {
        Evaluation {
            design,
            kin: None,
            statics: None,
            dynamics: None,
            offset: None,
            free: None,
            scene: None,
            x_off: 0.0,
            discard: None,
            partial: Partial::default(),
            stage_seconds: [0.0; 4],
        }
    }
    /// True when no stage discarded the design.
    pub fn feasible(&self) -> bool {
        self.discard.is_none()
    }
    /// Objectives in their natural sense as the optimiser ranks them (max_offset, α, F̃,
    /// t_stab; max_offset −Δ_off where not form closed, MODEL.md §6.7); None where not
    /// computed, t_stab only for a design no stage discarded.
    pub fn natural_objectives(&self) -> [Option<f64>; 4] {
        let s = self.statics.as_ref();
        let t = match (&self.dynamics, &self.discard) {
            (Some(d), None) => d.t_stab,
            _ => None,
        };
        [s.map(|s| s.max_offset), s.map(|s| s.alpha), s.map(|s| s.mean_force), t]
    }
    /// Objectives in minimisation form (−max_offset, α, −F̃, t_stab); NaN where not computed.
    pub fn objectives(&self) -> [f64; 4] {
        let o = self.natural_objectives();
        std::array::from_fn(|k| o[k].map_or(f64::NAN, |v| super::objectives::OBJECTIVES[k].sense.sign() * v))
    }
}

/// What to run.
#[derive(Debug, Clone, Copy)]
pub struct EvalOptions {
    /// Run stage 3 (dynamics). Off gives the static pipeline (stages 0–2).
    pub dynamics: bool,
    /// The numerics of stage 3.
    pub integration: Integration,
    /// The run controls of stage 3 (pipeline mode).
    pub controls: Controls,
    /// In the free kind, measure the free scene even when the finger's own criteria discard
    /// the design (a diagnostic simulation, `verify`); false in the pipeline, which stops at
    /// the first failing criterion.
    pub measure_always: bool,
}

impl EvalOptions {
    /// Stages 0–2 only.
    pub fn statics_only() -> Self {
        EvalOptions {
            dynamics: false,
            integration: Integration::new(1e-6, 1e-9, 200_000),
            controls: Controls::PIPELINE,
            measure_always: false,
        }
    }
    /// All four stages with the problem's solver settings, stopping at the first violated criterion.
    pub fn full(p: &Problem) -> Self {
        Self::pipeline(Integration::from_solver(&p.solver))
    }
    /// All four stages with the numerics `integration`, stopping at the first violated criterion.
    pub fn pipeline(integration: Integration) -> Self {
        EvalOptions { dynamics: true, integration, controls: Controls::PIPELINE, measure_always: false }
    }
    /// A diagnostic simulation with the problem's solver settings: every criterion run to
    /// its end, the free scene measured whatever the finger's criteria say (`gripopt
    /// simulate`, `verify`).
    pub fn diagnostic(p: &Problem) -> Self {
        let integration = Integration::from_solver(&p.solver);
        EvalOptions { dynamics: true, integration, controls: Controls::DIAGNOSTIC, measure_always: true }
    }
}

/// Stages 0 and 1: validity, open pose, mass, singularity sweep.
pub fn stage_kinematics(x: &Design, s: &SceneParams) -> Result<KinematicsResult, Discard> {
    kinematics_partial(x, s).map_err(|(d, _)| d)
}

/// Stage 2: spring, centred grasp, force constraints, α, F̃, form closure, max_offset.
pub fn stage_statics(f: &Finger, s: &SceneParams) -> Result<StaticsResult, Discard> {
    statics_partial(f, s).map_err(|(d, _)| d)
}

/// Stages 0 and 1, with the finger when the sweep discarded it.
// The large error carries the partial values by value: an evaluation allocates nothing.
#[allow(clippy::result_large_err)]
pub(crate) fn kinematics_partial(x: &Design, s: &SceneParams) -> Result<KinematicsResult, (Discard, Partial)> {
    let finger = Finger::new(x, s).map_err(|g| match g {
        GeomError::InvalidLength => Discard { stage: 0, reason: Reason::InvalidDesign, violation: 1.0 },
        other => Discard { stage: 1, reason: Reason::Geometry(other), violation: 90.0 },
    });
    let finger = finger.map_err(|d| (d, Partial::default()))?;
    let sweep = singularity_sweep(&finger, s).map_err(|e| {
        let d = Discard { stage: 1, reason: Reason::Sweep(e), violation: e.violation_deg(s.criteria.margin_sing) };
        (d, Partial { finger: Some(finger), ..Partial::default() })
    })?;
    Ok(KinematicsResult { finger, sweep })
}

/// Stage 2, with what was computed before a discard.
#[allow(clippy::result_large_err)]
fn statics_partial(f: &Finger, s: &SceneParams) -> Result<StaticsResult, (Discard, Partial)> {
    let d2 = |reason, violation| Discard { stage: 2, reason, violation };
    let (tau_s_min, tau_s0) =
        spring_preload(f, s).ok_or((d2(Reason::SpringUndefined, MISSING_POSE_VIOLATION), Partial::default()))?;
    statics_with_spring(f, s, tau_s_min, tau_s0)
}

/// Stage 2 with the spring preload given (τ_s^min, τ_s0): a robust problem sizes the spring
/// once, at the hand's torque, and grips each object with its own torque.
#[allow(clippy::result_large_err)]
pub(crate) fn statics_with_spring(
    f: &Finger,
    s: &SceneParams,
    tau_s_min: f64,
    tau_s0: f64,
) -> Result<StaticsResult, (Discard, Partial)> {
    let d2 = |reason, violation| Discard { stage: 2, reason, violation };
    let spring = Partial { spring: Some([tau_s_min, tau_s0]), ..Partial::default() };
    let g = grasp_at(f, s, tau_s0, 0.0).map_err(|e| (d2(Reason::Grasp(e), MISSING_POSE_VIOLATION), spring))?;
    let fmin = g.min_force();
    if !(fmin > 0.0) || !(g.hand_mu.y < 0.0) {
        let why = if !(fmin > 0.0) {
            OffsetFailure::ForceNotPositive(fmin)
        } else {
            OffsetFailure::PalmForceNotPositive(g.hand_mu.y)
        };
        let v = ((-fmin).max(g.hand_mu.y) / s.hand.tau).max(0.0);
        let grasp = CentredGrasp::of(&g);
        return Err((
            d2(Reason::Grasp(why), if v.is_finite() { v } else { MISSING_POSE_VIOLATION }),
            Partial { grasp: Some(grasp), ..spring },
        ));
    }
    let form_closed_0 = form_closure_test(&closure_matrix(f, &g.cp)).closed;
    let scan = max_offset(f, s, tau_s0);
    let ff = &g.forces[0];
    let (alpha_0, mean_force_0) = isotropy(ff.f0);
    let (alpha_mu, mean_force_mu) = isotropy(ff.fmu);
    let force_model = s.criteria.force_model;
    let (alpha, mean_force) = match force_model {
        crate::params::ForceModel::Mobilised => (alpha_mu, mean_force_mu),
        crate::params::ForceModel::Frictionless => (alpha_0, mean_force_0),
    };
    Ok(StaticsResult {
        tau_s_min,
        tau_s0,
        grasp: CentredGrasp::of(&g),
        form_closed_0,
        max_offset: scan.max_offset,
        offset_ended_by: scan.ended_by,
        alpha,
        mean_force,
        alpha_mu,
        mean_force_mu,
        alpha_0,
        mean_force_0,
        force_model,
    })
}

/// Stages 0–1 of a design: the evaluation so far, with `kin` set when the design passed
/// them, and what was computed before a discard (`partial`: the finger of a design the
/// singularity sweep discarded), as every later stage reports it (MODEL.md §10).
pub fn evaluate_kinematics(x: &Design, s: &SceneParams) -> Evaluation {
    let mut ev = Evaluation::new(*x);
    let t0 = Instant::now();
    match kinematics_partial(x, s) {
        Ok(k) => ev.kin = Some(k),
        Err((d, partial)) => {
            ev.discard = Some(d);
            ev.partial = partial;
        }
    }
    ev.stage_seconds[1] = t0.elapsed().as_secs_f64();
    ev
}

/// Stages 0–2 of a design (tens of µs): the evaluation so far, with `statics` set when the
/// design passed them. `evaluate_dynamics` finishes it; the two together are `evaluate`,
/// bit for bit.
pub fn evaluate_statics(x: &Design, s: &SceneParams) -> Evaluation {
    let mut ev = evaluate_kinematics(x, s);
    let Some(kin) = ev.kin else {
        return ev;
    };
    let t1 = Instant::now();
    let st = statics_partial(&kin.finger, s);
    ev.stage_seconds[2] = t1.elapsed().as_secs_f64();
    match st {
        Ok(st) => ev.statics = Some(st),
        Err((d, partial)) => {
            ev.discard = Some(d);
            ev.partial = partial;
        }
    }
    ev
}

#[cfg(test)]
mod tests {
    use super::{Cause, CAUSE_WORDS};

    /// The words of `Cause::as_str` are serde's, variant by variant.
    #[test]
    fn cause_words_are_serdes() {
        let all: Vec<Cause> =
            CAUSE_WORDS.iter().map(|w| serde_json::from_value(serde_json::json!(w)).unwrap()).collect();
        for (k, c) in all.iter().enumerate() {
            assert_eq!(*c as usize, k);
            assert_eq!(serde_json::to_value(c).unwrap(), serde_json::json!(c.as_str()));
        }
    }
}
