//! What a simulation gives: how a grasp ended ([`DynOutcome`]) and its stage-3 results
//! ([`DynamicsResult`]), how the free scene ended ([`FreeEnd`]), and the samples a
//! [`Sink`](super::Sink) receives ([`Sample`], [`PoseSample`]; [`Trajectory`] keeps them).

use super::criteria::Impact;
use super::integrate::Stats;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// Maximum number of events before the simulation is aborted (§8.7).
pub const MAX_EVENTS: u32 = 20_000;

/// An enum whose variants each stand for one fixed text: its `Display`, and its JSON form
/// (serialised as the text, read back from it); `ALL` lists the variants.
macro_rules! text_enum {
    ($(#[$m:meta])* pub enum $name:ident { $($(#[$vm:meta])* $v:ident => $text:expr,)* }) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum $name {
            $($(#[$vm])* $v,)*
        }

        impl $name {
            /// Every variant.
            pub const ALL: &'static [$name] = &[$($name::$v,)*];
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self {
                    $($name::$v => f.write_fmt($text),)*
                }
            }
        }

        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_str(self)
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let text = String::deserialize(d)?;
                Self::ALL
                    .iter()
                    .copied()
                    .find(|v| v.to_string() == text)
                    .ok_or_else(|| serde::de::Error::custom(format!("unknown value {text:?}")))
            }
        }
    };
}

text_enum! {
    /// How a grasp simulation ended, or the first criterion it violated (in JSON: its text).
    pub enum DynOutcome {
        /// All criteria hold and stability was reached.
        Stable => format_args!("stable"),
        /// Impact energy above the limit at the first contact.
        ImpactEnergy => format_args!("impact criterion: first impact energy above the limit"),
        /// Distal fold above fold_max at the first contact.
        Fold => format_args!("spring validity: distal fold at first contact above the limit"),
        /// Filtered hand force left the stability region.
        ForceCriterion => format_args!("force criterion: filtered hand force outside the stability region"),
        /// The static hand force F⁰_hand violates the force criterion.
        StaticForceLimit => format_args!("force criterion: static hand force outside the stability region"),
        /// E_ex did not fall below η U_min by t_max.
        NoStability => format_args!("no stability by t_max"),
        /// |sin q13| fell to 1e-3.
        Singular => format_args!("singular configuration during the grasp (|sin q13| <= 1e-3)"),
        /// The linkage could not be assembled along the trajectory.
        DgmFailure => format_args!("linkage not mountable during the grasp"),
        /// More than [`MAX_EVENTS`] events.
        Aborted => format_args!("aborted: more than {MAX_EVENTS} events"),
        /// More than max_steps steps.
        StepBudget => format_args!("aborted: step budget exhausted"),
        /// The step size underflowed.
        StepTooSmall => format_args!("aborted: step size underflow"),
        /// The open finger penetrates the object at t = 0.
        InitialPenetration => format_args!("open finger penetrates the object at t = 0"),
        /// The compliant equilibrium of §8.9 was not found.
        NoEquilibrium => format_args!("compliant static equilibrium not found"),
        /// Offset scene: the static grasp of the object at its offset does not exist
        /// (MODEL.md §6.7: a finger has no closed pose there, or its static forces are not
        /// admissible), so nothing is simulated.
        NoOffsetGrasp => format_args!("no static grasp of the object at its offset"),
    }
}

text_enum! {
    /// How the free scene's run ended (in JSON: `t_obs`, or the text of why it ended early).
    pub enum FreeEnd {
        // the ends the grasp scenes share say what [`DynOutcome`]'s say, in its words
        /// It reached t_end = min(t_max, t_obs): the motion was observed.
        Observed => format_args!("t_obs"),
        /// A finger reached |sin q13| = 1e-3.
        Singular => format_args!("{}", DynOutcome::Singular),
        /// An open finger penetrates the object at t = 0.
        InitialPenetration => format_args!("{}", DynOutcome::InitialPenetration),
        /// The step budget was spent.
        StepBudget => format_args!("{}", DynOutcome::StepBudget),
        /// The step size underflowed.
        StepTooSmall => format_args!("{}", DynOutcome::StepTooSmall),
        /// A linkage could not be assembled along the trajectory.
        NotMountable => format_args!("{}", DynOutcome::DgmFailure),
        /// More than [`MAX_EVENTS`] events.
        TooManyEvents => format_args!("{}", DynOutcome::Aborted),
        /// The run stopped before t_obs otherwise.
        Stopped => format_args!("the simulation ended before t_obs"),
    }
}

impl FreeEnd {
    /// The run observed the object to t_end.
    pub fn observed(self) -> bool {
        self == FreeEnd::Observed
    }

    /// The scene ran at all: it did not end before its first step (an open finger in the
    /// object at t = 0), so its measured values (displacement, tilt, energies) mean something.
    pub fn ran(self) -> bool {
        self != FreeEnd::InitialPenetration
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

/// One finger's state and contacts at a sample, in its local frame (finger 2's: mirrored).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FingerSample {
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
}

impl FingerSample {
    /// Every value with `f` applied (e.g. a recording's rounding).
    pub fn map(&self, f: impl Fn(f64) -> f64) -> FingerSample {
        FingerSample {
            q: self.q.map(&f),
            qd: self.qd.map(&f),
            theta2: f(self.theta2),
            delta: self.delta.map(&f),
            normal: self.normal.map(&f),
            friction: self.friction.map(&f),
        }
    }

    /// The values in the order q11, q21, q̇11, q̇21, θ2, δ (proximal, distal), F_n (same),
    /// F_t (same): the order of a trajectory's finger columns.
    pub fn values(&self) -> [f64; 11] {
        let [q, qd, d, n, f] = [self.q, self.qd, self.delta, self.normal, self.friction];
        [q[0], q[1], qd[0], qd[1], self.theta2, d[0], d[1], n[0], n[1], f[0], f[1]]
    }

    /// The finger of [`FingerSample::values`] `v`.
    pub fn from_values(v: [f64; 11]) -> FingerSample {
        FingerSample {
            q: [v[0], v[1]],
            qd: [v[2], v[3]],
            theta2: v[4],
            delta: [v[5], v[6]],
            normal: [v[7], v[8]],
            friction: [v[9], v[10]],
        }
    }
}

/// One trajectory sample: finger 1 in its local frame, the hand force and the energy of the
/// scene; finger 2 is finger 1's mirror image in the centred scene, and moves on its own in
/// the offset scene (`finger2`).
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
    /// Finger 2's own state and contacts (its mirrored frame) where it is not finger 1's
    /// mirror image (the offset scene); `None` in the centred scene. Read back from an
    /// offset recording of session 36 it holds the angles only (the rest NaN), and from an
    /// older one it is `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finger2: Option<FingerSample>,
}

impl Sample {
    /// Finger 1's part of the sample.
    pub fn finger1(&self) -> FingerSample {
        let s = self;
        FingerSample { q: s.q, qd: s.qd, theta2: s.theta2, delta: s.delta, normal: s.normal, friction: s.friction }
    }

    /// Every value of the sample with `f` applied (finger 2's too).
    pub fn map(&self, f: impl Fn(f64) -> f64) -> Sample {
        let f1 = self.finger1().map(&f);
        Sample {
            t: self.t,
            q: f1.q,
            qd: f1.qd,
            theta2: f1.theta2,
            delta: f1.delta,
            normal: f1.normal,
            friction: f1.friction,
            hand_fy: f(self.hand_fy),
            filtered_fy: f(self.filtered_fy),
            energy: f(self.energy),
            energy_excess: f(self.energy_excess),
            finger2: self.finger2.map(|g| g.map(&f)),
        }
    }
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
    /// Penetration δ of the phalanx contacts (m): finger 1 proximal, distal, finger 2
    /// proximal, distal (≤ 0: apart).
    pub delta: [f64; 4],
    /// Their normal forces (N), in the same order.
    pub normal: [f64; 4],
}

/// A recorded trajectory.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Samples at accepted steps and events, in time order.
    pub samples: Vec<Sample>,
    /// Samples on the uniform grid, if requested.
    pub grid: Vec<Sample>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The free scene's ends shared with the grasp scenes keep their words (JSON, CSV and
    /// recordings written before read back): each is the text written by earlier versions.
    #[test]
    fn free_ends_keep_their_words() {
        let words = [
            (FreeEnd::Observed, "t_obs"),
            (FreeEnd::Singular, "singular configuration during the grasp (|sin q13| <= 1e-3)"),
            (FreeEnd::InitialPenetration, "open finger penetrates the object at t = 0"),
            (FreeEnd::StepBudget, "aborted: step budget exhausted"),
            (FreeEnd::StepTooSmall, "aborted: step size underflow"),
            (FreeEnd::NotMountable, "linkage not mountable during the grasp"),
            (FreeEnd::TooManyEvents, "aborted: more than 20000 events"),
            (FreeEnd::Stopped, "the simulation ended before t_obs"),
        ];
        assert_eq!(words.len(), FreeEnd::ALL.len());
        for (end, word) in words {
            assert_eq!(end.to_string(), word);
            assert_eq!(serde_json::from_value::<FreeEnd>(serde_json::json!(word)).unwrap(), end);
        }
    }
}
