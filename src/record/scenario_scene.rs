//! A robust design's grasp in the run's own recording: the scenario that decided its verdict
//! ([`crate::eval::RobustRecord::deciding`]: a feasible design's worst by displacement, a
//! P(stay) failure's first failing scenario, a solver failure's aborted one), kept by the run
//! layer as a [`ScenarioScene`] and drawn in the design's window of its shard in the
//! scenario's own scene — the object at its drawn size, offset and height, the hand at the
//! scenario's height: its free scene (the object a moving frame `object`, both fingers at
//! their own angles, as `gripopt verify` draws it), or where the free scene did not run its
//! centred grasp (the object fixed, finger 2 the mirror of finger 1). Its columns go to
//! `/scenario/series` ([`ScenarioSeries`]), which scenario it is to `/designs` (`shown_scenario`,
//! with the `replay --scenario` command for any other) and to the label.

use super::entry::DesignEntry;
use super::messages::{at_precision, log_time, window_end_ns};
use super::options::Resolution;
use super::scenario_kept::{ScenarioMotion, ScenarioScene};
use super::scenario_series::ScenarioSeries;
use super::scene::{
    discarded_scene, fit_label, frames, free_fingers, free_frames, free_static_scene, scene, static_scene_with,
    verdict_after,
};
use crate::eval::Decides;
use crate::model::Finger;
use crate::params::Design;
use crate::sim::PoseSample;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use serde::{Deserialize, Serialize};

/// Which scenario a robust design's window draws (`/designs` → `shown_scenario`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShownScenario {
    /// The object's name.
    pub object: String,
    /// The scenario's index among the object's.
    pub k: u64,
    /// Why it is the one drawn: `worst displacement`, `first scenario`, `first failure`,
    /// `aborted`.
    pub why: String,
    /// What is drawn: the scenario's free scene (true) or its centred grasp (false: the free
    /// scene did not run).
    pub free_scene: bool,
    /// The free object's largest displacement in it (m; absent: not measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_displacement: Option<f64>,
    /// The object stayed in it.
    pub stays: bool,
    /// The drawn hand height offset (m).
    pub height_offset: f64,
    /// The object's drawn offset along the palm (m).
    pub x_off: f64,
    /// How to record any scenario of the design on its own.
    pub replay: String,
}

impl ScenarioScene {
    /// The `/designs` sub-record of design `d` drawing this scenario.
    pub fn shown(&self, d: &DesignEntry<'_>) -> ShownScenario {
        let (id, recorded) = (d.id, self.recorded(d));
        let (objects, per) = self.study;
        ShownScenario {
            object: self.name.clone(),
            k: self.k as u64,
            why: self.decides.as_str().into(),
            free_scene: matches!(self.motion, ScenarioMotion::Free { .. }),
            max_displacement: recorded.and_then(|s| s.max_displacement),
            stays: recorded.is_some_and(|s| s.stays),
            height_offset: self.height_offset,
            x_off: self.scene.setup.x_off,
            replay: format!(
                "gripopt replay RUN_DIR --design {id} --scenario {}:{} (any OBJECT:K of the {objects} objects, K 0 to {})",
                self.name,
                self.k,
                per.saturating_sub(1)
            ),
        }
    }

    /// The label: which scenario, why, and the design's verdict (at most the labels' length).
    fn label(&self, d: &DesignEntry<'_>) -> String {
        let why = match (self.decides, self.recorded(d).and_then(|s| s.max_displacement)) {
            (Decides::WorstDisplacement, Some(m)) => format!("worst, {:.2} mm", m * 1e3),
            _ => self.decides.as_str().to_string(),
        };
        let head = format!("{} (gen {}) {}:{} ({why});", d.id, d.generation, self.name, self.k);
        let v = &d.record.verdict;
        match (v.failed_stage, v.reason.as_deref()) {
            // the reason's object is the scenario's: named once
            (Some(stage), Some(reason)) => {
                let object = format!("object {}: ", self.name);
                fit_label(&format!("{head} stage {stage}: "), reason.strip_prefix(&object).unwrap_or(reason))
            }
            _ => fit_label("", &verdict_after(d, head)),
        }
    }

    /// This scenario's record in design `d`'s.
    fn recorded<'a>(&self, d: &DesignEntry<'a>) -> Option<&'a crate::eval::ScenarioRecord> {
        d.record.robust.as_ref()?.scenarios.iter().find(|s| (s.object, s.k) == (self.object, self.k))
    }

    /// `/scenario/series` of design `d`: the drawn simulation's kept samples at the
    /// recording's precision.
    pub fn series(&self, d: &DesignEntry<'_>, res: Resolution) -> ScenarioSeries {
        let p = |x: f64| at_precision(x, res);
        let mut m = ScenarioSeries {
            design_id: d.id,
            object: self.name.clone(),
            scenario_index: self.k as u32,
            ..Default::default()
        };
        match &self.motion {
            ScenarioMotion::Free { poses, simulated, .. } => {
                (m.free_scene, m.simulated_samples) = (true, *simulated as u32);
                let g0 = poses.first().map_or([0.0; 3], |q| q.g);
                for s in poses {
                    let disp = (s.g[0] - g0[0]).hypot(s.g[1] - g0[1]) * 1e3;
                    let [n, dl, f] = [s.normal, s.delta, s.fingers];
                    let v = [
                        disp,
                        s.tilt.to_degrees(),
                        n[0],
                        n[1],
                        n[2],
                        n[3],
                        dl[0],
                        dl[1],
                        dl[2],
                        dl[3],
                        f[0],
                        f[1],
                        f[2],
                        f[3],
                    ];
                    m.push(s.t, v.map(p));
                }
            }
            ScenarioMotion::Centred(tr) => {
                m.simulated_samples = tr.simulated as u32;
                let nan = f64::NAN;
                for s in &tr.samples {
                    let (n, dl, q) = (s.normal, s.delta, s.q);
                    // finger 2 is finger 1's mirror image in the centred grasp
                    let v = [nan, nan, n[0], n[1], n[0], n[1], dl[0], dl[1], dl[0], dl[1], q[0], q[1], q[0], q[1]];
                    m.push(s.t, v.map(p));
                }
            }
        }
        if m.t.is_empty() {
            m.simulated_samples = 0;
            m.push(0.0, [f64::NAN; 14]);
        }
        m
    }

    /// The 3-D messages of design `d`'s window starting at `t0`, as (`/tf`?, log time,
    /// message): true for a `/tf` message, false for a scene update — `/tf` at the window
    /// start, then `/scene/static`, the fingers at every drawn pose (with the object's pose in
    /// the free scene), and `/tf` at the window's last nanosecond.
    pub fn scene_messages(&self, d: &DesignEntry<'_>, t0: u64) -> Vec<SceneMessage> {
        let sc = &self.scene;
        let design = Design::from_array(&d.parameters);
        let finger = Finger::new(&design, sc).ok();
        let label = self.label(d);
        let end = window_end_ns(t0);
        let mut out = vec![];
        match &self.motion {
            ScenarioMotion::Free { poses, drawn, .. } => {
                let mut shown: Vec<PoseSample> = drawn.iter().map(|&k| poses[k]).collect();
                if shown.is_empty() {
                    shown.push(self.start_pose(finger.as_ref()));
                }
                for (j, p) in shown.iter().enumerate() {
                    let tn = if j == 0 { t0 } else { log_time(t0, p.t) };
                    out.push(SceneMessage::Tf(tn, free_frames(tn, sc, p.g, p.q)));
                    if j == 0 {
                        out.push(SceneMessage::Static(t0, free_static_scene(t0, d.id, &design, sc, &label)));
                    }
                    if let Some(m) = free_fingers(d.id, tn, finger.as_ref(), p.fingers, j == 0) {
                        out.push(SceneMessage::Scene(tn, m));
                    }
                }
                let last = shown.last().expect("one pose at least");
                out.push(SceneMessage::Tf(end, free_frames(end, sc, last.g, last.q)));
            }
            ScenarioMotion::Centred(tr) => {
                out.push(SceneMessage::Tf(t0, frames(t0, sc)));
                out.push(SceneMessage::Static(t0, static_scene_with(t0, d.id, &design, sc, &label)));
                if tr.samples.is_empty() {
                    let m = discarded_scene(t0, d.id, &design, None, sc, sc);
                    out.push(SceneMessage::Scene(t0, m));
                }
                for (j, &k) in tr.scene.iter().enumerate() {
                    let (s, first) = (&tr.samples[k], j == 0);
                    let tn = if first { t0 } else { log_time(t0, s.t) };
                    if let Some(m) = scene(d.id, tn, finger.as_ref(), Some(s), first) {
                        out.push(SceneMessage::Scene(tn, m));
                    }
                }
                out.push(SceneMessage::Tf(end, frames(end, sc)));
            }
        }
        out
    }

    /// The free scene's start where it drew no pose: the object standing at x_off touching
    /// the palm, the fingers open.
    fn start_pose(&self, finger: Option<&Finger>) -> PoseSample {
        let sc = &self.scene;
        let open = finger.map_or([0.0; 4], |f| [f.open.q11, f.open.q21, f.open.q11, f.open.q21]);
        PoseSample {
            t: 0.0,
            g: [sc.setup.x_off, sc.object.radius, sc.object.length / 2.0 - sc.object.grasp_height],
            q: [1.0, 0.0, 0.0, 0.0],
            tilt: 0.0,
            fingers: open,
            energy: 0.0,
            delta: [0.0; 4],
            normal: [0.0; 4],
        }
    }
}

/// One 3-D message of a scenario's window.
#[derive(Debug, Clone)]
pub enum SceneMessage {
    /// `/tf` at a log time.
    Tf(u64, FrameTransforms),
    /// `/scene/static`.
    Static(u64, SceneUpdate),
    /// `/scene`.
    Scene(u64, SceneUpdate),
}
