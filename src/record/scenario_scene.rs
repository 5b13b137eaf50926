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
use super::kept::KeptTrajectory;
use super::messages::{at_precision, log_time, window_end_ns};
use super::options::{RecordOptions, Resolution};
use super::scenario_series::ScenarioSeries;
use super::scene::{
    discarded_scene, fit_label, frames, free_fingers, free_frames, free_static_scene, scene, static_scene_with,
    verdict_after,
};
use crate::eval::Decides;
use crate::model::Finger;
use crate::params::{Design, SceneParams};
use crate::sim::PoseSample;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use serde::{Deserialize, Serialize};

/// What a recording draws of the scenario that decided a robust design.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioScene {
    /// The object's index and name.
    pub object: usize,
    /// Its name (`[[robust.objects]] name`).
    pub name: String,
    /// The scenario's index among the object's.
    pub k: usize,
    /// Why this scenario.
    pub decides: Decides,
    /// The scenario's scene: its object, its grasp height (the object's plus the drawn
    /// offset: the hand's height above the ground), x_off, contact laws.
    pub scene: SceneParams,
    /// The drawn hand height offset (m).
    pub height_offset: f64,
    /// Objects and scenarios per object of the run (for the replay hint).
    pub study: (usize, usize),
    /// What was simulated.
    pub motion: ScenarioMotion,
}

/// The simulation drawn of a [`ScenarioScene`].
#[derive(Debug, Clone, PartialEq)]
pub enum ScenarioMotion {
    /// The free scene ran: the poses kept (in time order; every one a `/scenario/series`
    /// sample), the indices of those drawn in 3-D (the first, one every `scene_dt` and the
    /// last), and how many the simulation produced.
    Free {
        /// The poses kept.
        poses: Vec<PoseSample>,
        /// Indices into `poses` drawn in 3-D.
        drawn: Vec<usize>,
        /// Poses the simulation produced.
        simulated: usize,
    },
    /// The scenario ended in its centred grasp (a finger criterion, or no static grasp at the
    /// scenario's torque: then nothing simulated, the trajectory empty).
    Centred(KeptTrajectory),
}

impl ScenarioMotion {
    /// The free scene's poses as kept for a recording with `opts` (`all`: every step and event
    /// of the simulation): the drawn ones ([`super::keep_poses`]'s rule at `scene_dt`, the first
    /// and the last), both poses around every change of a phalanx's contact state (δ > 0),
    /// every local peak of a phalanx's normal force, and one pose per [`SCENARIO_DT`] of
    /// simulated time between (every pose at full resolution).
    pub fn free(all: &[PoseSample], opts: &RecordOptions) -> Self {
        let n = all.len();
        let mut keep = vec![opts.resolution == Resolution::Full; n];
        let drawn_at = drawn_poses(all, opts.scene_dt);
        for &k in &drawn_at {
            keep[k] = true;
        }
        for i in 1..n {
            let (a, b) = (&all[i - 1], &all[i]);
            if (0..4).any(|c| (a.delta[c] > 0.0) != (b.delta[c] > 0.0)) {
                (keep[i - 1], keep[i]) = (true, true);
            }
            if let Some(z) = all.get(i + 1) {
                keep[i] |= (0..4).any(|c| b.normal[c] > a.normal[c] && b.normal[c] >= z.normal[c]);
            }
        }
        let mut last_t = f64::NEG_INFINITY;
        for (k, p) in all.iter().enumerate() {
            keep[k] |= p.t - last_t >= SCENARIO_DT;
            if keep[k] {
                last_t = p.t;
            }
        }
        let used: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
        let drawn = drawn_at.iter().map(|k| used.binary_search(k).expect("a drawn pose is kept")).collect();
        ScenarioMotion::Free { poses: used.iter().map(|&k| all[k]).collect(), drawn, simulated: n }
    }
}

/// Simulated-time spacing of the regular samples of a scenario's compact series (s): its
/// free scene lasts t_obs = 0.1 s, 50 samples besides its contacts' onsets and peaks.
pub const SCENARIO_DT: f64 = 2e-3;

/// Indices of the poses drawn every `scene_dt`: the first, then the first at least
/// `scene_dt` after the previously drawn one, and the last (replacing a drawn pose less than
/// 1 µs before it); none when `scene_dt` ≤ 0.
fn drawn_poses(all: &[PoseSample], scene_dt: f64) -> Vec<usize> {
    let mut out: Vec<usize> = vec![];
    if scene_dt <= 0.0 {
        return out;
    }
    for (k, p) in all.iter().enumerate() {
        let last = k + 1 == all.len();
        if out.last().is_none_or(|&l| p.t >= all[l].t + scene_dt || last) {
            if last && out.len() > 1 && out.last().is_some_and(|&l| p.t - all[l].t < 1e-6) {
                out.pop();
            }
            out.push(k);
        }
    }
    out
}

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
    /// The drawn hand height offset (m) and object offset (m).
    pub height_offset: f64,
    /// The object's offset along the palm (m).
    pub x_off: f64,
    /// How to record any scenario of the design on its own.
    pub replay: String,
}

impl ScenarioScene {
    /// The `/designs` sub-record of design `id` drawing this scenario.
    pub fn shown(&self, id: u64, d: &DesignEntry<'_>) -> ShownScenario {
        let recorded = d
            .record
            .robust
            .as_ref()
            .and_then(|r| r.scenarios.iter().find(|s| (s.object, s.k) == (self.object, self.k)));
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
        let why = match (self.decides, self.shown_displacement(d)) {
            (Decides::WorstDisplacement, Some(m)) => format!("worst, {:.2} mm", m * 1e3),
            _ => self.decides.as_str().to_string(),
        };
        let head = format!("{} (gen {}) scenario {}:{} ({why});", d.id, d.generation, self.name, self.k);
        fit_label("", &verdict_after(d, head))
    }

    fn shown_displacement(&self, d: &DesignEntry<'_>) -> Option<f64> {
        d.record.robust.as_ref()?.scenarios.iter().find(|s| (s.object, s.k) == (self.object, self.k))?.max_displacement
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

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(t: f64, delta: f64, normal: f64) -> PoseSample {
        PoseSample {
            t,
            g: [0.0; 3],
            q: [1.0, 0.0, 0.0, 0.0],
            tilt: 0.0,
            fingers: [0.0; 4],
            energy: 0.0,
            delta: [delta, -1.0, -1.0, -1.0],
            normal: [normal, 0.0, 0.0, 0.0],
        }
    }

    /// The free scene's kept poses: the drawn ones every `scene_dt` (and the last), both
    /// poses around a contact onset, the force peak, one pose per [`SCENARIO_DT`] between —
    /// written out by hand for a short run.
    #[test]
    fn free_poses_kept_are_the_drawn_the_contacts_and_the_peaks() {
        // 21 poses 0.25 ms apart (0 to 5 ms); a contact from pose 10 (2.5 ms), its force
        // peaking at pose 14
        let all: Vec<PoseSample> = (0..=20)
            .map(|i: i32| {
                let (d, f) = if i >= 10 { (1e-6, 1.0 - 0.1 * (i - 14).abs() as f64) } else { (-1e-6, 0.0) };
                pose(i as f64 * 2.5e-4, d, f)
            })
            .collect();
        let opts = RecordOptions { scene_dt: 4e-3, ..Default::default() };
        let ScenarioMotion::Free { poses, drawn, simulated } = ScenarioMotion::free(&all, &opts) else { panic!() };
        let index: Vec<i64> = poses.iter().map(|p| (p.t / 2.5e-4).round() as i64).collect();
        // 0 (first, drawn), 8 (2 ms: the regular spacing), 9 and 10 (the onset), 14 (the
        // peak), 16 (4 ms, drawn), 20 (the last, drawn)
        assert_eq!(index, vec![0, 8, 9, 10, 14, 16, 20]);
        let drawn_at: Vec<i64> = drawn.iter().map(|&k| index[k]).collect();
        assert_eq!((drawn_at, simulated), (vec![0, 16, 20], 21));
        let full = RecordOptions { resolution: Resolution::Full, ..opts };
        let ScenarioMotion::Free { poses, .. } = ScenarioMotion::free(&all, &full) else { panic!() };
        assert_eq!(poses.len(), 21);
    }
}
