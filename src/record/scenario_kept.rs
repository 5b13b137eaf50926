//! What a recording keeps of a robust design's deciding scenario until its shard is written
//! ([`ScenarioScene`]: which scenario, its scene, and the samples of its free scene or of its
//! centred grasp that the recording uses), as [`super::KeptTrajectory`] is for a grasp; drawn
//! by `scenario_scene`.

use super::kept::KeptTrajectory;
use super::options::{RecordOptions, Resolution};
use crate::eval::Decides;
use crate::params::SceneParams;
use crate::sim::PoseSample;

/// What a recording draws of the scenario that decided a robust design.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioScene {
    /// The object's index in the study.
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
