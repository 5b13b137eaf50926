//! The ONE typed record of an evaluation (MODEL.md §10), from which every output is
//! derived: `evaluate`/`simulate --json`, the run's CSV rows, the recording's `/designs`
//! messages, checkpoints, replay's comparison and sweeps. A sub-record per stage and per
//! scene (flat keys in JSON, snake_case; `null` = not computed), enums where a value is
//! one of a set (the scene, how a simulation ended, what discarded the design).

use super::objectives::Objectives;
use super::record_robust::RobustRecord;
use super::scene_record::{fin, FreeSceneRecord, GraspRecord, OffsetSceneRecord};
use super::stages::{Cause, Evaluation, Reason};
use crate::model::{ClosedPoseError, GeomError, OffsetFailure, SweepFailure};
use crate::params::{DesignParameters, ForceModel, SceneKind};
use crate::sim::Method;
use serde::{Deserialize, Serialize};

/// The evaluation record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The design (always known; ψ in degrees).
    #[serde(flatten)]
    pub design: DesignParameters,
    /// Stages 0–1: the finger.
    #[serde(flatten)]
    pub kinematics: KinematicsRecord,
    /// Stage 2: statics, form closure, the static objectives.
    #[serde(flatten)]
    pub statics: StaticsRecord,
    /// Stage 3: the grasp.
    #[serde(flatten)]
    pub grasp: GraspRecord,
    /// Stage 3 in the offset scene: the hand forces (absent in the other scenes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset_scene: Option<OffsetSceneRecord>,
    /// Stage 3 in the free scene: the measurement (absent in the other scenes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_scene: Option<FreeSceneRecord>,
    /// The verdict.
    #[serde(flatten)]
    pub verdict: Verdict,
    /// The scene stage 3 ran in (null: it did not run).
    #[serde(default)]
    pub scene: Option<SceneKind>,
    /// The object offset of that scene (m).
    #[serde(default)]
    pub x_off: Option<f64>,
    /// A robust problem's evaluation: aggregated objectives, per object P(stay), per
    /// scenario what happened (absent for a single-object problem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<RobustRecord>,
}

/// The derived lengths (m) as the outputs report them: l11, l12, l22 when stages 0–1 built
/// the finger, and l_hand.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Derived {
    /// l11.
    pub l11: Option<f64>,
    /// l12.
    pub l12: Option<f64>,
    /// l22.
    pub l22: Option<f64>,
    /// l_hand.
    pub l_hand: f64,
}

/// Stages 0–1: the finger built from the design (every value computed before a discard).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KinematicsRecord {
    /// l_hand = b + 2 t22 + 2 l21 (m; always known).
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
    /// Minimum singularity margin (deg); set iff stages 0–1 passed.
    pub min_margin_deg: Option<f64>,
}

/// Stage 2 (every value computed before a discard).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StaticsRecord {
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
    /// The offset scan admits the centred object (x_off = 0): max_offset is computed
    /// (MODEL.md §6.7; false: max_offset is null, as in the CSVs).
    pub form_closed: Option<bool>,
    /// Objective 1 (m); null when not computed, also when not form closed at 0 (the
    /// optimiser ranks such a design with −Δ_off internally, a placeholder never reported).
    pub max_offset: Option<f64>,
    /// What ended the offset scan (null if off_max was reached).
    pub max_offset_ended_by: Option<OffsetEnd>,
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
    /// Force model of alpha and mean_force.
    pub force_model: Option<ForceModel>,
}

/// The verdict (MODEL.md §10).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Verdict {
    /// No stage discarded the design.
    pub feasible: bool,
    /// The stage that discarded it (0–3).
    pub failed_stage: Option<u8>,
    /// Why, in words.
    pub reason: Option<String>,
    /// Violation magnitude (§10 units; larger = worse).
    pub violation: Option<f64>,
    /// What discarded it, as a class.
    pub cause: Option<Cause>,
}

/// The record of a simulation (`gripopt simulate --json`): the evaluation record in the
/// scene simulated, and the integration method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulationRecord {
    /// The evaluation record.
    #[serde(flatten)]
    pub record: Record,
    /// The integration method.
    pub method: Method,
}

/// The record of `gripopt evaluate --json` (and of the Python package's `Problem.record`):
/// the evaluation record and, where its grasp simulation uses another method than RADAU5
/// (a problem's `solver.method = "auto"`, `"trbdf2"`, `"dopri5"`), that method, so that the
/// work counters (`steps`, `jac_evals`, …) say which method did the work. A problem without
/// `solver.method` (or with `"radau5"`), and stages 0–2 only, give the record alone, as before
/// the key existed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvaluationRecord<'a> {
    /// The evaluation record.
    #[serde(flatten)]
    pub record: &'a Record,
    /// The integration method of the grasp simulation, where it is not RADAU5.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
}

impl<'a> EvaluationRecord<'a> {
    /// `record` of an evaluation with `method`, through stage 3 (`dynamics`) or not.
    pub fn new(record: &'a Record, method: Method, dynamics: bool) -> Self {
        EvaluationRecord { record, method: (dynamics && !method.is_default()).then_some(method) }
    }
}

impl Record {
    /// This record with the parts a record of scene `kind` holds beside the grasp, empty
    /// where it has none (the offset scene's `offset_scene`, the free scene's `free_scene`):
    /// the keys a sweep of that scene tabulates.
    pub fn with_scene_parts(mut self, kind: SceneKind) -> Self {
        match kind {
            SceneKind::Offset => self.offset_scene = Some(self.offset_scene.unwrap_or_default()),
            SceneKind::Free => self.free_scene = Some(self.free_scene.unwrap_or(FreeSceneRecord::from_result(None))),
            SceneKind::Centred => {}
        }
        self
    }

    /// The record of an evaluation.
    pub fn from_eval(ev: &Evaluation) -> Self {
        let x = &ev.design;
        let applies = |kind: SceneKind| ev.scene == Some(kind);
        Record {
            design: DesignParameters { l21: x.l21, b: x.b, t22: x.t22, r: x.r, p: x.p, psi_deg: x.psi.to_degrees() },
            kinematics: KinematicsRecord::from_eval(ev),
            statics: StaticsRecord::from_eval(ev),
            grasp: GraspRecord::from_result(ev.dynamics.as_ref()),
            offset_scene: applies(SceneKind::Offset)
                .then(|| ev.offset.as_ref().map(OffsetSceneRecord::from_result))
                .map(Option::unwrap_or_default),
            free_scene: applies(SceneKind::Free).then(|| FreeSceneRecord::from_result(ev.free.as_ref())),
            verdict: Verdict {
                feasible: ev.feasible(),
                failed_stage: ev.discard.map(|d| d.stage),
                reason: ev.discard.map(|d| d.reason.to_string()),
                violation: ev.discard.map(|d| d.violation),
                cause: ev.discard.and_then(|d| d.reason.cause()),
            },
            scene: ev.scene,
            x_off: ev.scene.map(|_| ev.x_off),
            robust: None,
        }
    }
}

impl KinematicsRecord {
    fn from_eval(ev: &Evaluation) -> Self {
        let x = &ev.design;
        // MODEL.md §10: every value computed before a discard is reported, the rest null
        let f = ev.kin.map(|k| k.finger).or(ev.partial.finger);
        KinematicsRecord {
            l_hand: x.l_hand(),
            // l11 and l22 follow from the design (stage 0 computes them before any check)
            l11: f.map(|f| f.l11).or_else(|| fin(x.p * x.l21)),
            l12: f.map(|f| f.l12),
            l22: f.map(|f| f.l22).or_else(|| fin(x.r * (x.p * x.l21))),
            q11_0: f.map(|f| f.open.q11),
            q21_0: f.map(|f| f.open.q21),
            q12_0: f.map(|f| f.open.q12),
            q22_0: f.map(|f| f.open.q22),
            q13_0: f.map(|f| f.open.q13),
            gamma: f.map(|f| f.gamma),
            sigma: f.map(|f| f.sigma),
            masses: f.map(|f| f.mass.m),
            // a sweep that discarded the design computed its margin too (the reason prints it)
            min_margin_deg: ev.kin.map(|k| k.sweep.min_margin.to_degrees()).or_else(|| match ev.discard?.reason {
                Reason::Sweep(SweepFailure::Margin(s)) => Some(s.min_margin.to_degrees()),
                _ => None,
            }),
        }
    }
}

impl StaticsRecord {
    fn from_eval(ev: &Evaluation) -> Self {
        let st = ev.statics;
        let spring = st.map(|s| [s.tau_s_min, s.tau_s0]).or(ev.partial.spring);
        // the grasp: from stage 2's result, or from the values it computed before a discard
        let g = st.map(|s| s.grasp).or(ev.partial.grasp);
        let (theta, k) = (g.map(|g| g.theta), g.map(|g| g.k));
        let (f0, fmu) = (g.map(|g| g.f0), g.map(|g| g.fmu));
        let (hand0, hand_mu) = (g.map(|g| g.hand0), g.map(|g| g.hand_mu));
        StaticsRecord {
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
            form_closed: st.map(|s| s.max_offset >= 0.0),
            max_offset: st.map(|s| s.max_offset).filter(|m| *m >= 0.0),
            max_offset_ended_by: st.and_then(|s| s.offset_ended_by.map(OffsetEnd::from)),
            alpha: st.and_then(|s| fin(s.alpha)),
            mean_force: st.map(|s| s.mean_force),
            alpha_mu: st.and_then(|s| fin(s.alpha_mu)),
            mean_force_mu: st.map(|s| s.mean_force_mu),
            alpha_0: st.and_then(|s| fin(s.alpha_0)),
            mean_force_0: st.map(|s| s.mean_force_0),
            force_model: st.map(|s| s.force_model),
        }
    }
}

impl Record {
    /// Objectives in their natural sense: max_offset (m; None also for a design not form
    /// closed at 0), α, F̃ (N), t_stab (s); None where not computed.
    pub fn objectives(&self) -> [Option<f64>; 4] {
        if let Some(r) = &self.robust {
            return r.objectives.to_array();
        }
        let st = &self.statics;
        [st.max_offset, st.alpha, st.mean_force, self.grasp.t_stab]
    }
    /// [`Record::objectives`] as the outputs report them ([`Objectives::reported`]).
    pub fn reported_objectives(&self) -> Objectives {
        Objectives::from_array(self.objectives()).reported()
    }
    /// The derived lengths l11, l12, l22 when stages 0–1 built the finger.
    pub fn lengths(&self) -> Option<[f64; 3]> {
        let k = &self.kinematics;
        let built = self.verdict.failed_stage.is_none_or(|s| s >= 2);
        built.then_some([k.l11?, k.l12?, k.l22?])
    }
    /// The derived lengths as the outputs report them ([`Record::lengths`], l_hand).
    pub fn derived(&self) -> Derived {
        let l = self.lengths();
        Derived { l11: l.map(|l| l[0]), l12: l.map(|l| l[1]), l22: l.map(|l| l[2]), l_hand: self.kinematics.l_hand }
    }
    /// Stage 3's grasp work: accepted steps and right-hand-side evaluations.
    /// For a robust design: all its simulations' (centred and free, every scenario run).
    pub fn sim_work(&self) -> Option<[u64; 2]> {
        if let Some(r) = &self.robust {
            return (r.scenarios_run > 0).then(|| [r.steps[0] + r.steps[1], r.rhs_evals[0] + r.rhs_evals[1]]);
        }
        Some([self.grasp.work.steps?, self.grasp.work.rhs_evals?])
    }
    /// Form closed at the centred object (the offset scan admits x_off = 0, MODEL.md §6.7).
    pub fn form_closed(&self) -> Option<bool> {
        self.statics.form_closed
    }
}

impl Record {
    /// The object of a robust design's discard ([`RobustRecord::failed_object`]); None for a
    /// single-object problem's record and for a feasible design.
    pub fn failed_object(&self) -> Option<usize> {
        let v = &self.verdict;
        self.robust.as_ref()?.failed_object(v.failed_stage, v.cause)
    }
}

/// What ended the offset scan of §6.7 (the record's `max_offset_ended_by`), written as its
/// text (the model's `OffsetFailure::reason`: "finger 2: distal cannot reach the object",
/// "force positiveness violated (min force -0.0123 N)", …). A force is held as the text
/// writes it (4 decimals), so an end read back equals the one computed; a text this gripopt
/// does not write (a record of an older one) is kept as it is.
#[derive(Debug, Clone)]
pub enum OffsetEnd {
    /// Finger `finger` (1 or 2) has no closed pose at the offset.
    NoClosedPose {
        /// 1 or 2.
        finger: usize,
        /// Why.
        why: ClosedPoseError,
    },
    /// Singular static force system.
    SingularForces,
    /// A force of f⁰ or f^μ is ≤ 0: the most negative (N).
    ForceNotPositive(f64),
    /// F^μ_hand,y ≥ 0: its value (N).
    PalmForceNotPositive(f64),
    /// Not form closed.
    NotFormClosed,
    /// A text of an older gripopt, kept verbatim.
    Other(String),
}

/// Every closed-pose failure (reading a `NoClosedPose` text back).
const CLOSED_POSE_ERRORS: [ClosedPoseError; 9] = [
    ClosedPoseError::OverlapsBase,
    ClosedPoseError::ProximalOutOfRange,
    ClosedPoseError::DistalBeyondTip,
    ClosedPoseError::DistalCannotReach,
    ClosedPoseError::Geometry(GeomError::InvalidLength),
    ClosedPoseError::Geometry(GeomError::NoOpenPose),
    ClosedPoseError::Geometry(GeomError::NotMountable),
    ClosedPoseError::Geometry(GeomError::AssemblyModeChange),
    ClosedPoseError::Singular,
];

const MIN_FORCE: (&str, &str) = ("force positiveness violated (min force ", " N)");
const PALM_FORCE: (&str, &str) = ("palm force positiveness violated (F_y = ", " N)");

/// `v` as the text writes it (4 decimals), read back.
fn printed(v: f64) -> f64 {
    format!("{v:.4}").parse().unwrap_or(v)
}

impl From<OffsetFailure> for OffsetEnd {
    fn from(e: OffsetFailure) -> Self {
        match e {
            OffsetFailure::NoClosedPose(j, why) => OffsetEnd::NoClosedPose { finger: j + 1, why },
            OffsetFailure::SingularForces => OffsetEnd::SingularForces,
            OffsetFailure::ForceNotPositive(v) => OffsetEnd::ForceNotPositive(printed(v)),
            OffsetFailure::PalmForceNotPositive(v) => OffsetEnd::PalmForceNotPositive(printed(v)),
            OffsetFailure::NotFormClosed => OffsetEnd::NotFormClosed,
        }
    }
}

impl std::fmt::Display for OffsetEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OffsetEnd::NoClosedPose { finger, why } => write!(f, "finger {finger}: {}", why.reason()),
            OffsetEnd::SingularForces => f.write_str("singular static force system"),
            OffsetEnd::ForceNotPositive(v) => write!(f, "{}{v:.4}{}", MIN_FORCE.0, MIN_FORCE.1),
            OffsetEnd::PalmForceNotPositive(v) => write!(f, "{}{v:.4}{}", PALM_FORCE.0, PALM_FORCE.1),
            OffsetEnd::NotFormClosed => f.write_str("not form closed"),
            OffsetEnd::Other(text) => f.write_str(text),
        }
    }
}

impl std::str::FromStr for OffsetEnd {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let number = |(head, tail): (&str, &str)| s.strip_prefix(head)?.strip_suffix(tail)?.parse::<f64>().ok();
        let closed_pose = || {
            let (finger, why) = s.strip_prefix("finger ")?.split_once(": ")?;
            let finger = finger.parse().ok().filter(|f| [1, 2].contains(f))?;
            let why = CLOSED_POSE_ERRORS.into_iter().find(|e| e.reason() == why)?;
            Some(OffsetEnd::NoClosedPose { finger, why })
        };
        let end = match s {
            "singular static force system" => Some(OffsetEnd::SingularForces),
            "not form closed" => Some(OffsetEnd::NotFormClosed),
            _ => closed_pose()
                .or_else(|| number(MIN_FORCE).map(OffsetEnd::ForceNotPositive))
                .or_else(|| number(PALM_FORCE).map(OffsetEnd::PalmForceNotPositive)),
        };
        // only a text this type writes back as it was is read as its variant
        Ok(end.filter(|e| e.to_string() == s).unwrap_or_else(|| OffsetEnd::Other(s.to_string())))
    }
}

/// Two ends are the same when their texts are (a force compares as written).
impl PartialEq for OffsetEnd {
    fn eq(&self, other: &Self) -> bool {
        self.to_string() == other.to_string()
    }
}

impl Serialize for OffsetEnd {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for OffsetEnd {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        Ok(text.parse().unwrap_or_else(|never: std::convert::Infallible| match never {}))
    }
}

#[cfg(test)]
mod offset_end_tests {
    use super::{OffsetEnd, CLOSED_POSE_ERRORS};
    use crate::model::OffsetFailure;

    #[test]
    fn every_offset_failure_reads_back_as_itself_with_the_models_text() {
        let mut failures: Vec<OffsetFailure> = vec![
            OffsetFailure::SingularForces,
            OffsetFailure::NotFormClosed,
            OffsetFailure::ForceNotPositive(-0.012345678),
            OffsetFailure::ForceNotPositive(-0.0),
            OffsetFailure::ForceNotPositive(-1234.56789),
            OffsetFailure::PalmForceNotPositive(0.30000000000000004),
            OffsetFailure::PalmForceNotPositive(f64::NAN),
        ];
        for j in 0..2 {
            failures.extend(CLOSED_POSE_ERRORS.map(|e| OffsetFailure::NoClosedPose(j, e)));
        }
        for f in failures {
            let end = OffsetEnd::from(f);
            assert_eq!(end.to_string(), f.reason(), "the model's text");
            let back: OffsetEnd = serde_json::from_value(serde_json::to_value(&end).unwrap()).unwrap();
            assert!(!matches!(back, OffsetEnd::Other(_)), "{end} read as its variant");
            assert_eq!(back, end);
            assert_eq!(serde_json::to_value(&back).unwrap(), serde_json::json!(f.reason()));
        }
    }

    #[test]
    fn an_unknown_text_is_kept_as_it_is() {
        for text in [
            "scan stopped by something new",
            "finger 3: distal cannot reach the object",
            "force positiveness violated (min force -1.5 N)",
        ] {
            let end: OffsetEnd = serde_json::from_value(serde_json::json!(text)).unwrap();
            assert_eq!(end, OffsetEnd::Other(text.to_string()));
            assert_eq!(serde_json::to_value(&end).unwrap(), serde_json::json!(text));
        }
    }
}
