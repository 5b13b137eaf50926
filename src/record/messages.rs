//! Building the messages of one design: the `/designs` JSON record and the
//! `gripopt.GraspSeries` columns; the Foxglove scene is drawn in `scene` (re-exported here).

use super::entry::DesignEntry;
use super::options::{RecordOptions, Resolution};
use super::proto::{GraspSeries, MEAN_FORCE_FIELD};
use super::schema::{DesignMessage, DesignParameters, StageSeconds, Window};
use crate::sim::{
    finger_from_values, finger_values, sample_from_values, sample_series_fields, sample_values, FingerSample, Sample,
    FINGER_COLUMNS,
};

pub use super::scene::{
    discarded_scene, drawn_scene, frames, free_fingers, free_frames, free_static_scene, scene, static_scene,
    window_end_ns,
};

/// Log time (ns since 1970) at which design `id`'s window starts: `epoch_ns + id` s.
pub fn window_start_ns(epoch_ns: u64, id: u64) -> u64 {
    epoch_ns + id * 1_000_000_000
}

/// Log time of simulated time `t` in the window starting at `t0_ns` (inside the window).
pub fn log_time(t0_ns: u64, t: f64) -> u64 {
    t0_ns + (t * 1e9).round().clamp(0.0, 999_999_999.0) as u64
}

/// `/designs` message of a design whose window starts at `t0_ns`, derived from its
/// evaluation record. Values that were not computed are left out (no nulls, so the schema
/// needs no union types).
pub fn design(i: &DesignEntry<'_>, problem: &str, t0_ns: u64, epoch_s: u64) -> DesignMessage {
    let r = i.record;
    let v = &r.verdict;
    DesignMessage {
        id: i.id,
        generation: i.generation,
        problem: problem.to_string(),
        window_start: Window { sec: t0_ns / 1_000_000_000, nsec: t0_ns % 1_000_000_000 },
        window_start_s: i.id as f64,
        epoch_s,
        parameters: DesignParameters::from_array(&i.parameters),
        derived: r.derived(),
        stages_passed: v.failed_stage.unwrap_or(4),
        feasible: v.failed_stage.is_none(),
        form_closed: r.form_closed(),
        failed_stage: v.failed_stage,
        reason: v.reason.clone(),
        violation: v.violation,
        // a design not form closed: form_closed = false, max_offset left out (as the CSVs)
        objectives: r.reported_objectives(),
        stage_seconds: StageSeconds {
            stages_0_1: i.stage_seconds[1],
            stage_2: i.stage_seconds[2],
            stage_3: i.stage_seconds[3],
        },
        sim_steps: r.sim_work().map(|w| w[0]),
        sim_rhs_evals: r.sim_work().map(|w| w[1]),
        free_scene: r.free_scene.clone(),
        robust: r.robust.clone(),
        shown_scenario: i.scenario.map(|s| s.shown(i)),
        trajectory_samples: i.trajectory.map_or(0, |t| t.simulated as u64),
    }
}

/// A value as recorded at `res` (f32 precision when compact).
pub fn at_precision(x: f64, res: Resolution) -> f64 {
    match res {
        Resolution::Full => x,
        Resolution::Compact => x as f32 as f64,
    }
}

/// The `/grasp/series` message of design `d` from the selected samples (`kept`, indices into
/// `samples`) of the `simulated` ones. A design without a
/// trajectory gets one placeholder sample (t = 0, every value NaN, `simulated_samples` = 0):
/// a Plot panel redraws only when a path yields at least one value, so an empty message
/// would leave the previous design's curves on screen after a seek (docs/recording.md).
/// `mean_force_objective` repeats the design's F̃ (stage 2's static mean contact force, the
/// objective) on every sample, so the Plot panel draws it as a line beside the simulated forces.
/// With `finger2` (the offset scene) the series has finger 2's columns (its angles, rates, θ2
/// and contacts), as long as the others (NaN in the placeholder).
pub fn series(
    d: &DesignEntry<'_>,
    samples: &[Sample],
    kept: &[usize],
    simulated: usize,
    opts: &RecordOptions,
    finger2: bool,
) -> GraspSeries {
    let r = opts.resolution;
    let mut m = GraspSeries {
        design_id: d.id,
        full_resolution: r == Resolution::Full,
        simulated_samples: simulated as u32,
        ..Default::default()
    };
    // the columns by the trajectory's vocabulary: a sample's values after the time, each
    // into its `/grasp/series` field
    let columns: Vec<&str> = sample_series_fields().collect();
    if kept.is_empty() {
        m.t.push(0.0);
        for c in columns.iter().copied().chain([MEAN_FORCE_FIELD]) {
            m.column_mut(c).expect("a series field").push(f64::NAN);
        }
        if finger2 {
            for c in &FINGER_COLUMNS {
                m.column_mut(c.finger2_series).expect("a series field").push(f64::NAN);
            }
        }
        return m;
    }
    let f_tilde = d.record.objectives()[2].map_or(f64::NAN, |f| at_precision(f, r));
    let p = |x: f64| at_precision(x, r);
    let rows: Vec<[f64; 16]> = kept.iter().map(|&k| sample_values(&samples[k])).collect();
    m.t = rows.iter().map(|v| v[0]).collect();
    for (j, c) in columns.iter().enumerate() {
        *m.column_mut(c).expect("a series field") = rows.iter().map(|v| p(v[1 + j])).collect();
    }
    m.mean_force_objective = vec![f_tilde; rows.len()];
    let finger2: Vec<[f64; 11]> = kept.iter().filter_map(|&k| samples[k].finger2.as_ref().map(finger_values)).collect();
    for (j, c) in FINGER_COLUMNS.iter().enumerate() {
        if !finger2.is_empty() {
            *m.column_mut(c.finger2_series).expect("a series field") = finger2.iter().map(|v| p(v[j])).collect();
        }
    }
    m
}

/// Which of finger 2's columns a `/grasp/series` message has (offset scene).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finger2Columns {
    /// None (another scene, or an offset shard written before session 36).
    None,
    /// Its angles `finger2_q11`, `finger2_q21` only (an offset shard of session 36).
    Angles,
    /// All of them (an offset shard written since session 37).
    All,
}

impl Finger2Columns {
    /// The finger-2 columns of `m`; `None` if they are not as long as `t` or not one of the
    /// sets gripopt has written.
    pub fn of(m: &GraspSeries) -> Option<Self> {
        let n = m.t.len();
        let lens = m.finger2_columns().map(Vec::len);
        let (angles, rest) = lens.split_at(2);
        let full = |c: &[usize]| c.iter().all(|&l| l == n);
        let empty = |c: &[usize]| c.iter().all(|&l| l == 0);
        match (full(angles), empty(angles), full(rest), empty(rest)) {
            (_, true, _, true) => Some(Finger2Columns::None),
            (true, _, _, true) => Some(Finger2Columns::Angles),
            (true, _, true, _) => Some(Finger2Columns::All),
            _ => None,
        }
    }

    /// `s` as a recording with these columns holds it: finger 2 left out without them, its
    /// rates, θ2 and contacts NaN with its angles only.
    pub fn shape(self, s: &Sample) -> Sample {
        let finger2 = match self {
            Finger2Columns::None => None,
            Finger2Columns::Angles => s.finger2.map(|f| FingerSample { q: f.q, ..FingerSample::map(&f, |_| f64::NAN) }),
            Finger2Columns::All => s.finger2,
        };
        Sample { finger2, ..*s }
    }
}

/// Samples back from a `/grasp/series` message (replay); `None` if its columns differ in
/// length. The placeholder of a design without a trajectory (`simulated_samples` = 0) gives
/// no sample. Finger 2's columns the message lacks are NaN ([`Finger2Columns`]).
pub fn samples_from(m: &GraspSeries) -> Option<Vec<Sample>> {
    if m.simulated_samples == 0 {
        return Some(vec![]);
    }
    let n = m.t.len();
    let cols: Vec<&Vec<f64>> =
        sample_series_fields().map(|f| m.column(f).expect("the vocabulary's fields are the series'")).collect();
    if cols.iter().any(|c| c.len() != n) {
        return None;
    }
    // finger 2's own columns: offset scene only; absent in older recordings (all of them
    // before session 36, all but the angles in session 36's)
    let f2 = m.finger2_columns();
    let finger2 = match Finger2Columns::of(m)? {
        Finger2Columns::None => None,
        Finger2Columns::Angles => Some(2),
        Finger2Columns::All => Some(f2.len()),
    };
    let finger2_at = |k: usize| {
        finger2.map(|cols| {
            let mut v = [f64::NAN; 11];
            for (x, c) in v.iter_mut().zip(&f2[..cols]) {
                *x = c[k];
            }
            finger_from_values(&v)
        })
    };
    Some(
        (0..n)
            .map(|k| {
                let mut v = [m.t[k]; 16];
                for (x, c) in v[1..].iter_mut().zip(&cols) {
                    *x = c[k];
                }
                sample_from_values(&v, finger2_at(k))
            })
            .collect(),
    )
}
