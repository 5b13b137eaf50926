//! [`KeptTrajectory`]: a stage-3 trajectory reduced, right after its evaluation, to the
//! samples its recording uses (the `/grasp/series` samples and the `/scene` poses), so a
//! run holds a few hundred samples per design until the generation's shard is written
//! instead of every accepted step (docs/benchmarks.md, "Memory").

use super::options::RecordOptions;
use crate::sim::{Sample, Trajectory};

/// What a recording uses of one design's trajectory: the samples of its series and of its
/// scene (in time order, each once) and how many the simulation produced. The shard written
/// from it is the one written from the whole trajectory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeptTrajectory {
    /// Samples the simulation produced (the record's `trajectory_samples`, the series'
    /// `simulated_samples`).
    pub simulated: usize,
    /// The samples recorded, in time order.
    pub samples: Vec<Sample>,
    /// Indices into `samples` of the `/grasp/series` samples ([`RecordOptions::kept_samples`]).
    pub series: Vec<usize>,
    /// Indices into `samples` of the `/scene` poses ([`scene_samples`]).
    pub scene: Vec<usize>,
}

impl KeptTrajectory {
    /// The samples of `tr` that a recording with `opts` uses.
    pub fn of(tr: &Trajectory, opts: &RecordOptions) -> Self {
        let all = &tr.samples[..];
        let series = opts.kept_samples(all);
        let scene = scene_samples(all, opts.scene_dt);
        // both in time order; each sample once
        let mut used: Vec<usize> = series.iter().chain(&scene).copied().collect();
        used.sort_unstable();
        used.dedup();
        let at = |k: &usize| used.binary_search(k).expect("a used sample");
        KeptTrajectory {
            simulated: all.len(),
            samples: used.iter().map(|&k| all[k]).collect(),
            series: series.iter().map(at).collect(),
            scene: scene.iter().map(at).collect(),
        }
    }
}

/// Indices of the samples drawn in the `/scene` channel every `scene_dt` of simulated time:
/// the first sample, then the first at least `scene_dt` after the previously drawn one, and
/// the last; none when `scene_dt` ≤ 0.
pub fn scene_samples(samples: &[Sample], scene_dt: f64) -> Vec<usize> {
    let Some(last) = samples.len().checked_sub(1).filter(|_| scene_dt > 0.0) else {
        return vec![];
    };
    let mut next = 0.0;
    let mut out = vec![];
    for (k, s) in samples.iter().enumerate() {
        if s.t < next && k != last {
            continue;
        }
        out.push(k);
        next = s.t + scene_dt;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::Resolution;

    fn traj(ts: &[f64]) -> Trajectory {
        let sample = |t: f64| Sample {
            t,
            q: [t, -t],
            qd: [0.0; 2],
            theta2: 0.0,
            delta: [0.0; 2],
            normal: [0.0; 2],
            friction: [0.0; 2],
            hand_fy: 0.0,
            filtered_fy: 0.0,
            energy: 0.0,
            energy_excess: 0.0,
            finger2: None,
        };
        let samples = ts.iter().map(|&t| sample(t)).collect();
        Trajectory { samples, grid: vec![] }
    }

    #[test]
    fn keeps_exactly_the_series_and_scene_samples() {
        let ts: Vec<f64> = (0..400).map(|k| k as f64 * 1.3e-4).collect();
        let tr = traj(&ts);
        let opts = RecordOptions { scene_dt: 2e-3, ..Default::default() };
        let kt = KeptTrajectory::of(&tr, &opts);
        let series = opts.kept_samples(&tr.samples);
        let scene = scene_samples(&tr.samples, 2e-3);
        assert_eq!(kt.simulated, 400);
        let pick = |idx: &[usize], from: &[Sample]| idx.iter().map(|&k| from[k]).collect::<Vec<_>>();
        assert_eq!(pick(&kt.series, &kt.samples), pick(&series, &tr.samples));
        assert_eq!(pick(&kt.scene, &kt.samples), pick(&scene, &tr.samples));
        // nothing else kept, in time order
        assert!(kt.samples.len() < 400 && kt.samples.windows(2).all(|w| w[0].t < w[1].t));
        let mut union: Vec<usize> = series.iter().chain(&scene).copied().collect();
        union.sort_unstable();
        union.dedup();
        assert_eq!(kt.samples.len(), union.len());
    }

    #[test]
    fn scene_samples_every_interval_and_the_last() {
        let tr = traj(&[0.0, 0.5e-3, 1.0e-3, 2.1e-3, 2.5e-3, 4.0e-3, 4.05e-3]);
        assert_eq!(scene_samples(&tr.samples, 2e-3), vec![0, 3, 6]);
        assert_eq!(scene_samples(&tr.samples, 0.0), Vec::<usize>::new());
        assert!(scene_samples(&[], 2e-3).is_empty());
        let full = RecordOptions { resolution: Resolution::Full, every: 3, scene_dt: 0.0, ..Default::default() };
        let kt = KeptTrajectory::of(&tr, &full);
        assert_eq!(kt.samples.iter().map(|s| s.t).collect::<Vec<_>>(), vec![0.0, 2.1e-3, 4.05e-3]);
        assert_eq!(kt.series, vec![0, 1, 2]);
    }
}
