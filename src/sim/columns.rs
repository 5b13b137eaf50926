//! The one vocabulary of a trajectory's columns, beside the sample types it names
//! ([`Sample`], [`FingerSample`], [`PoseSample`]): each column's name (as `simulate --csv`,
//! `replay --csv` and the Python trajectories name it), unit and meaning, the field of the
//! `/grasp/series` MCAP message that records it, and its value in a sample. The CSV writers,
//! the recording (`record::messages`, the `/grasp/series` schema of `record::proto`), the
//! Foxglove layouts and the Python package read these tables; a column is added or renamed
//! here only.
//!
//! The `/grasp/series` fields keep the names they had before this table (`proximal_penetration`
//! for `delta_1`, …): they are the schema of every recording written, which older recordings,
//! their layouts and other readers name; [`FingerColumn::series`] maps them.

use super::result::{FingerSample, PoseSample, Sample};

/// A column's name, unit and meaning (a table's column as the CSV header, its `# units:` line
/// and the Python package's `attrs` show it).
pub type Column = (&'static str, &'static str, &'static str);

/// One value of a finger in a grasp sample: finger 1's (every grasp scene), and finger 2's own
/// in the offset scene, where finger 2 is not finger 1's mirror image.
#[derive(Clone, Copy)]
pub struct FingerColumn {
    /// Finger 1's column name.
    pub name: &'static str,
    /// Finger 2's column name (`finger2_` before finger 1's).
    pub finger2: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// What finger 1's value is.
    pub meaning: &'static str,
    /// What finger 2's value is.
    pub finger2_meaning: &'static str,
    /// Finger 1's `/grasp/series` field.
    pub series: &'static str,
    /// Finger 2's `/grasp/series` field.
    pub finger2_series: &'static str,
    /// The value in a finger's sample.
    pub get: fn(&FingerSample) -> f64,
    /// Set the value in a finger's sample (a recording read back).
    pub set: fn(&mut FingerSample, f64),
}

/// A value of a grasp sample that is not a finger's: the time, the hand force and the energy.
#[derive(Clone, Copy)]
pub struct SceneColumn {
    /// Column name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// What it is.
    pub meaning: &'static str,
    /// Its `/grasp/series` field.
    pub series: &'static str,
    /// The value in a sample.
    pub get: fn(&Sample) -> f64,
    /// Set the value in a sample (a recording read back).
    pub set: fn(&mut Sample, f64),
}

/// A free-scene pose sample's value.
#[derive(Clone, Copy)]
pub struct PoseColumn {
    /// Column name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// What it is.
    pub meaning: &'static str,
    /// The value in a pose sample.
    pub get: fn(&PoseSample) -> f64,
}

/// The time, first column of a grasp trajectory.
pub const TIME: SceneColumn =
    SceneColumn { name: "t", unit: "s", meaning: "time", series: "t", get: |s| s.t, set: |s, v| s.t = v };

/// A finger's values, in the order of a trajectory's finger columns (and of
/// [`FingerSample::values`]).
pub const FINGER_COLUMNS: [FingerColumn; 11] = [
    FingerColumn {
        name: "q11",
        finger2: "finger2_q11",
        unit: "rad",
        meaning: "active joint angle q11",
        finger2_meaning: "finger 2's q11 (its mirrored frame)",
        series: "q11",
        finger2_series: "finger2_q11",
        get: |f| f.q[0],
        set: |f, v| f.q[0] = v,
    },
    FingerColumn {
        name: "q21",
        finger2: "finger2_q21",
        unit: "rad",
        meaning: "active joint angle q21",
        finger2_meaning: "finger 2's q21",
        series: "q21",
        finger2_series: "finger2_q21",
        get: |f| f.q[1],
        set: |f, v| f.q[1] = v,
    },
    FingerColumn {
        name: "q11_dot",
        finger2: "finger2_q11_dot",
        unit: "rad/s",
        meaning: "its rate",
        finger2_meaning: "its rate",
        series: "q11_dot",
        finger2_series: "finger2_q11_dot",
        get: |f| f.qd[0],
        set: |f, v| f.qd[0] = v,
    },
    FingerColumn {
        name: "q21_dot",
        finger2: "finger2_q21_dot",
        unit: "rad/s",
        meaning: "its rate",
        finger2_meaning: "its rate",
        series: "q21_dot",
        finger2_series: "finger2_q21_dot",
        get: |f| f.qd[1],
        set: |f, v| f.qd[1] = v,
    },
    FingerColumn {
        name: "theta2",
        finger2: "finger2_theta2",
        unit: "rad",
        meaning: "distal phalanx angle θ2",
        finger2_meaning: "finger 2's θ2",
        series: "theta2",
        finger2_series: "finger2_theta2",
        get: |f| f.theta2,
        set: |f, v| f.theta2 = v,
    },
    FingerColumn {
        name: "delta_1",
        finger2: "finger2_delta_1",
        unit: "m",
        meaning: "penetration of the proximal contact",
        finger2_meaning: "penetration of finger 2's proximal contact",
        series: "proximal_penetration",
        finger2_series: "finger2_proximal_penetration",
        get: |f| f.delta[0],
        set: |f, v| f.delta[0] = v,
    },
    FingerColumn {
        name: "delta_2",
        finger2: "finger2_delta_2",
        unit: "m",
        meaning: "penetration of the distal contact",
        finger2_meaning: "penetration of finger 2's distal contact",
        series: "distal_penetration",
        finger2_series: "finger2_distal_penetration",
        get: |f| f.delta[1],
        set: |f, v| f.delta[1] = v,
    },
    FingerColumn {
        name: "fn_1",
        finger2: "finger2_fn_1",
        unit: "N",
        meaning: "normal force of the proximal contact",
        finger2_meaning: "normal force of finger 2's proximal contact",
        series: "proximal_normal_force",
        finger2_series: "finger2_proximal_normal_force",
        get: |f| f.normal[0],
        set: |f, v| f.normal[0] = v,
    },
    FingerColumn {
        name: "fn_2",
        finger2: "finger2_fn_2",
        unit: "N",
        meaning: "normal force of the distal contact",
        finger2_meaning: "normal force of finger 2's distal contact",
        series: "distal_normal_force",
        finger2_series: "finger2_distal_normal_force",
        get: |f| f.normal[1],
        set: |f, v| f.normal[1] = v,
    },
    FingerColumn {
        name: "ft_1",
        finger2: "finger2_ft_1",
        unit: "N",
        meaning: "friction force of the proximal contact (on the finger along t_c)",
        finger2_meaning: "friction force of finger 2's proximal contact (on the finger along its t_c)",
        series: "proximal_friction_force",
        finger2_series: "finger2_proximal_friction_force",
        get: |f| f.friction[0],
        set: |f, v| f.friction[0] = v,
    },
    FingerColumn {
        name: "ft_2",
        finger2: "finger2_ft_2",
        unit: "N",
        meaning: "friction force of the distal contact",
        finger2_meaning: "friction force of finger 2's distal contact",
        series: "distal_friction_force",
        finger2_series: "finger2_distal_friction_force",
        get: |f| f.friction[1],
        set: |f, v| f.friction[1] = v,
    },
];

/// A grasp sample's values after finger 1's: the hand force and the energy.
pub const HAND_COLUMNS: [SceneColumn; 4] = [
    SceneColumn {
        name: "hand_fy",
        unit: "N",
        meaning: "hand force F_hand,y (raw)",
        series: "hand_force",
        get: |s| s.hand_fy,
        set: |s, v| s.hand_fy = v,
    },
    SceneColumn {
        name: "filtered_fy",
        unit: "N",
        meaning: "hand force, filtered",
        series: "filtered_hand_force",
        get: |s| s.filtered_fy,
        set: |s, v| s.filtered_fy = v,
    },
    SceneColumn {
        name: "energy",
        unit: "J",
        meaning: "total energy E",
        series: "energy",
        get: |s| s.energy,
        set: |s, v| s.energy = v,
    },
    SceneColumn {
        name: "energy_excess",
        unit: "J",
        meaning: "E − V*",
        series: "energy_excess",
        get: |s| s.energy_excess,
        set: |s, v| s.energy_excess = v,
    },
];

/// The free scene's pose sample, as `simulate --scene free --csv` writes it.
pub const POSE_TABLE: [PoseColumn; 14] = [
    PoseColumn { name: "t", unit: "s", meaning: "time", get: |p| p.t },
    PoseColumn { name: "gx", unit: "m", meaning: "object centre of mass, x", get: |p| p.g[0] },
    PoseColumn { name: "gy", unit: "m", meaning: "object centre of mass, y", get: |p| p.g[1] },
    PoseColumn { name: "gz", unit: "m", meaning: "object centre of mass, z", get: |p| p.g[2] },
    PoseColumn { name: "qw", unit: "-", meaning: "object orientation quaternion, w", get: |p| p.q[0] },
    PoseColumn { name: "qx", unit: "-", meaning: "object orientation quaternion, x", get: |p| p.q[1] },
    PoseColumn { name: "qy", unit: "-", meaning: "object orientation quaternion, y", get: |p| p.q[2] },
    PoseColumn { name: "qz", unit: "-", meaning: "object orientation quaternion, z", get: |p| p.q[3] },
    PoseColumn { name: "tilt_deg", unit: "deg", meaning: "object tilt", get: |p| p.tilt.to_degrees() },
    PoseColumn { name: "q11_1", unit: "rad", meaning: "finger 1: q11", get: |p| p.fingers[0] },
    PoseColumn { name: "q21_1", unit: "rad", meaning: "finger 1: q21", get: |p| p.fingers[1] },
    PoseColumn { name: "q11_2", unit: "rad", meaning: "finger 2: q11", get: |p| p.fingers[2] },
    PoseColumn { name: "q21_2", unit: "rad", meaning: "finger 2: q21", get: |p| p.fingers[3] },
    PoseColumn { name: "energy", unit: "J", meaning: "total energy", get: |p| p.energy },
];

/// The columns of a grasp [`Sample`]: the time, finger 1's values (finger 2 is its mirror in
/// the centred scene), the hand force and the energy, named as `gripopt simulate --csv` and
/// `replay --csv` name them, with units.
pub const SAMPLE_COLUMNS: [Column; 16] = sample_columns();

/// Finger 2's own columns in an offset-scene trajectory (its mirrored frame), after
/// [`SAMPLE_COLUMNS`]. The centred scene has none (finger 2 is finger 1's mirror).
pub const FINGER2_COLUMNS: [Column; 11] = finger2_columns();

/// The columns of a free-scene [`PoseSample`].
pub const POSE_COLUMNS: [Column; 14] = pose_columns();

const fn sample_columns() -> [Column; 16] {
    let mut out = [(TIME.name, TIME.unit, TIME.meaning); 16];
    let mut i = 0;
    while i < FINGER_COLUMNS.len() {
        let c = &FINGER_COLUMNS[i];
        out[1 + i] = (c.name, c.unit, c.meaning);
        i += 1;
    }
    let mut j = 0;
    while j < HAND_COLUMNS.len() {
        let c = &HAND_COLUMNS[j];
        out[1 + FINGER_COLUMNS.len() + j] = (c.name, c.unit, c.meaning);
        j += 1;
    }
    out
}

const fn finger2_columns() -> [Column; 11] {
    let mut out = [("", "", ""); 11];
    let mut i = 0;
    while i < FINGER_COLUMNS.len() {
        let c = &FINGER_COLUMNS[i];
        out[i] = (c.finger2, c.unit, c.finger2_meaning);
        i += 1;
    }
    out
}

const fn pose_columns() -> [Column; 14] {
    let mut out = [("", "", ""); 14];
    let mut i = 0;
    while i < POSE_TABLE.len() {
        let c = &POSE_TABLE[i];
        out[i] = (c.name, c.unit, c.meaning);
        i += 1;
    }
    out
}

/// The `/grasp/series` fields of a grasp sample's values after the time, in
/// [`SAMPLE_COLUMNS`]' order (finger 1's, the hand force, the energy).
pub fn sample_series_fields() -> impl Iterator<Item = &'static str> {
    FINGER_COLUMNS.iter().map(|c| c.series).chain(HAND_COLUMNS.iter().map(|c| c.series))
}

/// The `/grasp/series` field of the grasp column `name` (finger 2's `finger2_…` included).
pub fn series_field(name: &str) -> Option<&'static str> {
    let scene = std::iter::once(&TIME).chain(&HAND_COLUMNS).find(|c| c.name == name).map(|c| c.series);
    let finger = || {
        FINGER_COLUMNS.iter().find_map(|c| {
            (c.name == name).then_some(c.series).or_else(|| (c.finger2 == name).then_some(c.finger2_series))
        })
    };
    scene.or_else(finger)
}

/// A [`Sample`]'s values in the order of [`SAMPLE_COLUMNS`].
pub fn sample_values(s: &Sample) -> [f64; 16] {
    let f = s.finger1();
    let mut v = [(TIME.get)(s); 16];
    for (x, c) in v[1..].iter_mut().zip(&FINGER_COLUMNS) {
        *x = (c.get)(&f);
    }
    for (x, c) in v[1 + FINGER_COLUMNS.len()..].iter_mut().zip(&HAND_COLUMNS) {
        *x = (c.get)(s);
    }
    v
}

/// A [`Sample`] from its values in the order of [`SAMPLE_COLUMNS`] (finger 2 as given).
pub fn sample_from_values(v: &[f64; 16], finger2: Option<FingerSample>) -> Sample {
    let mut f = FingerSample::from_values([f64::NAN; 11]);
    for (x, c) in v[1..].iter().zip(&FINGER_COLUMNS) {
        (c.set)(&mut f, *x);
    }
    let mut s = Sample {
        t: 0.0,
        q: f.q,
        qd: f.qd,
        theta2: f.theta2,
        delta: f.delta,
        normal: f.normal,
        friction: f.friction,
        hand_fy: f64::NAN,
        filtered_fy: f64::NAN,
        energy: f64::NAN,
        energy_excess: f64::NAN,
        finger2,
    };
    (TIME.set)(&mut s, v[0]);
    for (x, c) in v[1 + FINGER_COLUMNS.len()..].iter().zip(&HAND_COLUMNS) {
        (c.set)(&mut s, *x);
    }
    s
}

/// A finger's values in the order of [`FINGER_COLUMNS`].
pub fn finger_values(f: &FingerSample) -> [f64; 11] {
    FINGER_COLUMNS.map(|c| (c.get)(f))
}

/// A finger from its values in the order of [`FINGER_COLUMNS`].
pub fn finger_from_values(v: &[f64; 11]) -> FingerSample {
    let mut f = FingerSample::from_values([f64::NAN; 11]);
    for (x, c) in v.iter().zip(&FINGER_COLUMNS) {
        (c.set)(&mut f, *x);
    }
    f
}

/// A grasp trajectory's columns: [`SAMPLE_COLUMNS`], then with `finger2` (the offset scene,
/// where finger 2 moves on its own) [`FINGER2_COLUMNS`].
pub fn trajectory_columns(finger2: bool) -> Vec<Column> {
    let extra = if finger2 { &FINGER2_COLUMNS[..] } else { &[] };
    SAMPLE_COLUMNS.iter().chain(extra).copied().collect()
}

/// A [`Sample`]'s values in the order of [`trajectory_columns`]`(finger2)`: finger 2's NaN
/// where the sample lacks them (a recording of an older gripopt).
pub fn trajectory_row(s: &Sample, finger2: bool) -> Vec<f64> {
    let mut v = sample_values(s).to_vec();
    if finger2 {
        v.extend(s.finger2.map_or([f64::NAN; 11], |f| finger_values(&f)));
    }
    v
}

/// A [`PoseSample`]'s values in the order of [`POSE_COLUMNS`].
pub fn pose_values(p: &PoseSample) -> [f64; 14] {
    POSE_TABLE.map(|c| (c.get)(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every column reads its own field: a sample whose every value is distinct gives each
    /// column the value of the field its name says (written out here field by field), and
    /// reads back from its values unchanged.
    #[test]
    fn each_column_reads_its_field() {
        let f2 = FingerSample::from_values(std::array::from_fn(|k| 100.0 + k as f64));
        let s = Sample {
            t: 0.5,
            q: [1.0, 2.0],
            qd: [3.0, 4.0],
            theta2: 5.0,
            delta: [6.0, 7.0],
            normal: [8.0, 9.0],
            friction: [10.0, 11.0],
            hand_fy: 12.0,
            filtered_fy: 13.0,
            energy: 14.0,
            energy_excess: 15.0,
            finger2: Some(f2),
        };
        let v = sample_values(&s);
        let at = |name: &str| v[SAMPLE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        let expect = [
            ("t", 0.5),
            ("q11", 1.0),
            ("q21", 2.0),
            ("q11_dot", 3.0),
            ("q21_dot", 4.0),
            ("theta2", 5.0),
            ("delta_1", 6.0),
            ("delta_2", 7.0),
            ("fn_1", 8.0),
            ("fn_2", 9.0),
            ("ft_1", 10.0),
            ("ft_2", 11.0),
            ("hand_fy", 12.0),
            ("filtered_fy", 13.0),
            ("energy", 14.0),
            ("energy_excess", 15.0),
        ];
        for (name, x) in expect {
            assert_eq!(at(name), x, "{name}");
        }
        assert_eq!(finger_values(&f2), f2.values());
        assert_eq!(finger_from_values(&f2.values()), f2);
        assert_eq!(sample_from_values(&v, Some(f2)), s);
        let row = trajectory_row(&s, true);
        assert_eq!(row[16..], f2.values());
        let names: Vec<&str> = trajectory_columns(true).iter().map(|c| c.0).collect();
        assert_eq!(names[16], "finger2_q11");
        assert_eq!(names.len(), row.len());
        assert_eq!(series_field("delta_1"), Some("proximal_penetration"));
        assert_eq!(series_field("finger2_fn_2"), Some("finger2_distal_normal_force"));
        assert_eq!(series_field("hand_fy"), Some("hand_force"));
    }

    #[test]
    fn pose_columns_read_their_fields() {
        let p = PoseSample {
            t: 0.5,
            g: [1.0, 2.0, 3.0],
            q: [4.0, 5.0, 6.0, 7.0],
            tilt: 0.1,
            fingers: [8.0, 9.0, 10.0, 11.0],
            energy: 12.0,
            delta: [13.0; 4],
            normal: [14.0; 4],
        };
        let v = pose_values(&p);
        let at = |name: &str| v[POSE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        assert_eq!(
            [at("t"), at("gz"), at("qw"), at("tilt_deg"), at("q21_2"), at("energy")],
            [0.5, 3.0, 4.0, 0.1f64.to_degrees(), 11.0, 12.0]
        );
    }
}
