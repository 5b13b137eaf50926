//! The stage-3 parts of the evaluation [`Record`](super::Record): the grasp
//! ([`GraspRecord`], the centred or offset scene), the offset scene's hand forces
//! ([`OffsetSceneRecord`]) and the free scene's measurement ([`FreeSceneRecord`]). Keys
//! are flat, one per quantity, the free scene's carrying its name; `null` = not computed.

use crate::sim::{DynOutcome, DynamicsResult, FreeEnd, FreeResult, OffsetResult};
use serde::{Deserialize, Serialize};

/// A finite value, or None (NaN, ±∞: not a value).
pub(crate) fn fin(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The phalanx of a first contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phalanx {
    /// Proximal (phalanx 1).
    Proximal,
    /// Distal (phalanx 2).
    Distal,
}

impl Phalanx {
    /// Phalanx 1 or 2.
    pub fn of(index: u8) -> Self {
        if index == 1 {
            Phalanx::Proximal
        } else {
            Phalanx::Distal
        }
    }
}

/// Stage 3's grasp (MODEL.md §8–9): the problem's scene (centred or offset), or in the
/// free kind the centred scene's prediction; all `null` when it did not run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GraspRecord {
    /// Time of first contact (s).
    pub t_first_contact: Option<f64>,
    /// The phalanx of the first contact.
    pub first_contact_phalanx: Option<Phalanx>,
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
    /// Right-hand-side evaluations (including event location).
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
    /// Wall seconds of the simulation.
    pub cpu_s: Option<f64>,
    /// A knuckle contact was seen.
    pub knuckle_contact: Option<bool>,
    /// How the grasp ended, or the first criterion it violated.
    pub outcome: Option<DynOutcome>,
    /// The impact criterion holds (null: no contact).
    pub impact_ok: Option<bool>,
    /// The fold criterion holds (null: no contact).
    pub fold_ok: Option<bool>,
    /// The force criterion holds (filtered and static hand force).
    pub force_ok: Option<bool>,
    /// Time the simulation ended (s).
    pub t_end: Option<f64>,
}

impl GraspRecord {
    /// Flatten a result (None → all null).
    pub fn from_result(d: Option<&DynamicsResult>) -> Self {
        let Some(d) = d else { return Self::default() };
        let fc = d.first;
        let imp = |f: fn(&crate::sim::Impact) -> f64| fc.map(|c| f(&c.impact));
        let st = &d.stats;
        GraspRecord {
            t_first_contact: fc.map(|f| f.t),
            first_contact_phalanx: fc.map(|f| Phalanx::of(f.phalanx)),
            v_impact: imp(|i| i.v_impact),
            m_finger: imp(|i| i.m_finger),
            e_cyl: imp(|i| i.e_cyl),
            e_trans: imp(|i| i.e_trans),
            e_rot: imp(|i| i.e_rot),
            e_lim: imp(|i| i.e_lim),
            theta2_first_contact: fc.map(|f| f.theta2),
            min_force_margin: fin(d.min_force_margin),
            static_force_margin: fin(d.static_force_margin),
            t_stab: d.t_stab,
            f_stab_1: d.t_stab.map(|_| d.f_end[0]),
            f_stab_2: d.t_stab.map(|_| d.f_end[1]),
            fstar_1: fin(d.fstar[0]),
            fstar_2: fin(d.fstar[1]),
            max_qdd_end: fin(d.max_qdd_end),
            steps: Some(st.steps),
            rejected_steps: Some(st.rejected),
            rhs_evals: Some(d.rhs_evals),
            jac_evals: Some(st.jac),
            lu_count: Some(st.lu),
            newton_iters: Some(st.newton),
            newton_failures: Some(st.newton_fail),
            events: Some(d.events),
            cpu_s: Some(d.cpu_s),
            knuckle_contact: Some(d.knuckle_flag),
            outcome: Some(d.outcome),
            impact_ok: d.impact_ok,
            fold_ok: d.fold_ok,
            force_ok: Some(d.t_force_violation.is_none() && d.static_force_margin >= 0.0),
            t_end: Some(d.t_end),
        }
    }
}

/// The offset scene's hand forces (present only when stage 3 ran in the offset scene).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OffsetSceneRecord {
    /// F_hand,x at the end (N, world).
    pub hand_x_end: Option<f64>,
    /// F_hand,y at the end (N, world).
    pub hand_y_end: Option<f64>,
    /// F⁰_hand,x of the static model at the offset (N, world).
    pub hand0_x: Option<f64>,
    /// F⁰_hand,y of the static model at the offset (N, world).
    pub hand0_y: Option<f64>,
    /// The hand force at the end pushes the object back toward the centre.
    pub recentres: Option<bool>,
}

impl OffsetSceneRecord {
    /// From the offset scene's result.
    pub fn from_result(o: &OffsetResult) -> Self {
        OffsetSceneRecord {
            hand_x_end: fin(o.hand_end[0]),
            hand_y_end: fin(o.hand_end[1]),
            hand0_x: fin(o.hand0[0]),
            hand0_y: fin(o.hand0[1]),
            recentres: Some(o.hand_end[0] * o.x_off < 0.0),
        }
    }
}

/// The free scene's measurement (MODEL.md §14.4; present only when stage 3 ran in the
/// free scene; all `null` when the free scene itself did not run). The verdict flags are
/// `null` when the run ended before t_obs (nothing observed).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FreeSceneRecord {
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
    /// How the free scene ended: `t_obs` (observed to min(t_max, t_obs)) or why it stopped
    /// early (then the maxima cover the part simulated).
    pub free_end: Option<FreeEnd>,
    /// Largest |a_x|: the axis leaning along the palm (sine of the tilt about y).
    pub object_max_tilt_y: Option<f64>,
    /// Largest spin about the vertical, 2|q_z| (rad, small-angle).
    pub object_max_spin: Option<f64>,
    /// Time the free scene reached (s).
    pub free_t_end: Option<f64>,
    /// First phalanx contact of the free scene (s).
    pub free_t_first_contact: Option<f64>,
    /// Its phalanx (of finger 1 or 2).
    pub free_first_contact_phalanx: Option<Phalanx>,
    /// §9.1's onset velocity at that contact (m/s).
    pub free_v_impact: Option<f64>,
    /// §9.1's effective finger mass at that contact (kg).
    pub free_m_finger: Option<f64>,
    /// §9.1's E_cyl at that contact (J).
    pub free_e_cyl: Option<f64>,
    /// §9.1's E_trans at that contact (J).
    pub free_e_trans: Option<f64>,
    /// §9.1's E_rot at that contact (J).
    pub free_e_rot: Option<f64>,
    /// §9.1's E_lim (J).
    pub free_e_lim: Option<f64>,
    /// Accepted steps of the free scene.
    pub free_steps: Option<u64>,
    /// Rejected steps.
    pub free_rejected_steps: Option<u64>,
    /// Right-hand-side evaluations of the free scene (including event location).
    pub free_rhs_evals: Option<u64>,
    /// Jacobian evaluations.
    pub free_jac_evals: Option<u64>,
    /// Partial evaluations of the block Jacobian.
    pub free_jac_block_evals: Option<u64>,
    /// LU factorisations.
    pub free_lu_count: Option<u64>,
    /// Newton iterations.
    pub free_newton_iters: Option<u64>,
    /// Step attempts rejected for Newton failure.
    pub free_newton_failures: Option<u64>,
    /// Events.
    pub free_events: Option<u32>,
    /// Wall seconds of the free scene.
    pub free_cpu_s: Option<f64>,
    /// Total energy at the start (J).
    pub free_energy_start: Option<f64>,
    /// Total energy at the end (J).
    pub free_energy_end: Option<f64>,
    /// Largest energy increase between two consecutive accepted states (J; ≈ 0).
    pub free_max_energy_rise: Option<f64>,
}

impl FreeSceneRecord {
    /// Flatten a result (None → all null).
    pub fn from_result(r: Option<&FreeResult>) -> Self {
        let Some(r) = r else { return Self::default() };
        let seen = |v: bool| r.end.observed().then_some(v);
        let imp = |f: fn(&crate::sim::Impact) -> f64| r.first_impact.as_ref().map(f);
        let st = &r.stats;
        FreeSceneRecord {
            object_max_displacement: Some(r.object_max_displacement),
            object_max_dx: Some(r.object_max_dx),
            object_max_dy: Some(r.object_max_dy),
            object_max_tilt_deg: Some(r.object_max_tilt_deg),
            object_final_displacement: Some(r.object_final_displacement),
            object_final_tilt_deg: Some(r.object_final_tilt_deg),
            object_peak_e_trans: Some(r.object_peak_e_trans),
            object_peak_e_rot: Some(r.object_peak_e_rot),
            moved: seen(r.moved),
            toppled: seen(r.toppled),
            escaped: seen(r.escaped),
            rim_contact: Some(r.rim_contact),
            free_end: Some(r.end),
            object_max_tilt_y: Some(r.object_max_tilt_y),
            object_max_spin: Some(r.object_max_spin),
            free_t_end: Some(r.t_end),
            free_t_first_contact: r.first_contact_t,
            free_first_contact_phalanx: r.first_contact_phalanx.map(Phalanx::of),
            free_v_impact: imp(|i| i.v_impact),
            free_m_finger: imp(|i| i.m_finger),
            free_e_cyl: imp(|i| i.e_cyl),
            free_e_trans: imp(|i| i.e_trans),
            free_e_rot: imp(|i| i.e_rot),
            free_e_lim: imp(|i| i.e_lim),
            free_steps: Some(st.steps),
            free_rejected_steps: Some(st.rejected),
            free_rhs_evals: Some(r.rhs_evals),
            free_jac_evals: Some(st.jac),
            free_jac_block_evals: Some(r.jac_block_evals),
            free_lu_count: Some(st.lu),
            free_newton_iters: Some(st.newton),
            free_newton_failures: Some(st.newton_fail),
            free_events: Some(r.events),
            free_cpu_s: Some(r.cpu_s),
            free_energy_start: fin(r.energy[0]),
            free_energy_end: fin(r.energy[1]),
            free_max_energy_rise: Some(r.max_energy_rise),
        }
    }
}

impl FreeSceneRecord {
    /// A record with every value set (a placeholder of each type, not a result): gives
    /// every key with its JSON type, e.g. for the recording's schema.
    pub fn full_example() -> Self {
        let (x, n, b) = (Some(0.5), Some(1), Some(true));
        FreeSceneRecord {
            object_max_displacement: x,
            object_max_dx: x,
            object_max_dy: x,
            object_max_tilt_deg: x,
            object_final_displacement: x,
            object_final_tilt_deg: x,
            object_peak_e_trans: x,
            object_peak_e_rot: x,
            moved: b,
            toppled: b,
            escaped: b,
            rim_contact: b,
            free_end: Some(FreeEnd::Observed),
            object_max_tilt_y: x,
            object_max_spin: x,
            free_t_end: x,
            free_t_first_contact: x,
            free_first_contact_phalanx: Some(Phalanx::Proximal),
            free_v_impact: x,
            free_m_finger: x,
            free_e_cyl: x,
            free_e_trans: x,
            free_e_rot: x,
            free_e_lim: x,
            free_steps: n,
            free_rejected_steps: n,
            free_rhs_evals: n,
            free_jac_evals: n,
            free_jac_block_evals: n,
            free_lu_count: n,
            free_newton_iters: n,
            free_newton_failures: n,
            free_events: Some(1),
            free_cpu_s: x,
            free_energy_start: x,
            free_energy_end: x,
            free_max_energy_rise: x,
        }
    }
}
