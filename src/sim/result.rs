//! What a simulation gives: how a grasp ended ([`DynOutcome`]) and its stage-3 results
//! ([`DynamicsResult`]), how the free scene ended ([`FreeEnd`]), and the samples a
//! [`Sink`](super::Sink) receives ([`Sample`], [`PoseSample`]; [`Trajectory`] keeps them).

use super::criteria::Impact;
use super::integrate::Stats;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// Maximum number of events before the simulation is aborted (§8.7).
pub const MAX_EVENTS: u32 = 20_000;

/// How a grasp simulation ended, or the first criterion it violated (in JSON: its text,
/// one of a fixed set).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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
    /// More than [`MAX_EVENTS`] events.
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

impl DynOutcome {
    /// Every outcome.
    pub const ALL: [DynOutcome; 13] = [
        DynOutcome::Stable,
        DynOutcome::ImpactEnergy,
        DynOutcome::Fold,
        DynOutcome::ForceCriterion,
        DynOutcome::StaticForceLimit,
        DynOutcome::NoStability,
        DynOutcome::Singular,
        DynOutcome::DgmFailure,
        DynOutcome::Aborted,
        DynOutcome::StepBudget,
        DynOutcome::StepTooSmall,
        DynOutcome::InitialPenetration,
        DynOutcome::NoEquilibrium,
    ];
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
            DynOutcome::Aborted => return write!(f, "aborted: more than {MAX_EVENTS} events"),
            DynOutcome::StepBudget => "aborted: step budget exhausted",
            DynOutcome::StepTooSmall => "aborted: step size underflow",
            DynOutcome::InitialPenetration => "open finger penetrates the object at t = 0",
            DynOutcome::NoEquilibrium => "compliant static equilibrium not found",
        };
        f.write_str(s)
    }
}

/// Serialise an enum of a fixed set of texts as its text.
fn as_text<T: fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

/// Deserialise one of `all` from its text.
fn from_text<'de, T: fmt::Display + Copy, D: Deserializer<'de>>(all: &[T], d: D) -> Result<T, D::Error> {
    let text = String::deserialize(d)?;
    all.iter()
        .copied()
        .find(|v| v.to_string() == text)
        .ok_or_else(|| serde::de::Error::custom(format!("unknown value {text:?}")))
}

impl Serialize for DynOutcome {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        as_text(self, s)
    }
}

impl<'de> Deserialize<'de> for DynOutcome {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        from_text(&Self::ALL, d)
    }
}

/// How the free scene's run ended (in JSON: `t_obs`, or the text of why it ended early).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FreeEnd {
    /// It reached t_end = min(t_max, t_obs): the motion was observed.
    Observed,
    /// A finger reached |sin q13| = 1e-3.
    Singular,
    /// An open finger penetrates the object at t = 0.
    InitialPenetration,
    /// The step budget was spent.
    StepBudget,
    /// The step size underflowed.
    StepTooSmall,
    /// A linkage could not be assembled along the trajectory.
    NotMountable,
    /// More than [`MAX_EVENTS`] events.
    TooManyEvents,
    /// The run stopped before t_obs otherwise.
    Stopped,
}

impl FreeEnd {
    /// Every end.
    pub const ALL: [FreeEnd; 8] = [
        FreeEnd::Observed,
        FreeEnd::Singular,
        FreeEnd::InitialPenetration,
        FreeEnd::StepBudget,
        FreeEnd::StepTooSmall,
        FreeEnd::NotMountable,
        FreeEnd::TooManyEvents,
        FreeEnd::Stopped,
    ];
    /// The run observed the object to t_end.
    pub fn observed(self) -> bool {
        self == FreeEnd::Observed
    }
}

impl fmt::Display for FreeEnd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            FreeEnd::Observed => "t_obs",
            FreeEnd::Singular => "singular configuration during the grasp (|sin q13| <= 1e-3)",
            FreeEnd::InitialPenetration => "open finger penetrates the object at t = 0",
            FreeEnd::StepBudget => "aborted: step budget exhausted",
            FreeEnd::StepTooSmall => "aborted: step size underflow",
            FreeEnd::NotMountable => "linkage not mountable during the grasp",
            FreeEnd::TooManyEvents => return write!(f, "aborted: more than {MAX_EVENTS} events"),
            FreeEnd::Stopped => "the simulation ended before t_obs",
        };
        f.write_str(s)
    }
}

impl Serialize for FreeEnd {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        as_text(self, s)
    }
}

impl<'de> Deserialize<'de> for FreeEnd {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        from_text(&Self::ALL, d)
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

/// A sample of the free scene's object pose and fingers (for `--csv` and recordings).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PoseSample {
    /// Time (s).
    pub t: f64,
    /// Position of G (m).
    pub g: [f64; 3],
    /// Orientation (w, x, y, z).
    pub q: [f64; 4],
    /// Tilt (rad).
    pub tilt: f64,
    /// Active angles (q11, q21) of finger 1 and finger 2.
    pub fingers: [f64; 4],
    /// Total energy (J).
    pub energy: f64,
}

/// A recorded trajectory.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Samples at accepted steps and events, in time order.
    pub samples: Vec<Sample>,
    /// Samples on the uniform grid, if requested.
    pub grid: Vec<Sample>,
}
