//! A recorded design compared with its re-evaluation, typed: the `/designs` record's values
//! (objectives, violation, stage, reason, simulation work) against the fresh [`Record`], the
//! recorded trajectory against the fresh samples selected and rounded as recorded, a robust
//! design's scenarios against the fresh ones, and a recording of another simulator revision
//! within the integration tolerance ([`AcrossRevisions`]). What `gripopt replay` reports.

use super::messages::at_precision;
use super::read::Recorded;
use super::schema::DesignMessage;
use super::{RecordOptions, Resolution};
use crate::eval::Record;
use crate::sim::{finger_values, sample_values, Sample, ACROSS_REVISIONS_RTOL, SIMULATOR_REVISION};

/// A recorded design against its re-evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// The re-evaluation equals the recording: its trajectory, selected and rounded as
    /// recorded (bitwise for the same build; else within 1e-12 relative for a
    /// full-resolution recording, within one f32 unit, 1.2e-7 relative, for a compact one),
    /// and its record's values (a robust design: every scenario, bit for bit).
    pub verified: bool,
    /// Largest relative difference found (infinite where a value is on one side only).
    pub max_difference: f64,
    /// Trajectory samples compared.
    pub compared: usize,
    /// Values of the `/designs` record compared with the re-evaluation (failing stage,
    /// reason, violation, objectives, simulation steps and RHS evaluations): what verifies a
    /// design recorded without a trajectory (discarded before stage 3, a robust design, or a
    /// scene whose trajectory is not recorded).
    pub values_compared: usize,
    /// For a recording made by another simulator revision that this one does not reproduce
    /// bit for bit: whether the re-evaluation agrees with it within the integration tolerance.
    pub across_revisions: Option<AcrossRevisions>,
}

/// Compare `recorded` with the re-evaluation `fresh` and its grasp samples `samples` (every
/// sample of the re-simulation; selected and rounded here as the run's recording options
/// `run_opts` and the recording's resolution kept them). `comparable` false: the
/// re-evaluation cannot verify the recording whatever it gives (another problem file than
/// the one the design was recorded with).
pub fn compare_grasp(
    recorded: &Recorded,
    fresh: &Record,
    samples: &[Sample],
    run_opts: &RecordOptions,
    comparable: bool,
) -> Comparison {
    // rounded as recorded (t exact), finger 2 left as the recording has it
    let fresh_samples: Vec<Sample> = if recorded.samples.is_empty() {
        vec![]
    } else {
        let round = |s: &Sample| recorded.finger2_columns.shape(&s.map(|x| at_precision(x, recorded.resolution)));
        let opts = RecordOptions { resolution: recorded.resolution, ..*run_opts };
        opts.kept_samples(samples).into_iter().map(|k| round(&samples[k])).collect()
    };
    let mut maxd = 0.0f64;
    let same_len = fresh_samples.len() == recorded.samples.len();
    for (a, b) in fresh_samples.iter().zip(&recorded.samples) {
        maxd = maxd.max(sample_difference(a, b));
    }
    // same build: 0 (bitwise); another build may differ in the last bits, then by at most
    // one unit of the recorded precision
    let tol = match recorded.resolution {
        Resolution::Full => 1e-12,
        Resolution::Compact => f32::EPSILON as f64,
    };
    let (values_compared, alike, vmaxd) = compare_values(&recorded.record, fresh);
    let feasible = recorded.record.feasible == fresh.verdict.feasible;
    let verified = same_len && maxd <= tol && feasible && alike && vmaxd <= tol && comparable;
    let maxd = maxd.max(vmaxd);
    let across_revisions = (!verified && comparable && recorded.simulator_revision != SIMULATOR_REVISION)
        .then(|| AcrossRevisions::compare(recorded, fresh));
    Comparison {
        compared: fresh_samples.len().min(recorded.samples.len()),
        values_compared,
        verified,
        max_difference: if same_len && alike { maxd } else { f64::INFINITY },
        across_revisions,
    }
}

/// Compare a robust design's recording with its re-evaluation `fresh`: the record's values
/// and every scenario (as written: a scenario's solver account is not in the recording; an
/// older gripopt's −Δ_off placeholder of max_offset read as not computed). No trajectory is
/// recorded. `comparable` as for [`compare_grasp`].
pub fn compare_robust(recorded: &Recorded, fresh: &Record, comparable: bool) -> Comparison {
    let (values_compared, alike, vmaxd) = compare_values(&recorded.record, fresh);
    let recorded_robust = recorded.record.robust.as_ref().map(|r| r.without_offset_placeholder());
    let fresh_robust = fresh.robust.as_ref().map(|r| r.as_written());
    let verified = alike && vmaxd == 0.0 && recorded_robust == fresh_robust && comparable;
    Comparison {
        compared: 0,
        values_compared,
        verified,
        max_difference: if alike { vmaxd } else { f64::INFINITY },
        across_revisions: None,
    }
}

/// A recording compared with a re-evaluation by another simulator revision: the verdict
/// (feasibility, failing stage, reason) must be the same, the objectives and the violation
/// within [`ACROSS_REVISIONS_RTOL`] relative, and a full-resolution trajectory must end at the
/// same time within it (its samples are not compared: the steps differ).
#[derive(Debug, Clone, PartialEq)]
pub struct AcrossRevisions {
    /// The revision that recorded the design.
    pub recorded: u32,
    /// This build's revision.
    pub current: u32,
    /// Largest relative difference of the objectives and the violation.
    pub max_difference: f64,
    /// What differs beyond the tolerance (None: they agree).
    pub differs: Option<String>,
}

impl AcrossRevisions {
    /// The recording and the re-evaluation agree within the tolerance.
    pub fn agrees(&self) -> bool {
        self.differs.is_none()
    }

    /// Compare `recorded` (by revision `recorded.simulator_revision`) with `fresh`, this
    /// build's re-evaluation.
    pub fn compare(recorded: &Recorded, fresh: &Record) -> AcrossRevisions {
        let rec = &recorded.record;
        let mut out = AcrossRevisions {
            recorded: recorded.simulator_revision,
            current: SIMULATOR_REVISION,
            max_difference: 0.0,
            differs: None,
        };
        let verdict = |f: bool, s: Option<u8>, r: Option<&str>| (f, s, r.map(str::to_owned));
        if verdict(rec.feasible, rec.failed_stage, rec.reason.as_deref())
            != verdict(fresh.verdict.feasible, fresh.verdict.failed_stage, fresh.verdict.reason.as_deref())
        {
            out.differs = Some(format!(
                "the verdict differs (recorded feasible {}, stage {:?}; now feasible {}, stage {:?})",
                rec.feasible, rec.failed_stage, fresh.verdict.feasible, fresh.verdict.failed_stage
            ));
            return out;
        }
        // an older gripopt wrote max_offset's −Δ_off sentinel where it was not computed
        let (r_o, o) = (rec.objectives.reported(), fresh.reported_objectives());
        let mut pairs = vec![
            ("max_offset", r_o.max_offset, o.max_offset),
            ("alpha", r_o.alpha, o.alpha),
            ("mean_force", r_o.mean_force, o.mean_force),
            ("t_stab", r_o.t_stab, o.t_stab),
            ("violation", rec.violation, fresh.verdict.violation),
        ];
        if recorded.resolution == Resolution::Full && !recorded.samples.is_empty() {
            pairs.push(("trajectory end", recorded.samples.last().map(|s| s.t), fresh.grasp.t_end));
        }
        for (what, a, b) in pairs {
            match (a, b) {
                (Some(a), Some(b)) => {
                    let d = rel(a, b);
                    out.max_difference = out.max_difference.max(d);
                    if d > ACROSS_REVISIONS_RTOL && out.differs.is_none() {
                        out.differs = Some(format!("{what}: recorded {a}, now {b}"));
                    }
                }
                (None, None) => {}
                (a, b) if out.differs.is_none() => out.differs = Some(format!("{what}: recorded {a:?}, now {b:?}")),
                _ => {}
            }
        }
        out
    }
}

/// Compare the recorded `/designs` message with the re-evaluation's record `fresh`:
/// (values compared, all present on both sides alike, largest relative difference of the
/// numbers). The values: objectives, violation, failing stage, reason, the grasp
/// simulation's steps and right-hand-side evaluations.
fn compare_values(rec: &DesignMessage, fresh: &Record) -> (usize, bool, f64) {
    // the optimiser's negative max_offset placeholder (MODEL.md §6.7) is not a value
    let fresh_obj = fresh.reported_objectives().to_array();
    let rec_obj = rec.objectives.reported().to_array();
    let (mut n, mut alike, mut maxd) = (0usize, true, 0.0f64);
    let mut num = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => {
            n += 1;
            maxd = maxd.max(rel(a, b));
        }
        (None, None) => {}
        _ => {
            n += 1;
            alike = false;
        }
    };
    for (a, b) in fresh_obj.into_iter().zip(rec_obj) {
        num(a, b);
    }
    let v = &fresh.verdict;
    num(v.violation, rec.violation);
    let w = fresh.sim_work();
    let ints = [
        (v.failed_stage.map(u64::from), rec.failed_stage.map(u64::from)),
        (w.map(|w| w[0]), rec.sim_steps),
        (w.map(|w| w[1]), rec.sim_rhs_evals),
    ];
    for (a, b) in ints {
        if a.is_some() || b.is_some() {
            n += 1;
            alike &= a == b;
        }
    }
    if v.reason.is_some() || rec.reason.is_some() {
        n += 1;
        alike &= v.reason == rec.reason;
    }
    (n, alike, maxd)
}

/// The largest relative difference between fresh sample `a` (shaped as recorded) and the
/// recorded `b`: finger 1's values, the hand force and energy, and finger 2's where recorded
/// (a value NaN on one side only, or finger 2 on one side only, differs infinitely).
fn sample_difference(a: &Sample, b: &Sample) -> f64 {
    let mut d = sample_values(a).into_iter().zip(sample_values(b)).map(|(u, v)| rel(u, v)).fold(0.0, f64::max);
    match (a.finger2, b.finger2) {
        (Some(u), Some(v)) => {
            let nan_apart = |(x, y): (f64, f64)| if x.is_nan() != y.is_nan() { f64::INFINITY } else { rel(x, y) };
            d = finger_values(&u).into_iter().zip(finger_values(&v)).map(nan_apart).fold(d, f64::max);
        }
        (None, None) => {}
        _ => d = f64::INFINITY,
    }
    d
}

fn rel(a: f64, b: f64) -> f64 {
    if a.to_bits() == b.to_bits() {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
    }
}
