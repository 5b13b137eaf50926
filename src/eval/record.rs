//! The ONE place that flattens an evaluation into its record: the per-design JSON record
//! of MODEL.md §10 (`gripopt evaluate --json`, CSV rows, recordings, sweeps).

use super::free_stage::{FreeEnd, FreeMeasure};
use super::stages::Evaluation;
use crate::params::SceneKind;
use crate::sim::DynamicsResult;
use serde::Serialize;

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
    pub dynamics: DynamicsRecord,
    /// The free scene's §14.4 keys (flattened), present only when the problem's scene is
    /// free (null when the free scene did not run); absent for the centred and offset scenes.
    #[serde(flatten)]
    pub free: Option<FreeRecord>,
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
        let fin = |v: f64| v.is_finite().then_some(v);
        // MODEL.md §10: every value computed before a discard is reported, the rest null
        let f = ev.kin.map(|k| k.finger).or(ev.partial.finger);
        let st = ev.statics;
        let spring = st.map(|s| [s.tau_s_min, s.tau_s0]).or(ev.partial.spring);
        let pg = ev.partial.grasp;
        let grasp = |a: fn(&super::stages::StaticsResult) -> [f64; 2],
                     b: fn(&super::stages::PartialGrasp) -> [f64; 2]| {
            st.as_ref().map(a).or(pg.as_ref().map(b))
        };
        let theta = grasp(|s| s.theta, |g| g.theta);
        let k = grasp(|s| s.k, |g| g.k);
        let f0 = grasp(|s| s.f0, |g| g.f0);
        let fmu = grasp(|s| s.fmu, |g| g.fmu);
        let hand0 = grasp(|s| s.hand0, |g| g.hand0);
        let hand_mu = grasp(|s| s.hand_mu, |g| g.hand_mu);
        // l11 and l22 follow from the design (stage 0 computes them before any check)
        let l11 = f.map(|f| f.l11).or_else(|| fin(x.p * x.l21));
        let l22 = f.map(|f| f.l22).or_else(|| fin(x.r * (x.p * x.l21)));
        let fin = |v: f64| v.is_finite().then_some(v);
        Record {
            l21: x.l21,
            b: x.b,
            t22: x.t22,
            r: x.r,
            p: x.p,
            psi_deg: x.psi.to_degrees(),
            l_hand: x.l_hand(),
            l11,
            l12: f.map(|f| f.l12),
            l22,
            q11_0: f.map(|f| f.open.q11),
            q21_0: f.map(|f| f.open.q21),
            q12_0: f.map(|f| f.open.q12),
            q22_0: f.map(|f| f.open.q22),
            q13_0: f.map(|f| f.open.q13),
            gamma: f.map(|f| f.gamma),
            sigma: f.map(|f| f.sigma),
            masses: f.map(|f| f.mass.m),
            min_margin_deg: ev.kin.map(|k| k.sweep.min_margin.to_degrees()),
            tau_s_min: spring.map(|s| s[0]),
            tau_s0: spring.map(|s| s[1]),
            theta1: theta.map(|v| v[0]),
            theta2: theta.map(|v| v[1]),
            k1: k.map(|v| v[0]),
            k2: k.map(|v| v[1]),
            f0_1: f0.map(|v| v[0]),
            f0_2: f0.map(|v| v[1]),
            fmu_1: fmu.map(|v| v[0]),
            fmu_2: fmu.map(|v| v[1]),
            fhand0_x: hand0.map(|v| v[0]),
            fhand0_y: hand0.map(|v| v[1]),
            fhandmu_x: hand_mu.map(|v| v[0]),
            fhandmu_y: hand_mu.map(|v| v[1]),
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
            dynamics: DynamicsRecord::from_result(ev.dynamics.as_ref()),
            free: (ev.scene == SceneKind::Free).then(|| FreeRecord::from_measure(ev.free.as_ref())),
            feasible: ev.feasible(),
            failed_stage: ev.discard.map(|d| d.stage),
            reason: ev.discard.map(|d| d.reason.to_string()),
            violation: ev.discard.map(|d| d.violation),
        }
    }
}

/// Stage-3 keys of the JSON record (MODEL.md §10); all `null` when stage 3 did not run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct DynamicsRecord {
    /// Time of first contact (s).
    pub t_first_contact: Option<f64>,
    /// "proximal" or "distal".
    pub first_contact_phalanx: Option<&'static str>,
    /// Onset velocity (m/s).
    pub v_impact: Option<f64>,
    /// Effective finger mass (kg).
    pub m_finger: Option<f64>,
    /// E_cyl (J).
    pub e_cyl: Option<f64>,
    /// E_trans (J).
    pub e_trans: Option<f64>,
    /// E_rot (J).
    pub e_rot: Option<f64>,
    /// min(E_lim,trans, E_lim,rot) (J).
    pub e_lim: Option<f64>,
    /// θ2 at first contact (rad).
    pub theta2_first_contact: Option<f64>,
    /// Min filtered-force margin (N).
    pub min_force_margin: Option<f64>,
    /// Static hand-force margin (N).
    pub static_force_margin: Option<f64>,
    /// Time to stability (s).
    pub t_stab: Option<f64>,
    /// Proximal normal force at t_stab (N).
    pub f_stab_1: Option<f64>,
    /// Distal normal force at t_stab (N).
    pub f_stab_2: Option<f64>,
    /// f*_1 (N).
    pub fstar_1: Option<f64>,
    /// f*_2 (N).
    pub fstar_2: Option<f64>,
    /// max |q̈| at the end (rad/s²).
    pub max_qdd_end: Option<f64>,
    /// Accepted steps.
    pub steps: Option<u64>,
    /// Rejected steps.
    pub rejected_steps: Option<u64>,
    /// RHS evaluations.
    pub rhs_evals: Option<u64>,
    /// Jacobian evaluations.
    pub jac_evals: Option<u64>,
    /// LU factorisations.
    pub lu_count: Option<u64>,
    /// Newton iterations.
    pub newton_iters: Option<u64>,
    /// Step attempts rejected for Newton failure (part of `rejected_steps`).
    pub newton_failures: Option<u64>,
    /// Events.
    pub events: Option<u32>,
    /// CPU seconds of stage 3.
    pub cpu_s: Option<f64>,
    /// A knuckle contact was seen.
    pub knuckle_contact: Option<bool>,
}

impl DynamicsRecord {
    /// Flatten a result (None → all null).
    pub fn from_result(d: Option<&DynamicsResult>) -> Self {
        let Some(d) = d else { return Self::default() };
        let fin = |v: f64| v.is_finite().then_some(v);
        let fc = d.first;
        DynamicsRecord {
            t_first_contact: fc.map(|f| f.t),
            first_contact_phalanx: fc.map(|f| if f.phalanx == 1 { "proximal" } else { "distal" }),
            v_impact: fc.map(|f| f.impact.v_impact),
            m_finger: fc.map(|f| f.impact.m_finger),
            e_cyl: fc.map(|f| f.impact.e_cyl),
            e_trans: fc.map(|f| f.impact.e_trans),
            e_rot: fc.map(|f| f.impact.e_rot),
            e_lim: fc.map(|f| f.impact.e_lim),
            theta2_first_contact: fc.map(|f| f.theta2),
            min_force_margin: fin(d.min_force_margin),
            static_force_margin: fin(d.static_force_margin),
            t_stab: d.t_stab,
            f_stab_1: d.t_stab.map(|_| d.f_end[0]),
            f_stab_2: d.t_stab.map(|_| d.f_end[1]),
            fstar_1: fin(d.fstar[0]),
            fstar_2: fin(d.fstar[1]),
            max_qdd_end: fin(d.max_qdd_end),
            steps: Some(d.stats.steps),
            rejected_steps: Some(d.stats.rejected),
            rhs_evals: Some(d.rhs_evals),
            jac_evals: Some(d.stats.jac),
            lu_count: Some(d.stats.lu),
            newton_iters: Some(d.stats.newton),
            newton_failures: Some(d.stats.newton_fail),
            events: Some(d.events),
            cpu_s: Some(d.cpu_s),
            knuckle_contact: Some(d.knuckle_flag),
        }
    }
}

/// The free scene's keys of the JSON record (MODEL.md §14.4, the names of
/// `simulate --scene free --json`); all `null` when the free scene did not run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FreeRecord {
    /// Largest horizontal displacement of G (m).
    pub object_max_displacement: Option<f64>,
    /// Largest |Δx| of G (m).
    pub object_max_dx: Option<f64>,
    /// Largest |Δy| of G (m).
    pub object_max_dy: Option<f64>,
    /// Largest tilt (°).
    pub object_max_tilt_deg: Option<f64>,
    /// Horizontal displacement at the end (m).
    pub object_final_displacement: Option<f64>,
    /// Tilt at the end (°).
    pub object_final_tilt_deg: Option<f64>,
    /// Peak translational kinetic energy of the object during the first contact (J).
    pub object_peak_e_trans: Option<f64>,
    /// Peak rotational kinetic energy of the object during the first contact (J).
    pub object_peak_e_rot: Option<f64>,
    /// Max displacement > Δx_max or max tilt > θ_max.
    pub moved: Option<bool>,
    /// Tilt above 45° at some time.
    pub toppled: Option<bool>,
    /// No phalanx in contact at the end.
    pub escaped: Option<bool>,
    /// A loaded phalanx met the object's rim or a face.
    pub rim_contact: Option<bool>,
    /// Object offset x_off of the free scene (m).
    pub object_x_off: Option<f64>,
    /// How the free scene ended: "t_obs" (observed to min(t_max, t_obs)) or why it stopped
    /// early (then the maxima cover the part simulated and the verdict flags are null).
    pub free_end: Option<String>,
    /// Accepted steps of the free scene.
    pub free_steps: Option<u64>,
    /// Right-hand-side evaluations of the free scene.
    pub free_rhs_evals: Option<u64>,
}

impl FreeRecord {
    /// Flatten a measurement (None → all null).
    pub fn from_measure(m: Option<&FreeMeasure>) -> Self {
        let Some(m) = m else { return Self::default() };
        let observed = m.end == FreeEnd::Observed;
        FreeRecord {
            object_max_displacement: Some(m.max_displacement),
            object_max_dx: Some(m.max_dx),
            object_max_dy: Some(m.max_dy),
            object_max_tilt_deg: Some(m.max_tilt_deg),
            object_final_displacement: Some(m.final_displacement),
            object_final_tilt_deg: Some(m.final_tilt_deg),
            object_peak_e_trans: Some(m.peak_e_trans),
            object_peak_e_rot: Some(m.peak_e_rot),
            moved: observed.then_some(m.moved),
            toppled: observed.then_some(m.toppled),
            escaped: observed.then_some(m.escaped),
            rim_contact: Some(m.rim_contact),
            object_x_off: Some(m.x_off),
            free_end: Some(m.end.to_string()),
            free_steps: Some(m.steps),
            free_rhs_evals: Some(m.rhs_evals),
        }
    }
}
