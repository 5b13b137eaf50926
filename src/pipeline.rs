//! Staged evaluation of a design (MODEL.md §10). Each stage returns its values or a
//! [`Discard`] with the stage, a reason and a non-negative violation (0 = satisfied), so an
//! optimiser can rank infeasible designs. No heap allocation per evaluation.

use crate::model::closure::{closure_matrix, form_closure_test, grasp_at, max_offset, OffsetFailure};
use crate::model::constraints::{singularity_sweep, Sweep, SweepFailure};
use crate::model::geometry::{Finger, GeomError};
use crate::model::statics::spring_preload;
use crate::model::statics::isotropy;
use crate::params::{Design, Problem, SceneParams};
use crate::sim::grasp::{DynOutcome, DynamicsResult, SimOptions};
use serde::Serialize;
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

/// Stage 2 values (centred object).
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

/// Everything known about one evaluated design.
#[derive(Debug, Clone, Copy)]
pub struct Evaluation {
    /// The design.
    pub design: Design,
    /// Stage 1 values, if stage 1 ran to its end.
    pub kin: Option<KinematicsResult>,
    /// Stage 2 values, if stage 2 passed.
    pub statics: Option<StaticsResult>,
    /// Stage 3 values, if stage 3 ran (also when it discarded the design).
    pub dynamics: Option<DynamicsResult>,
    /// `None` = feasible.
    pub discard: Option<Discard>,
    /// Wall time per stage (s): 0–1 together in [1], 2, 3.
    pub stage_seconds: [f64; 4],
}

impl Evaluation {
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
    /// Simulation options for stage 3.
    pub sim: SimOptions,
}

impl EvalOptions {
    /// Stages 0–2 only.
    pub fn statics_only() -> Self {
        EvalOptions { dynamics: false, sim: SimOptions::pipeline(1e-6, 1e-9, 200_000) }
    }
    /// All four stages with the problem's solver settings, stopping at the first violated criterion.
    pub fn full(p: &Problem) -> Self {
        EvalOptions { dynamics: true, sim: SimOptions::pipeline(p.solver.rtol, p.solver.atol, p.solver.max_steps) }
    }
}

/// Stages 0 and 1: validity, open pose, mass, singularity sweep.
pub fn stage_kinematics(x: &Design, s: &SceneParams) -> Result<KinematicsResult, Discard> {
    let finger = Finger::new(x, s).map_err(|g| match g {
        GeomError::InvalidLength => Discard { stage: 0, reason: Reason::InvalidDesign, violation: 1.0 },
        other => Discard { stage: 1, reason: Reason::Geometry(other), violation: 90.0 },
    })?;
    let sweep = singularity_sweep(&finger, s).map_err(|e| Discard {
        stage: 1,
        reason: Reason::Sweep(e),
        violation: e.violation_deg(s.criteria.margin_sing),
    })?;
    Ok(KinematicsResult { finger, sweep })
}

/// Stage 2: spring, centred grasp, force constraints, α, F̃, form closure, max_offset.
pub fn stage_statics(f: &Finger, s: &SceneParams) -> Result<StaticsResult, Discard> {
    let d2 = |reason, violation| Discard { stage: 2, reason, violation };
    let (tau_s_min, tau_s0) = spring_preload(f, s).ok_or(d2(Reason::SpringUndefined, MISSING_POSE_VIOLATION))?;
    let g = grasp_at(f, s, tau_s0, 0.0).map_err(|e| d2(Reason::Grasp(e), MISSING_POSE_VIOLATION))?;
    let fmin = g.min_force();
    if !(fmin > 0.0) || !(g.hand_mu.y < 0.0) {
        let why = if !(fmin > 0.0) { OffsetFailure::ForceNotPositive(fmin) } else { OffsetFailure::PalmForceNotPositive(g.hand_mu.y) };
        let v = ((-fmin).max(g.hand_mu.y) / s.hand.tau).max(0.0);
        return Err(d2(Reason::Grasp(why), if v.is_finite() { v } else { MISSING_POSE_VIOLATION }));
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
    evaluate_inner(x, s, opts, None)
}

/// Evaluate and return the stage-3 trajectory (if stage 3 ran), recorded by the same
/// simulation that decided the verdict.
pub fn evaluate_with_trajectory(x: &Design, s: &SceneParams, opts: &EvalOptions) -> (Evaluation, Option<crate::sim::grasp::Trajectory>) {
    let mut tr = crate::sim::grasp::Trajectory::default();
    let ev = evaluate_inner(x, s, opts, Some(&mut tr));
    let has = ev.dynamics.is_some();
    (ev, has.then_some(tr))
}

fn evaluate_inner(x: &Design, s: &SceneParams, opts: &EvalOptions, traj: Option<&mut crate::sim::grasp::Trajectory>) -> Evaluation {
    let mut ev = Evaluation { design: *x, kin: None, statics: None, dynamics: None, discard: None, stage_seconds: [0.0; 4] };
    let t0 = Instant::now();
    let kin = match stage_kinematics(x, s) {
        Ok(k) => k,
        Err(d) => {
            ev.stage_seconds[1] = t0.elapsed().as_secs_f64();
            ev.discard = Some(d);
            return ev;
        }
    };
    ev.kin = Some(kin);
    let t1 = Instant::now();
    ev.stage_seconds[1] = (t1 - t0).as_secs_f64();
    let st = stage_statics(&kin.finger, s);
    let t2 = Instant::now();
    ev.stage_seconds[2] = (t2 - t1).as_secs_f64();
    let st = match st {
        Ok(st) => st,
        Err(d) => {
            ev.discard = Some(d);
            return ev;
        }
    };
    ev.statics = Some(st);
    if !opts.dynamics {
        return ev;
    }
    let dynr = crate::sim::grasp::simulate_grasp_into(&kin.finger, s, &st, &opts.sim, traj);
    ev.stage_seconds[3] = t2.elapsed().as_secs_f64();
    if let Some(v) = dynr.discard_violation() {
        ev.discard = Some(Discard { stage: 3, reason: Reason::Dynamics(dynr.outcome), violation: v });
    }
    ev.dynamics = Some(dynr);
    ev
}

/// Evaluate the problem's design `x` with all stages.
pub fn evaluate_full(p: &Problem, x: &Design) -> Evaluation {
    evaluate(x, &p.scene, &EvalOptions::full(p))
}

/// The per-design JSON record of MODEL.md §10 (snake_case keys; `null` = not computed).
#[derive(Debug, Clone, Serialize)]
pub struct Record {
    /// Design: l21 (m).
    pub l21: f64,
    /// Design: b (m).
    pub b: f64,
    /// Design: t22 (m).
    pub t22: f64,
    /// Design: r.
    pub r: f64,
    /// Design: p.
    pub p: f64,
    /// Design: ψ (deg).
    pub psi_deg: f64,
    /// l_hand (m).
    pub l_hand: f64,
    /// l11 (m).
    pub l11: Option<f64>,
    /// l12 (m).
    pub l12: Option<f64>,
    /// l22 (m).
    pub l22: Option<f64>,
    /// Open q11 (rad).
    pub q11_0: Option<f64>,
    /// Open q21 (rad).
    pub q21_0: Option<f64>,
    /// Open q12 (rad).
    pub q12_0: Option<f64>,
    /// Open q22 (rad).
    pub q22_0: Option<f64>,
    /// Open q13 (rad).
    pub q13_0: Option<f64>,
    /// Assembly mode Γ.
    pub gamma: Option<f64>,
    /// Working mode σ.
    pub sigma: Option<f64>,
    /// Body masses m11, m12, m21, m22 (kg).
    pub masses: Option<[f64; 4]>,
    /// Minimum singularity margin (deg).
    pub min_margin_deg: Option<f64>,
    /// τ_s^min before clipping (N·m).
    pub tau_s_min: Option<f64>,
    /// Spring preload τ_s0 (N·m).
    pub tau_s0: Option<f64>,
    /// Closed pose θ1 (rad).
    pub theta1: Option<f64>,
    /// Closed pose θ2 (rad).
    pub theta2: Option<f64>,
    /// k1 (m).
    pub k1: Option<f64>,
    /// k2 (m).
    pub k2: Option<f64>,
    /// f⁰_1 (N).
    pub f0_1: Option<f64>,
    /// f⁰_2 (N).
    pub f0_2: Option<f64>,
    /// f^μ_1 (N).
    pub fmu_1: Option<f64>,
    /// f^μ_2 (N).
    pub fmu_2: Option<f64>,
    /// F⁰_hand,x (N).
    pub fhand0_x: Option<f64>,
    /// F⁰_hand,y (N).
    pub fhand0_y: Option<f64>,
    /// F^μ_hand,x (N).
    pub fhandmu_x: Option<f64>,
    /// F^μ_hand,y (N).
    pub fhandmu_y: Option<f64>,
    /// Form closed at x_off = 0.
    pub form_closed_0: Option<bool>,
    /// Objective 1 (m).
    pub max_offset: Option<f64>,
    /// What ended the offset scan (null if off_max was reached).
    pub max_offset_ended_by: Option<String>,
    /// Objective 2: α of the problem's force model (D22).
    pub alpha: Option<f64>,
    /// Objective 3 (N): F̃ of the problem's force model (D22).
    pub mean_force: Option<f64>,
    /// α from f^μ.
    pub alpha_mu: Option<f64>,
    /// F̃ from f^μ (N).
    pub mean_force_mu: Option<f64>,
    /// α from f⁰.
    pub alpha_0: Option<f64>,
    /// F̃ from f⁰ (N).
    pub mean_force_0: Option<f64>,
    /// Force model of alpha and mean_force ("mobilised" or "frictionless").
    pub force_model: Option<&'static str>,
    /// Stage-3 keys (flattened; all null when stage 3 did not run).
    #[serde(flatten)]
    pub dynamics: crate::sim::grasp::DynamicsRecord,
    /// No stage discarded the design.
    pub feasible: bool,
    /// Stage that discarded it.
    pub failed_stage: Option<u8>,
    /// Why.
    pub reason: Option<String>,
    /// Violation magnitude (§10 units).
    pub violation: Option<f64>,
}

impl Record {
    /// Build the record of an evaluation.
    pub fn from_eval(ev: &Evaluation) -> Self {
        let x = &ev.design;
        let f = ev.kin.map(|k| k.finger);
        let st = ev.statics;
        let fin = |v: f64| v.is_finite().then_some(v);
        Record {
            l21: x.l21,
            b: x.b,
            t22: x.t22,
            r: x.r,
            p: x.p,
            psi_deg: x.psi.to_degrees(),
            l_hand: x.l_hand(),
            l11: f.map(|f| f.l11),
            l12: f.map(|f| f.l12),
            l22: f.map(|f| f.l22),
            q11_0: f.map(|f| f.open.q11),
            q21_0: f.map(|f| f.open.q21),
            q12_0: f.map(|f| f.open.q12),
            q22_0: f.map(|f| f.open.q22),
            q13_0: f.map(|f| f.open.q13),
            gamma: f.map(|f| f.gamma),
            sigma: f.map(|f| f.sigma),
            masses: f.map(|f| f.mass.m),
            min_margin_deg: ev.kin.map(|k| k.sweep.min_margin.to_degrees()),
            tau_s_min: st.map(|s| s.tau_s_min),
            tau_s0: st.map(|s| s.tau_s0),
            theta1: st.map(|s| s.theta[0]),
            theta2: st.map(|s| s.theta[1]),
            k1: st.map(|s| s.k[0]),
            k2: st.map(|s| s.k[1]),
            f0_1: st.map(|s| s.f0[0]),
            f0_2: st.map(|s| s.f0[1]),
            fmu_1: st.map(|s| s.fmu[0]),
            fmu_2: st.map(|s| s.fmu[1]),
            fhand0_x: st.map(|s| s.hand0[0]),
            fhand0_y: st.map(|s| s.hand0[1]),
            fhandmu_x: st.map(|s| s.hand_mu[0]),
            fhandmu_y: st.map(|s| s.hand_mu[1]),
            form_closed_0: st.map(|s| s.form_closed_0),
            max_offset: st.map(|s| s.max_offset),
            max_offset_ended_by: st.and_then(|s| s.offset_ended_by.map(|e| e.reason())),
            alpha: st.and_then(|s| fin(s.alpha)),
            mean_force: st.map(|s| s.mean_force),
            alpha_mu: st.and_then(|s| fin(s.alpha_mu)),
            mean_force_mu: st.map(|s| s.mean_force_mu),
            alpha_0: st.and_then(|s| fin(s.alpha_0)),
            mean_force_0: st.map(|s| s.mean_force_0),
            force_model: st.map(|s| s.force_model.as_str()),
            dynamics: crate::sim::grasp::DynamicsRecord::from_result(ev.dynamics.as_ref()),
            feasible: ev.feasible(),
            failed_stage: ev.discard.map(|d| d.stage),
            reason: ev.discard.map(|d| d.reason.to_string()),
            violation: ev.discard.map(|d| d.violation),
        }
    }
}
