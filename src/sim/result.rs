//! What a grasp simulation takes and gives: options, the outcome, the stage-3 results of
//! the centred scene, trajectory samples.

use super::criteria::Impact;
use super::integrate::Stats;
use serde::Serialize;
use std::fmt;

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Method {
    /// Radau IIA order 5 (default; stiff, L-stable, stiffly accurate).
    Radau5,
    /// TR-BDF2 (stiff, L-stable, order 2; the thesis' method).
    TrBdf2,
    /// Dormand–Prince 5(4) (explicit; for comparison only).
    Dopri5,
}

/// Pipeline mode stops at the first violated criterion; diagnostic mode runs to t_stab or t_max.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Mode {
    /// Stop at the first violated criterion.
    Pipeline,
    /// Always run to t_stab (or t_max), reporting every criterion.
    Diagnostic,
}

/// Simulation options.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SimOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance on angles (rad) and rates (rad/s).
    pub atol: f64,
    /// Budget of accepted + rejected steps.
    pub max_steps: u64,
    /// Pipeline or diagnostic.
    pub mode: Mode,
    /// Method.
    pub method: Method,
    /// Record a trajectory at accepted steps.
    pub record: bool,
    /// Also sample a uniform grid with this step (s) when recording.
    pub grid_dt: Option<f64>,
    /// Contacts with the object (false: the fingers close on nothing — a diagnostic scene
    /// for the linkage alone; no compliant equilibrium, no stability).
    pub contacts: bool,
    /// Print every located event to stderr (a debugging aid).
    pub trace: bool,
}

impl SimOptions {
    /// Pipeline-mode options with Radau IIA.
    pub fn pipeline(rtol: f64, atol: f64, max_steps: u64) -> Self {
        SimOptions {
            rtol,
            atol,
            max_steps,
            mode: Mode::Pipeline,
            method: Method::Radau5,
            record: false,
            grid_dt: None,
            contacts: true,
            trace: false,
        }
    }
    /// Diagnostic-mode options with Radau IIA.
    pub fn diagnostic(rtol: f64, atol: f64, max_steps: u64) -> Self {
        SimOptions { mode: Mode::Diagnostic, ..Self::pipeline(rtol, atol, max_steps) }
    }
}

/// Maximum number of events before the simulation is aborted (§8.7).
pub const MAX_EVENTS: u32 = 20_000;

/// How a grasp simulation ended, or the first criterion it violated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DynOutcome {
    /// All criteria hold and stability was reached.
    Stable,
    /// Impact energy above the limit at the first contact.
    ImpactEnergy,
    /// Distal fold above fold_max at the first contact.
    Fold,
    /// Filtered hand force left the stability region.
    ForceCriterion,
    /// The static hand force F⁰_hand violates the force criterion.
    StaticForceLimit,
    /// E_ex did not fall below η U_min by t_max.
    NoStability,
    /// |sin q13| fell to 1e-3.
    Singular,
    /// The linkage could not be assembled along the trajectory.
    DgmFailure,
    /// More than 20 000 events.
    Aborted,
    /// More than max_steps steps.
    StepBudget,
    /// The step size underflowed.
    StepTooSmall,
    /// The open finger penetrates the object at t = 0.
    InitialPenetration,
    /// The compliant equilibrium of §8.9 was not found.
    NoEquilibrium,
}

impl fmt::Display for DynOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            DynOutcome::Stable => "stable",
            DynOutcome::ImpactEnergy => "impact criterion: first impact energy above the limit",
            DynOutcome::Fold => "spring validity: distal fold at first contact above the limit",
            DynOutcome::ForceCriterion => "force criterion: filtered hand force outside the stability region",
            DynOutcome::StaticForceLimit => "force criterion: static hand force outside the stability region",
            DynOutcome::NoStability => "no stability by t_max",
            DynOutcome::Singular => "singular configuration during the grasp (|sin q13| <= 1e-3)",
            DynOutcome::DgmFailure => "linkage not mountable during the grasp",
            DynOutcome::Aborted => "aborted: more than 20000 events",
            DynOutcome::StepBudget => "aborted: step budget exhausted",
            DynOutcome::StepTooSmall => "aborted: step size underflow",
            DynOutcome::InitialPenetration => "open finger penetrates the object at t = 0",
            DynOutcome::NoEquilibrium => "compliant static equilibrium not found",
        };
        f.write_str(s)
    }
}

/// The first contact onset and its impact criterion (§9.1–9.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FirstContact {
    /// Time of onset (s).
    pub t: f64,
    /// 1 = proximal, 2 = distal.
    pub phalanx: u8,
    /// Impact energies.
    pub impact: Impact,
    /// θ2 at onset (rad).
    pub theta2: f64,
}

/// Stage-3 results.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicsResult {
    /// First violated criterion (pipeline) or, in diagnostic mode, the first in time; `Stable` if none.
    pub outcome: DynOutcome,
    /// First contact.
    pub first: Option<FirstContact>,
    /// Impact criterion holds (None: no contact).
    pub impact_ok: Option<bool>,
    /// Fold criterion holds.
    pub fold_ok: Option<bool>,
    /// Min of the filtered-force margin over [0, end] (N).
    pub min_force_margin: f64,
    /// Time of the first force-criterion violation.
    pub t_force_violation: Option<f64>,
    /// Margin of the static hand force F⁰_hand (N).
    pub static_force_margin: f64,
    /// R_area (N).
    pub r_area: f64,
    /// Time to stability (s).
    pub t_stab: Option<f64>,
    /// Normal forces at t_stab (or at the end).
    pub f_end: [f64; 2],
    /// Compliant equilibrium forces f*.
    pub fstar: [f64; 2],
    /// V*.
    pub v_star: f64,
    /// η U_min.
    pub threshold: f64,
    /// E_ex at the end.
    pub e_ex_end: f64,
    /// max_k |q̈_k| at the end (diagnostic of §9.4).
    pub max_qdd_end: f64,
    /// Time at which the simulation ended.
    pub t_end: f64,
    /// Number of events processed.
    pub events: u32,
    /// Integrator counters.
    pub stats: Stats,
    /// RHS evaluations including event location.
    pub rhs_evals: u64,
    /// CPU (wall) seconds of the simulation.
    pub cpu_s: f64,
    /// A knuckle (O22 cap) contact was seen (double-counted force, §8.5).
    pub knuckle_flag: bool,
    /// Time of the first onset of each phalanx (proximal, distal), if it touched.
    pub onsets: [Option<f64>; 2],
}

impl DynamicsResult {
    /// Violation (§10) when the outcome discards the design; `None` when stable.
    pub fn discard_violation(&self) -> Option<f64> {
        let v = match self.outcome {
            DynOutcome::Stable => return None,
            DynOutcome::ImpactEnergy => self.first.map(|f| f.impact.e_cyl / f.impact.e_lim - 1.0).unwrap_or(1.0),
            DynOutcome::Fold => self.first.map(|f| f.theta2.to_degrees() - 5.0).unwrap_or(1.0),
            DynOutcome::ForceCriterion | DynOutcome::StaticForceLimit => {
                -self.min_force_margin.min(self.static_force_margin) / self.r_area
            }
            DynOutcome::NoStability => self.e_ex_end / self.threshold,
            _ => 1e3,
        };
        Some(if v.is_finite() { v.max(0.0) } else { 1e3 })
    }
}

/// One trajectory sample (finger 1, local frame; finger 2 is its mirror image).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// q11, q21 (rad).
    pub q: [f64; 2],
    /// q̇11, q̇21 (rad/s).
    pub qd: [f64; 2],
    /// θ2 (rad).
    pub theta2: f64,
    /// Penetrations δ (m), proximal and distal.
    pub delta: [f64; 2],
    /// Normal forces (N).
    pub normal: [f64; 2],
    /// Friction forces (N, on the finger along t_c).
    pub friction: [f64; 2],
    /// Raw hand force F_hand,y (N).
    pub hand_fy: f64,
    /// Filtered hand force F̄_y (N).
    pub filtered_fy: f64,
    /// Total energy E (J).
    pub energy: f64,
    /// E_ex = E − V* (J).
    pub energy_excess: f64,
}

/// A recorded trajectory.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Samples at accepted steps and events, in time order.
    pub samples: Vec<Sample>,
    /// Samples on the uniform grid, if requested.
    pub grid: Vec<Sample>,
}
