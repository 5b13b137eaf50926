//! gripopt's protobuf message `gripopt.ScenarioSeries` (one per design of a robust run's
//! shard on `/scenario/series`): the scenario its recording draws as columns against the
//! scenario's simulated time — the free object's horizontal displacement and tilt, each
//! phalanx's penetration and normal force and both fingers' angles — for the robust layout's
//! plots. Its schema (a serialized `FileDescriptorSet`) is built from [`SCENARIO_FIELDS`], the
//! one list of its fields, which a unit test decodes against.

use prost::Message;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// Full name of the message (the MCAP schema name).
pub const SCENARIO_SERIES_NAME: &str = "gripopt.ScenarioSeries";

/// The scenario a robust design's window draws, as columns (all as long as `t`; values at f32
/// precision, times exact). A design without a drawn scenario has one placeholder sample (t =
/// 0, every value NaN, `simulated_samples` 0), so a Plot panel redraws empty.
#[derive(Clone, PartialEq, Message)]
pub struct ScenarioSeries {
    /// Design id.
    #[prost(uint64, tag = "1")]
    pub design_id: u64,
    /// The scenario's object (`[[robust.objects]] name`).
    #[prost(string, tag = "2")]
    pub object: String,
    /// The scenario's index among the object's.
    #[prost(uint32, tag = "3")]
    pub scenario_index: u32,
    /// True when the series is the scenario's free scene; false: its centred grasp (the free
    /// scene did not run; the object is fixed, displacement and tilt NaN).
    #[prost(bool, tag = "4")]
    pub free_scene: bool,
    /// Samples of the simulation before selection (0: the placeholder).
    #[prost(uint32, tag = "5")]
    pub simulated_samples: u32,
    /// Simulated time (s), exact.
    #[prost(double, repeated, tag = "6")]
    pub t: Vec<f64>,
    /// |G_xy(t) − G_xy(0)| of the free object (mm).
    #[prost(double, repeated, tag = "7")]
    pub displacement_mm: Vec<f64>,
    /// Angle between the object's axis and the vertical (°).
    #[prost(double, repeated, tag = "8")]
    pub tilt_deg: Vec<f64>,
    /// Finger 1's proximal normal force (N).
    #[prost(double, repeated, tag = "9")]
    pub finger1_proximal_normal_force: Vec<f64>,
    /// Finger 1's distal normal force (N).
    #[prost(double, repeated, tag = "10")]
    pub finger1_distal_normal_force: Vec<f64>,
    /// Finger 2's proximal normal force (N).
    #[prost(double, repeated, tag = "11")]
    pub finger2_proximal_normal_force: Vec<f64>,
    /// Finger 2's distal normal force (N).
    #[prost(double, repeated, tag = "12")]
    pub finger2_distal_normal_force: Vec<f64>,
    /// Finger 1's proximal penetration δ (m).
    #[prost(double, repeated, tag = "13")]
    pub finger1_proximal_penetration: Vec<f64>,
    /// Finger 1's distal penetration (m).
    #[prost(double, repeated, tag = "14")]
    pub finger1_distal_penetration: Vec<f64>,
    /// Finger 2's proximal penetration (m).
    #[prost(double, repeated, tag = "15")]
    pub finger2_proximal_penetration: Vec<f64>,
    /// Finger 2's distal penetration (m).
    #[prost(double, repeated, tag = "16")]
    pub finger2_distal_penetration: Vec<f64>,
    /// Finger 1's q11 (rad).
    #[prost(double, repeated, tag = "17")]
    pub finger1_q11: Vec<f64>,
    /// Finger 1's q21 = θ1 (rad).
    #[prost(double, repeated, tag = "18")]
    pub finger1_q21: Vec<f64>,
    /// Finger 2's q11 (rad, in its own mirrored frame).
    #[prost(double, repeated, tag = "19")]
    pub finger2_q11: Vec<f64>,
    /// Finger 2's q21 (rad, in its own mirrored frame).
    #[prost(double, repeated, tag = "20")]
    pub finger2_q21: Vec<f64>,
}

/// (name, tag, type, repeated) of every field of [`ScenarioSeries`], in tag order.
pub const SCENARIO_FIELDS: [(&str, i32, Type, bool); 20] = [
    ("design_id", 1, Type::Uint64, false),
    ("object", 2, Type::String, false),
    ("scenario_index", 3, Type::Uint32, false),
    ("free_scene", 4, Type::Bool, false),
    ("simulated_samples", 5, Type::Uint32, false),
    ("t", 6, Type::Double, true),
    ("displacement_mm", 7, Type::Double, true),
    ("tilt_deg", 8, Type::Double, true),
    ("finger1_proximal_normal_force", 9, Type::Double, true),
    ("finger1_distal_normal_force", 10, Type::Double, true),
    ("finger2_proximal_normal_force", 11, Type::Double, true),
    ("finger2_distal_normal_force", 12, Type::Double, true),
    ("finger1_proximal_penetration", 13, Type::Double, true),
    ("finger1_distal_penetration", 14, Type::Double, true),
    ("finger2_proximal_penetration", 15, Type::Double, true),
    ("finger2_distal_penetration", 16, Type::Double, true),
    ("finger1_q11", 17, Type::Double, true),
    ("finger1_q21", 18, Type::Double, true),
    ("finger2_q11", 19, Type::Double, true),
    ("finger2_q21", 20, Type::Double, true),
];

impl ScenarioSeries {
    /// The value columns after `t`, in tag order.
    pub fn columns_mut(&mut self) -> [&mut Vec<f64>; 14] {
        [
            &mut self.displacement_mm,
            &mut self.tilt_deg,
            &mut self.finger1_proximal_normal_force,
            &mut self.finger1_distal_normal_force,
            &mut self.finger2_proximal_normal_force,
            &mut self.finger2_distal_normal_force,
            &mut self.finger1_proximal_penetration,
            &mut self.finger1_distal_penetration,
            &mut self.finger2_proximal_penetration,
            &mut self.finger2_distal_penetration,
            &mut self.finger1_q11,
            &mut self.finger1_q21,
            &mut self.finger2_q11,
            &mut self.finger2_q21,
        ]
    }

    /// Append one sample: time `t` and the 14 values in the order of [`Self::columns_mut`].
    pub fn push(&mut self, t: f64, values: [f64; 14]) {
        self.t.push(t);
        for (c, v) in self.columns_mut().into_iter().zip(values) {
            c.push(v);
        }
    }
}

/// The serialized `FileDescriptorSet` of `gripopt.ScenarioSeries` (proto3).
pub fn scenario_series_descriptor() -> Vec<u8> {
    let field = |&(name, number, ty, repeated): &(&str, i32, Type, bool)| FieldDescriptorProto {
        name: Some(name.into()),
        number: Some(number),
        label: Some(if repeated { Label::Repeated } else { Label::Optional } as i32),
        r#type: Some(ty as i32),
        json_name: Some(name.into()),
        ..Default::default()
    };
    let msg = DescriptorProto {
        name: Some("ScenarioSeries".into()),
        field: SCENARIO_FIELDS.iter().map(field).collect(),
        ..Default::default()
    };
    let file = FileDescriptorProto {
        name: Some("gripopt/ScenarioSeries.proto".into()),
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

    /// The descriptor says what prost writes: a message whose every column holds its own tag
    /// is decoded by hand, field by field, with the table.
    #[test]
    fn the_descriptor_matches_the_encoding() {
        let mut m = ScenarioSeries {
            design_id: 7,
            object: "can".into(),
            scenario_index: 3,
            free_scene: true,
            simulated_samples: 9,
            ..Default::default()
        };
        m.push(6.0, std::array::from_fn(|j| (7 + j) as f64));
        let b = m.encode_to_vec();
        let (mut i, mut seen) = (0, vec![]);
        while i < b.len() {
            // the key is a varint (two bytes from tag 16 on)
            let (mut v, mut shift) = (0u32, 0);
            loop {
                v |= ((b[i] & 0x7f) as u32) << shift;
                (shift, i) = (shift + 7, i + 1);
                if b[i - 1] < 0x80 {
                    break;
                }
            }
            let (key, wire) = ((v >> 3) as i32, (v & 7) as u8);
            let (name, _, ty, _) = SCENARIO_FIELDS.iter().find(|f| f.1 == key).copied().expect("a field of the table");
            match ty {
                Type::Double => {
                    assert_eq!((wire, b[i]), (2, 8), "{name}: one packed double");
                    assert_eq!(f64::from_le_bytes(b[i + 1..i + 9].try_into().unwrap()), key as f64, "{name}");
                    i += 9;
                }
                Type::String => {
                    assert_eq!((wire, &b[i + 1..i + 1 + b[i] as usize]), (2, &b"can"[..]), "{name}");
                    i += 1 + b[i] as usize;
                }
                _ => {
                    assert_eq!(wire, 0, "{name}: a varint");
                    i += 1;
                }
            }
            seen.push(key);
        }
        assert_eq!(seen, (1..=20).collect::<Vec<_>>());
        let set = FileDescriptorSet::decode(&scenario_series_descriptor()[..]).unwrap();
        let fields: Vec<(String, i32)> =
            set.file[0].message_type[0].field.iter().map(|f| (f.name().to_string(), f.number())).collect();
        assert_eq!(fields, SCENARIO_FIELDS.iter().map(|f| (f.0.to_string(), f.1)).collect::<Vec<_>>());
    }
}
