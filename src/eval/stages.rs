//! The stages of MODEL.md §10: each returns its values or a [`Discard`] with the stage, a
//! reason and a non-negative violation (0 = satisfied), so an optimiser can rank infeasible
//! designs. No heap allocation per evaluation.

use super::free_stage::{stage3_free, FreeMeasure, ObjectMotion};
use crate::model::isotropy;
use crate::model::spring_preload;
pub use crate::model::StaticsResult;
use crate::model::{closure_matrix, form_closure_test, grasp_at, max_offset, OffsetFailure};
use crate::model::{singularity_sweep, Sweep, SweepFailure};
use crate::model::{Finger, GeomError};
use crate::params::{Design, Problem, SceneKind, SceneParams};
use crate::sim::{Controls, DynOutcome, DynamicsResult, Integration, SceneSpec, Sink};
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
    /// Stage 3 of a free-kind problem: the free object did not barely move (§14.4).
    ObjectMoved(ObjectMotion),
    /// Stage 3 of a free-kind problem: the free scene ended before t_obs (why).
    FreeSceneEnded(crate::sim::FreeEnd),
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
    /// Stage 3 values, if stage 3 ran (also when it discarded the design). For a
    /// free-kind problem: the centred scene's (in diagnostic mode).
    pub dynamics: Option<DynamicsResult>,
    /// For a free-kind problem: the free scene's measurement, if it ran (MODEL.md §14.4).
    pub free: Option<FreeMeasure>,
    /// The scene stage 3 ran in (the problem's `[scene] kind`; centred when stage 3 did not run).
    pub scene: SceneKind,
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
    pub grasp: Option<PartialGrasp>,
}

/// Stage-2 values of a grasp whose forces were not all positive.
#[derive(Debug, Clone, Copy)]
pub struct PartialGrasp {
    /// θ1, θ2 of the closed pose.
    pub theta: [f64; 2],
    /// k1, k2.
    pub k: [f64; 2],
    /// f⁰ (finger 1).
    pub f0: [f64; 2],
    /// f^μ (finger 1).
    pub fmu: [f64; 2],
    /// F⁰_hand.
    pub hand0: [f64; 2],
    /// F^μ_hand.
    pub hand_mu: [f64; 2],
}

impl Evaluation {
    /// A design not evaluated yet.
    pub fn new(design: Design) -> Self {
        Evaluation {
            design,
            kin: None,
            statics: None,
            dynamics: None,
            free: None,
            scene: SceneKind::Centred,
            discard: None,
            partial: Partial::default(),
            stage_seconds: [0.0; 4],
        }
    }
    /// True when no stage discarded the design.
    pub fn feasible(&self) -> bool {
        self.discard.is_none()
    }
    /// Objectives in minimisation form (−max_offset, α, −F̃, t_stab); NaN where not computed.
    pub fn objectives(&self) -> [f64; 4] {
        let (a, b, c) = match &self.statics {
            Some(s) => (-s.max_offset, s.alpha, -s.mean_force),
            None => (f64::NAN, f64::NAN, f64::NAN),
        };
        let t = match (&self.dynamics, &self.discard) {
            (Some(d), None) => d.t_stab.unwrap_or(f64::NAN),
            _ => f64::NAN,
        };
        [a, b, c, t]
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
}

impl EvalOptions {
    /// Stages 0–2 only.
    pub fn statics_only() -> Self {
        EvalOptions {
            dynamics: false,
            integration: Integration::new(1e-6, 1e-9, 200_000),
            controls: Controls::PIPELINE,
        }
    }
    /// All four stages with the problem's solver settings, stopping at the first violated criterion.
    pub fn full(p: &Problem) -> Self {
        EvalOptions { dynamics: true, integration: Integration::from_solver(&p.solver), controls: Controls::PIPELINE }
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
fn kinematics_partial(x: &Design, s: &SceneParams) -> Result<KinematicsResult, (Discard, Partial)> {
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
        let (cp, ff) = (&g.cp[0], &g.forces[0]);
        let grasp = PartialGrasp {
            theta: [cp.theta1, cp.theta2],
            k: [cp.k1, cp.k2],
            f0: ff.f0,
            fmu: ff.fmu,
            hand0: [g.hand0.x, g.hand0.y],
            hand_mu: [g.hand_mu.x, g.hand_mu.y],
        };
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
    let cp = &g.cp[0];
    Ok(StaticsResult {
        tau_s_min,
        tau_s0,
        theta: [cp.theta1, cp.theta2],
        k: [cp.k1, cp.k2],
        f0: ff.f0,
        fmu: ff.fmu,
        hand0: [g.hand0.x, g.hand0.y],
        hand_mu: [g.hand_mu.x, g.hand_mu.y],
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

/// Evaluate a design through the staged pipeline.
pub fn evaluate(x: &Design, s: &SceneParams, opts: &EvalOptions) -> Evaluation {
    evaluate_inner(x, s, opts)
}

/// Evaluate, reporting stage 3's samples to `sink` (the simulation that decides the
/// verdict; results do not depend on the sink).
pub fn evaluate_into<K: Sink + ?Sized>(x: &Design, s: &SceneParams, opts: &EvalOptions, sink: &mut K) -> Evaluation {
    let ev = evaluate_statics(x, s);
    if !opts.dynamics {
        return ev;
    }
    evaluate_dynamics(ev, s, opts, sink)
}

fn evaluate_inner(x: &Design, s: &SceneParams, opts: &EvalOptions) -> Evaluation {
    evaluate_into(x, s, opts, &mut ())
}

/// Stages 0–2 of a design (tens of µs): the evaluation so far, with `statics` set when the
/// design passed them. [`evaluate_dynamics`] finishes it; the two together are
/// [`evaluate`], bit for bit.
pub fn evaluate_statics(x: &Design, s: &SceneParams) -> Evaluation {
    let mut ev = Evaluation::new(*x);
    let t0 = Instant::now();
    let kin = match kinematics_partial(x, s) {
        Ok(k) => k,
        Err((d, partial)) => {
            ev.stage_seconds[1] = t0.elapsed().as_secs_f64();
            ev.discard = Some(d);
            ev.partial = partial;
            return ev;
        }
    };
    ev.kin = Some(kin);
    let t1 = Instant::now();
    ev.stage_seconds[1] = (t1 - t0).as_secs_f64();
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

/// Stage 3 of an evaluation from [`evaluate_statics`] in the problem's scene, reporting
/// its samples to `sink`; an evaluation that did not pass stages 0–2 comes back unchanged.
pub fn evaluate_dynamics<K: Sink + ?Sized>(
    mut ev: Evaluation,
    s: &SceneParams,
    opts: &EvalOptions,
    sink: &mut K,
) -> Evaluation {
    let (Some(kin), Some(st), None) = (ev.kin, ev.statics, ev.discard) else { return ev };
    let t2 = Instant::now();
    ev.scene = s.setup.kind;
    if s.setup.kind == SceneKind::Free {
        let (dynr, free, discard) = stage3_free(&kin.finger, s, &st, &opts.integration, sink);
        ev.stage_seconds[3] = t2.elapsed().as_secs_f64();
        (ev.dynamics, ev.free, ev.discard) = (Some(dynr), free, discard);
        return ev;
    }
    let spec = SceneSpec::of(&s.setup);
    let run = crate::sim::simulate(&kin.finger, s, &st, &spec, &opts.integration, &opts.controls, sink);
    let dynr = *run.grasp().expect("a grasp scene");
    ev.stage_seconds[3] = t2.elapsed().as_secs_f64();
    if let Some(v) = dynr.discard_violation() {
        ev.discard = Some(Discard { stage: 3, reason: Reason::Dynamics(dynr.outcome), violation: v });
    }
    ev.dynamics = Some(dynr);
    ev
}

/// True when stage 3 of a design that passed stages 0–2 is known to end before its
/// simulation starts: the centred scene in pipeline mode with a violated static force
/// criterion (MODEL.md §9.3). Only orders work (a cost hint); the verdict is stage 3's own.
pub fn stage3_ends_at_once(st: &StaticsResult, s: &SceneParams, opts: &EvalOptions) -> bool {
    use crate::sim::{force_margin, r_area, Mode};
    opts.controls.mode == Mode::Pipeline
        && s.setup.kind == SceneKind::Centred
        && force_margin(s, r_area(s), nalgebra::Vector2::new(st.hand0[0], st.hand0[1])) < 0.0
}

/// Evaluate the problem's design `x` with all stages.
pub fn evaluate_full(p: &Problem, x: &Design) -> Evaluation {
    evaluate(x, &p.scene, &EvalOptions::full(p))
}
