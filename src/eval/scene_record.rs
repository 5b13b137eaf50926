//! The stage-3 parts of the evaluation [`Record`](super::Record): the grasp
//! ([`GraspRecord`], the centred or offset scene; in the free kind the centred prediction),
//! the offset scene's hand forces ([`OffsetSceneRecord`], as `offset_scene`) and the free
//! scene's measurement ([`FreeSceneRecord`], as `free_scene`). What every simulation gives
//! (a first impact, the integrator's work) is one sub-record each, the same in every scene.
//! `null` = not computed.

use crate::sim::{DynOutcome, DynamicsResult, FirstContact, FreeEnd, FreeResult, Impact, OffsetResult, Stats};
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

/// The first contact of a simulation and §9.1's impact energies there.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ImpactRecord {
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
}

impl ImpactRecord {
    /// The first contact at `t` on phalanx 1 or 2 with its impact energies.
    fn of(t: f64, phalanx: u8, i: &Impact) -> Self {
        ImpactRecord {
            t_first_contact: Some(t),
            first_contact_phalanx: Some(if phalanx == 1 { Phalanx::Proximal } else { Phalanx::Distal }),
            v_impact: Some(i.v_impact),
            m_finger: Some(i.m_finger),
            e_cyl: Some(i.e_cyl),
            e_trans: Some(i.e_trans),
            e_rot: Some(i.e_rot),
            e_lim: Some(i.e_lim),
        }
    }
}

/// What a simulation cost: the integrator's counters and the wall time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct WorkRecord {
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
    /// Switches between Dormand–Prince and RADAU5, both ways (method `auto` only: the key is
    /// absent for every other method).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub switches: Option<u64>,
    /// Accepted steps Dormand–Prince took (part of `steps`; RADAU5 took the rest; method
    /// `auto` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit_steps: Option<u64>,
}

impl WorkRecord {
    fn of(st: &Stats, rhs_evals: u64, events: u32, cpu_s: f64) -> Self {
        WorkRecord {
            steps: Some(st.steps),
            rejected_steps: Some(st.rejected),
            rhs_evals: Some(rhs_evals),
            jac_evals: Some(st.jac),
            lu_count: Some(st.lu),
            newton_iters: Some(st.newton),
            newton_failures: Some(st.newton_fail),
            events: Some(events),
            cpu_s: Some(cpu_s),
            switches: st.switches,
            explicit_steps: st.explicit_steps,
        }
    }
}

/// Stage 3's grasp (MODEL.md §8–9): the problem's scene (centred or offset), or in the
/// free kind the centred scene's prediction; all `null` when it did not run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GraspRecord {
    /// The first contact.
    #[serde(flatten)]
    pub impact: ImpactRecord,
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
    /// The simulation's work.
    #[serde(flatten)]
    pub work: WorkRecord,
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
        let fc: Option<FirstContact> = d.first;
        // the hand force is watched once a contact force acts: not when the simulation
        // ended at or before its first contact (a design discarded at its first impact)
        let watched = fc.is_some_and(|f| d.t_end > f.t);
        GraspRecord {
            impact: fc.map_or_else(ImpactRecord::default, |f| ImpactRecord::of(f.t, f.phalanx, &f.impact)),
            theta2_first_contact: fc.map(|f| f.theta2),
            min_force_margin: fin(d.min_force_margin).filter(|_| watched),
            static_force_margin: fin(d.static_force_margin),
            t_stab: d.t_stab,
            f_stab_1: d.t_stab.map(|_| d.f_end[0]),
            f_stab_2: d.t_stab.map(|_| d.f_end[1]),
            fstar_1: fin(d.fstar[0]),
            fstar_2: fin(d.fstar[1]),
            max_qdd_end: fin(d.max_qdd_end),
            work: WorkRecord::of(&d.stats, d.rhs_evals, d.events, d.cpu_s),
            knuckle_contact: Some(d.knuckle_flag),
            outcome: Some(d.outcome),
            impact_ok: d.impact_ok,
            fold_ok: d.fold_ok,
            // failed where either part failed; passed only where the hand force was watched
            force_ok: if d.t_force_violation.is_some() || d.static_force_margin < 0.0 {
                Some(false)
            } else {
                watched.then_some(true)
            },
            t_end: Some(d.t_end),
        }
    }
}

/// The offset scene's hand forces (`offset_scene`, present only when stage 3 ran in the
/// offset scene).
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
            // unknown (null) when the scene never reached an end state, not "false"
            recentres: fin(o.hand_end[0]).map(|h| h * o.x_off < 0.0),
        }
    }
}

/// The free scene's measurement (`free_scene`, MODEL.md §14.4; present only when stage 3
/// ran in the free scene, its values all `null` when the free scene itself did not run).
/// The verdict flags are `null` when the run ended before t_obs (nothing observed).
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
    /// Largest |a_x|: the axis leaning along the palm (sine of the tilt about y).
    pub object_max_tilt_y: Option<f64>,
    /// Largest spin about the vertical, 2|q_z| (rad, small-angle).
    pub object_max_spin: Option<f64>,
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
    pub end: Option<FreeEnd>,
    /// Time the free scene reached (s).
    pub t_end: Option<f64>,
    /// The first phalanx contact of the fingers as this scene's object is hit.
    #[serde(flatten)]
    pub impact: ImpactRecord,
    /// The simulation's work.
    #[serde(flatten)]
    pub work: WorkRecord,
    /// Partial evaluations of the block Jacobian.
    pub jac_block_evals: Option<u64>,
    /// Total energy at the start and at the end (J).
    pub energy: Option<[f64; 2]>,
    /// Largest energy increase between two consecutive accepted states (J; ≈ 0).
    pub max_energy_rise: Option<f64>,
}

impl FreeSceneRecord {
    /// Flatten a result (None → all null).
    pub fn from_result(r: Option<&FreeResult>) -> Self {
        let Some(r) = r else { return Self::default() };
        let seen = |v: bool| r.end.observed().then_some(v);
        // measured values of a scene that never started are not zeros but unknown
        let ran = |v: f64| r.end.ran().then_some(v);
        let impact = match (r.first_contact_t, r.first_contact_phalanx, &r.first_impact) {
            (Some(t), Some(ph), Some(i)) => ImpactRecord::of(t, ph, i),
            _ => ImpactRecord::default(),
        };
        FreeSceneRecord {
            object_max_displacement: ran(r.object_max_displacement),
            object_max_dx: ran(r.object_max_dx),
            object_max_dy: ran(r.object_max_dy),
            object_max_tilt_deg: ran(r.object_max_tilt_deg),
            object_max_tilt_y: ran(r.object_max_tilt_y),
            object_max_spin: ran(r.object_max_spin),
            object_final_displacement: ran(r.object_final_displacement),
            object_final_tilt_deg: ran(r.object_final_tilt_deg),
            object_peak_e_trans: ran(r.object_peak_e_trans),
            object_peak_e_rot: ran(r.object_peak_e_rot),
            moved: seen(r.moved),
            toppled: seen(r.toppled),
            escaped: seen(r.escaped),
            rim_contact: r.end.ran().then_some(r.rim_contact),
            end: Some(r.end),
            t_end: Some(r.t_end),
            impact,
            work: WorkRecord::of(&r.stats, r.rhs_evals, r.events, r.cpu_s),
            jac_block_evals: Some(r.jac_block_evals),
            energy: r.energy.iter().all(|e| e.is_finite()).then_some(r.energy),
            max_energy_rise: ran(r.max_energy_rise),
        }
    }
}
