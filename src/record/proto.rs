//! gripopt's own protobuf message, `gripopt.GraspSeries` (one per design on
//! `/grasp/series`): prost encodes and decodes it; its schema (a serialized
//! `FileDescriptorSet`, as MCAP's protobuf profile wants) is built from the trajectory's
//! vocabulary (`sim::SAMPLE_COLUMNS` and `FINGER_COLUMNS`, each column's `/grasp/series`
//! field), [`series_fields`], so the two cannot drift apart silently (a unit test fills every
//! column by its name and decodes the message field by field against the table).

use crate::sim::{sample_series_fields, FINGER_COLUMNS, TIME};
use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// Full name of the message (the MCAP schema name).
pub const SERIES_NAME: &str = "gripopt.GraspSeries";

/// One design's recorded grasp trajectory as columns: finger 1's (finger 2 mirrors it in the
/// centred scene), and in the offset scene finger 2's own (`finger2_q11` … `finger2_distal_friction_force`;
/// empty, i.e. absent from the bytes, otherwise; shards of session 36 have its angles only). Plotted in Foxglove with the x-axis
/// "Path (current)" `/grasp/series.t`.
#[derive(Clone, PartialEq, Message)]
pub struct GraspSeries {
    /// Design id.
    #[prost(uint64, tag = "1")]
    pub design_id: u64,
    /// True when every sample is stored in f64 (else: compact subset, values to f32 precision).
    #[prost(bool, tag = "2")]
    pub full_resolution: bool,
    /// Samples of the simulation before selection.
    #[prost(uint32, tag = "3")]
    pub simulated_samples: u32,
    /// Simulated time (s), exact.
    #[prost(double, repeated, tag = "4")]
    pub t: Vec<f64>,
    /// q11 (rad).
    #[prost(double, repeated, tag = "5")]
    pub q11: Vec<f64>,
    /// q21 = θ1 (rad).
    #[prost(double, repeated, tag = "6")]
    pub q21: Vec<f64>,
    /// q̇11 (rad/s).
    #[prost(double, repeated, tag = "7")]
    pub q11_dot: Vec<f64>,
    /// q̇21 (rad/s).
    #[prost(double, repeated, tag = "8")]
    pub q21_dot: Vec<f64>,
    /// θ2 (rad).
    #[prost(double, repeated, tag = "9")]
    pub theta2: Vec<f64>,
    /// Proximal penetration δ1 (m).
    #[prost(double, repeated, tag = "10")]
    pub proximal_penetration: Vec<f64>,
    /// Distal penetration δ2 (m).
    #[prost(double, repeated, tag = "11")]
    pub distal_penetration: Vec<f64>,
    /// Proximal normal force (N).
    #[prost(double, repeated, tag = "12")]
    pub proximal_normal_force: Vec<f64>,
    /// Distal normal force (N).
    #[prost(double, repeated, tag = "13")]
    pub distal_normal_force: Vec<f64>,
    /// Proximal friction force (N).
    #[prost(double, repeated, tag = "14")]
    pub proximal_friction_force: Vec<f64>,
    /// Distal friction force (N).
    #[prost(double, repeated, tag = "15")]
    pub distal_friction_force: Vec<f64>,
    /// Raw hand force F_hand,y (N).
    #[prost(double, repeated, tag = "16")]
    pub hand_force: Vec<f64>,
    /// Filtered hand force (N).
    #[prost(double, repeated, tag = "17")]
    pub filtered_hand_force: Vec<f64>,
    /// Energy E (J).
    #[prost(double, repeated, tag = "18")]
    pub energy: Vec<f64>,
    /// E − V* (J).
    #[prost(double, repeated, tag = "19")]
    pub energy_excess: Vec<f64>,
    /// The design's F̃ (N): stage 2's static mean contact force, the objective, repeated on
    /// every sample (a line in the Plot panel beside the simulated forces; NaN when not
    /// computed).
    #[prost(double, repeated, tag = "20")]
    pub mean_force_objective: Vec<f64>,
    /// Finger 2's q11 (rad, in its own mirrored frame), offset scene only (finger 2 is not
    /// finger 1's mirror image there); empty otherwise.
    #[prost(double, repeated, tag = "21")]
    pub finger2_q11: Vec<f64>,
    /// Finger 2's q21 (rad, in its own mirrored frame), offset scene only; empty otherwise.
    #[prost(double, repeated, tag = "22")]
    pub finger2_q21: Vec<f64>,
    /// Finger 2's q̇11 (rad/s), offset scene only (since session 37); empty otherwise.
    #[prost(double, repeated, tag = "23")]
    pub finger2_q11_dot: Vec<f64>,
    /// Finger 2's q̇21 (rad/s), offset scene only.
    #[prost(double, repeated, tag = "24")]
    pub finger2_q21_dot: Vec<f64>,
    /// Finger 2's θ2 (rad), offset scene only.
    #[prost(double, repeated, tag = "25")]
    pub finger2_theta2: Vec<f64>,
    /// Finger 2's proximal penetration (m), offset scene only.
    #[prost(double, repeated, tag = "26")]
    pub finger2_proximal_penetration: Vec<f64>,
    /// Finger 2's distal penetration (m), offset scene only.
    #[prost(double, repeated, tag = "27")]
    pub finger2_distal_penetration: Vec<f64>,
    /// Finger 2's proximal normal force (N), offset scene only.
    #[prost(double, repeated, tag = "28")]
    pub finger2_proximal_normal_force: Vec<f64>,
    /// Finger 2's distal normal force (N), offset scene only.
    #[prost(double, repeated, tag = "29")]
    pub finger2_distal_normal_force: Vec<f64>,
    /// Finger 2's proximal friction force (N, on the finger along its t_c), offset scene only.
    #[prost(double, repeated, tag = "30")]
    pub finger2_proximal_friction_force: Vec<f64>,
    /// Finger 2's distal friction force (N), offset scene only.
    #[prost(double, repeated, tag = "31")]
    pub finger2_distal_friction_force: Vec<f64>,
}

/// `column` and `column_mut`: a repeated double field of [`GraspSeries`] by its name (the
/// one place the message's fields are named besides their declaration).
macro_rules! columns_by_name {
    ($($field:ident),* $(,)?) => {
        impl GraspSeries {
            /// The column of the repeated field `name` (None: no such field).
            pub fn column(&self, name: &str) -> Option<&Vec<f64>> {
                match name {
                    $(stringify!($field) => Some(&self.$field),)*
                    _ => None,
                }
            }
            /// The column of the repeated field `name`, mutable.
            pub fn column_mut(&mut self, name: &str) -> Option<&mut Vec<f64>> {
                match name {
                    $(stringify!($field) => Some(&mut self.$field),)*
                    _ => None,
                }
            }
        }
    };
}

columns_by_name!(
    t,
    q11,
    q21,
    q11_dot,
    q21_dot,
    theta2,
    proximal_penetration,
    distal_penetration,
    proximal_normal_force,
    distal_normal_force,
    proximal_friction_force,
    distal_friction_force,
    hand_force,
    filtered_hand_force,
    energy,
    energy_excess,
    mean_force_objective,
    finger2_q11,
    finger2_q21,
    finger2_q11_dot,
    finger2_q21_dot,
    finger2_theta2,
    finger2_proximal_penetration,
    finger2_distal_penetration,
    finger2_proximal_normal_force,
    finger2_distal_normal_force,
    finger2_proximal_friction_force,
    finger2_distal_friction_force,
);

/// The field after a sample's values: the design's F̃ repeated on every sample.
pub const MEAN_FORCE_FIELD: &str = "mean_force_objective";

impl GraspSeries {
    /// Finger 2's columns (offset scene), in the order of `sim::FINGER_COLUMNS`.
    pub fn finger2_columns(&self) -> [&Vec<f64>; 11] {
        FINGER_COLUMNS.map(|c| self.column(c.finger2_series).expect("finger 2's fields are the series'"))
    }
}

/// (name, number, type, repeated) of every field of [`GraspSeries`], in tag order: the
/// design's id, resolution and sample count, the time, a sample's values named by the
/// trajectory vocabulary (`sim::SAMPLE_COLUMNS`, each its `/grasp/series` field) and the
/// design's F̃; with `finger2` (a shard of the offset scene) finger 2's own values after them
/// (their angles since session 36, the rest since session 37).
pub fn series_fields(finger2: bool) -> Vec<(&'static str, i32, Type, bool)> {
    let head = [
        ("design_id", Type::Uint64, false),
        ("full_resolution", Type::Bool, false),
        ("simulated_samples", Type::Uint32, false),
        (TIME.series, Type::Double, true),
    ];
    let values = sample_series_fields().chain([MEAN_FORCE_FIELD]).map(|f| (f, Type::Double, true));
    let f2 = FINGER_COLUMNS.iter().filter(|_| finger2).map(|c| (c.finger2_series, Type::Double, true));
    head.into_iter().chain(values).chain(f2).zip(1..).map(|((name, ty, rep), tag)| (name, tag, ty, rep)).collect()
}

/// The serialized `FileDescriptorSet` of `gripopt.GraspSeries` (proto3): [`series_fields`]
/// (finger 2's only with `finger2`, a shard of the offset scene — a centred run's shards
/// keep the schema, and so the bytes, they always had).
pub fn series_descriptor(finger2: bool) -> Vec<u8> {
    let field = |(name, number, ty, repeated): (&str, i32, Type, bool)| FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(if repeated { Label::Repeated } else { Label::Optional } as i32),
        r#type: Some(ty as i32),
        json_name: Some(name.into()),
        ..Default::default()
    };
    let msg = DescriptorProto {
        name: Some("GraspSeries".into()),
        field: series_fields(finger2).into_iter().map(field).collect(),
        ..Default::default()
    };
    let file = FileDescriptorProto {
        name: Some("gripopt/GraspSeries.proto".into()),
        package: Some("gripopt".into()),
        message_type: vec![msg],
        syntax: Some("proto3".into()),
        ..Default::default()
    };
    FileDescriptorSet { file: vec![file] }.encode_to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptor_matches_the_encoding() {
        // every column gets a distinct value through its name; decode the bytes by hand with
        // the table built from the vocabulary
        let mut m = GraspSeries { design_id: 7, full_resolution: true, simulated_samples: 3, ..Default::default() };
        let fields = series_fields(true);
        for (name, tag, ty, _) in &fields {
            if *ty == Type::Double {
                m.column_mut(name).unwrap_or_else(|| panic!("{name}: not a field")).push(*tag as f64 - 3.5);
            }
        }
        let b = m.encode_to_vec();
        let mut i = 0;
        let mut seen = vec![];
        while i < b.len() {
            // the key is a varint (two bytes from tag 16 on)
            let (mut key, mut shift) = (0u32, 0);
            loop {
                key |= ((b[i] & 0x7f) as u32) << shift;
                shift += 7;
                i += 1;
                if b[i - 1] < 0x80 {
                    break;
                }
            }
            let (tag, wire) = ((key >> 3) as i32, (key & 7) as u8);
            let (_, _, ty, rep) = fields.iter().find(|f| f.1 == tag).copied().expect("field in the table");
            match (ty, rep) {
                (Type::Double, true) => {
                    assert_eq!((wire, b[i]), (2, 8), "packed double");
                    let v = f64::from_le_bytes(b[i + 1..i + 9].try_into().unwrap());
                    assert_eq!(v, (tag - 4) as f64 + 0.5, "field {tag}");
                    i += 9;
                }
                _ => {
                    assert_eq!(wire, 0, "varint field {tag}");
                    i += 1;
                }
            }
            seen.push(tag);
        }
        assert_eq!(seen, (1..=31).collect::<Vec<_>>());
        // the fields of every recording written keep their names and tags
        for pinned in [("t", 4), ("proximal_penetration", 10), ("energy_excess", 19), ("mean_force_objective", 20)] {
            assert!(fields.iter().any(|f| (f.0, f.1) == pinned), "{pinned:?}");
        }
        assert!(fields.iter().any(|f| (f.0, f.1) == ("finger2_distal_friction_force", 31)));
        // the centred scene's schema is the one of older recordings: the offset fields only with `finger2`
        let (plain, with2) = (series_descriptor(false), series_descriptor(true));
        let names = |b: &[u8]| {
            let set = FileDescriptorSet::decode(b).unwrap();
            set.file[0].message_type[0].field.iter().map(|f| f.number()).collect::<Vec<_>>()
        };
        assert_eq!((names(&plain), names(&with2)), ((1..=20).collect(), (1..=31).collect()));
    }
}
