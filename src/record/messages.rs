//! Building the messages of one design: the `/designs` JSON record, the
//! `gripopt.GraspSeries` columns, and the Foxglove scene (official `foxglove` SDK types).

use super::entry::DesignEntry;
use super::options::{RecordOptions, Resolution};
use super::proto::GraspSeries;
use super::schema::{Derived, DesignMessage, DesignParameters, Objectives, StageSeconds, Window};
use crate::math::V2;
use crate::model::Finger;
use crate::params::{Design, SceneParams};
use crate::sim::{PoseSample, Sample};
use foxglove::messages::{
    line_primitive, scene_entity_deletion, Color, CubePrimitive, CylinderPrimitive, Duration, FrameTransform,
    FrameTransforms, KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity, SceneEntityDeletion,
    SceneUpdate, Timestamp, Vector3,
};

/// Log time (ns since 1970) at which design `id`'s window starts: `epoch_ns + id` s.
pub fn window_start_ns(epoch_ns: u64, id: u64) -> u64 {
    epoch_ns + id * 1_000_000_000
}

/// Log time of simulated time `t` in the window starting at `t0_ns` (inside the window).
pub fn log_time(t0_ns: u64, t: f64) -> u64 {
    t0_ns + (t * 1e9).round().clamp(0.0, 999_999_999.0) as u64
}

fn stamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000).min(u32::MAX as u64) as u32, (ns % 1_000_000_000) as u32)
}

/// `/designs` message of a design whose window starts at `t0_ns`, derived from its
/// evaluation record. Values that were not computed are left out (no nulls, so the schema
/// needs no union types).
pub fn design(i: &DesignEntry<'_>, problem: &str, t0_ns: u64, epoch_s: u64) -> DesignMessage {
    let r = i.record;
    let v = &r.verdict;
    let o = r.objectives();
    let l = r.lengths();
    DesignMessage {
        id: i.id,
        generation: i.generation,
        problem: problem.to_string(),
        window_start: Window { sec: t0_ns / 1_000_000_000, nsec: t0_ns % 1_000_000_000 },
        window_start_s: i.id as f64,
        epoch_s,
        parameters: DesignParameters::from_array(&i.parameters),
        derived: Derived {
            l11: l.map(|l| l[0]),
            l12: l.map(|l| l[1]),
            l22: l.map(|l| l[2]),
            l_hand: r.kinematics.l_hand,
        },
        stages_passed: v.failed_stage.unwrap_or(4),
        feasible: v.failed_stage.is_none(),
        form_closed: r.form_closed(),
        failed_stage: v.failed_stage,
        reason: v.reason.clone(),
        violation: v.violation,
        // MODEL.md §6.7: a design not form closed at 0 carries max_offset = −Δ_off inside the
        // optimiser; the record says form_closed = false and leaves max_offset out (as the CSVs)
        objectives: Objectives { max_offset: o[0].filter(|m| *m >= 0.0), alpha: o[1], mean_force: o[2], t_stab: o[3] },
        stage_seconds: StageSeconds {
            stages_0_1: i.stage_seconds[1],
            stage_2: i.stage_seconds[2],
            stage_3: i.stage_seconds[3],
        },
        sim_steps: r.sim_work().map(|w| w[0]),
        sim_rhs_evals: r.sim_work().map(|w| w[1]),
        free_scene: r.free_scene.clone(),
        trajectory_samples: i.trajectory.map_or(0, |t| t.samples.len() as u64),
    }
}

/// A value as recorded at `res` (f32 precision when compact).
pub fn at_precision(x: f64, res: Resolution) -> f64 {
    match res {
        Resolution::Full => x,
        Resolution::Compact => x as f32 as f64,
    }
}

/// The `/grasp/series` message of design `id` from the selected samples (empty when the
/// design has no trajectory).
pub fn series(id: u64, samples: &[Sample], kept: &[usize], opts: &RecordOptions) -> GraspSeries {
    let r = opts.resolution;
    let mut m = GraspSeries {
        design_id: id,
        full_resolution: r == Resolution::Full,
        simulated_samples: samples.len() as u32,
        ..Default::default()
    };
    for &k in kept {
        let s = &samples[k];
        let p = |x: f64| at_precision(x, r);
        m.t.push(s.t);
        m.q11.push(p(s.q[0]));
        m.q21.push(p(s.q[1]));
        m.q11_dot.push(p(s.qd[0]));
        m.q21_dot.push(p(s.qd[1]));
        m.theta2.push(p(s.theta2));
        m.proximal_penetration.push(p(s.delta[0]));
        m.distal_penetration.push(p(s.delta[1]));
        m.proximal_normal_force.push(p(s.normal[0]));
        m.distal_normal_force.push(p(s.normal[1]));
        m.proximal_friction_force.push(p(s.friction[0]));
        m.distal_friction_force.push(p(s.friction[1]));
        m.hand_force.push(p(s.hand_fy));
        m.filtered_hand_force.push(p(s.filtered_fy));
        m.energy.push(p(s.energy));
        m.energy_excess.push(p(s.energy_excess));
    }
    m
}

/// Samples back from a `/grasp/series` message (replay); `None` if its columns differ in length.
pub fn samples_from(m: &GraspSeries) -> Option<Vec<Sample>> {
    let n = m.t.len();
    let cols = [
        &m.q11,
        &m.q21,
        &m.q11_dot,
        &m.q21_dot,
        &m.theta2,
        &m.proximal_penetration,
        &m.distal_penetration,
        &m.proximal_normal_force,
        &m.distal_normal_force,
        &m.proximal_friction_force,
        &m.distal_friction_force,
        &m.hand_force,
        &m.filtered_hand_force,
        &m.energy,
        &m.energy_excess,
    ];
    if cols.iter().any(|c| c.len() != n) {
        return None;
    }
    Some(
        (0..n)
            .map(|k| Sample {
                t: m.t[k],
                q: [m.q11[k], m.q21[k]],
                qd: [m.q11_dot[k], m.q21_dot[k]],
                theta2: m.theta2[k],
                delta: [m.proximal_penetration[k], m.distal_penetration[k]],
                normal: [m.proximal_normal_force[k], m.distal_normal_force[k]],
                friction: [m.proximal_friction_force[k], m.distal_friction_force[k]],
                hand_fy: m.hand_force[k],
                filtered_fy: m.filtered_hand_force[k],
                energy: m.energy[k],
                energy_excess: m.energy_excess[k],
            })
            .collect(),
    )
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Option<Color> {
    Some(Color { r, g, b, a })
}

fn at(x: f64, y: f64, z: f64) -> Option<Pose> {
    Some(Pose { position: Some(Vector3 { x, y, z }), orientation: Some(Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }) })
}

fn entity(t_ns: u64, frame: &str, id: &str, design_id: u64) -> SceneEntity {
    SceneEntity {
        timestamp: Some(stamp(t_ns)),
        frame_id: frame.into(),
        id: id.into(),
        lifetime: Some(Duration::new(0, 0)),
        metadata: vec![KeyValuePair { key: "design_id".into(), value: design_id.to_string() }],
        ..Default::default()
    }
}

fn delete_all(t_ns: u64) -> Vec<SceneEntityDeletion> {
    vec![SceneEntityDeletion {
        timestamp: Some(stamp(t_ns)),
        r#type: scene_entity_deletion::Type::All as i32,
        id: String::new(),
    }]
}

/// `/tf` message at a design's window start: `world` (z up, ground at z = 0) → `hand`
/// (the model's plane: x across the palm, y from the palm towards the object, which lies
/// on the ground; so the hand looks down, its palm 2 r above the ground).
pub fn frames(t_ns: u64, sc: &SceneParams) -> FrameTransforms {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    FrameTransforms {
        transforms: vec![FrameTransform {
            timestamp: Some(stamp(t_ns)),
            parent_frame_id: "world".into(),
            child_frame_id: "hand".into(),
            translation: Some(Vector3 { x: 0.0, y: 0.0, z: 2.0 * sc.object.radius }),
            // −90° about x: hand y → world −z, hand z (the object's axis) → world y
            rotation: Some(Quaternion { x: -h, y: 0.0, z: 0.0, w: h }),
        }],
    }
}

/// `/scene/static` message at a design's window start: it first deletes everything of the
/// previous design on this topic, then draws the ground plane (frame `world`), the palm
/// (width b + 2 cm) and the object (frame `hand`). Its latest message is always valid.
pub fn static_scene(t_ns: u64, id: u64, design: &Design, sc: &SceneParams) -> SceneUpdate {
    let r = sc.object.radius;
    let object = object_entity(t_ns, "hand", id, sc, at(0.0, r, 0.0));
    SceneUpdate {
        deletions: delete_all(t_ns),
        entities: vec![ground_entity(t_ns, id), palm_entity(t_ns, id, design), object],
    }
}

/// The ground plane (frame `world`, top face at z = 0).
fn ground_entity(t_ns: u64, id: u64) -> SceneEntity {
    let mut ground = entity(t_ns, "world", "ground", id);
    ground.cubes.push(CubePrimitive {
        pose: at(0.0, 0.0, -0.0005),
        size: Some(Vector3 { x: 0.6, y: 0.6, z: 0.001 }),
        color: rgba(0.55, 0.55, 0.5, 1.0),
    });
    ground
}

/// The palm (frame `hand`: width b + 2 cm, its face the line y = 0, 4 cm across the plane).
fn palm_entity(t_ns: u64, id: u64, design: &Design) -> SceneEntity {
    let mut palm = entity(t_ns, "hand", "palm", id);
    palm.cubes.push(CubePrimitive {
        pose: at(0.0, -0.005, 0.0),
        size: Some(Vector3 { x: design.b + 0.02, y: 0.01, z: 0.04 }),
        color: rgba(0.5, 0.5, 0.5, 1.0),
    });
    palm
}

/// The bottle: a cylinder of radius R and length L_c along the z axis of `frame`, centred at `pose`.
fn object_entity(t_ns: u64, frame: &str, id: u64, sc: &SceneParams, pose: Option<Pose>) -> SceneEntity {
    let r = sc.object.radius;
    let mut object = entity(t_ns, frame, "object", id);
    object.cylinders.push(CylinderPrimitive {
        pose,
        size: Some(Vector3 { x: 2.0 * r, y: 2.0 * r, z: sc.object.length }),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: rgba(0.2, 0.5, 0.9, 0.5),
    });
    object
}

/// Round a coordinate to 2⁻²⁰ m (≈ 1 µm): invisible, and the zeroed low mantissa bits
/// compress well.
fn q(x: f64) -> f64 {
    (x * 1_048_576.0).round() / 1_048_576.0
}

/// `/scene` message: both fingers at sample `s` (a line strip per finger through tip, O22,
/// base, O12, O13, O22); with `first`, it first deletes the previous design's fingers.
/// `None` when there is no finger or the pose cannot be assembled (then, with `first`, a
/// message that only deletes).
pub fn scene(id: u64, t_ns: u64, finger: Option<&Finger>, s: Option<&Sample>, first: bool) -> Option<SceneUpdate> {
    let deletions = if first { delete_all(t_ns) } else { vec![] };
    let pose = finger.zip(s).and_then(|(f, s)| f.dgm(s.q[0], s.q[1]).ok().map(|p| (f, p)));
    let Some((finger, p)) = pose else {
        return first.then(|| SceneUpdate { deletions, entities: vec![] });
    };
    let mut e = entity(t_ns, "hand", "fingers", id);
    for mirror in [1.0, -1.0] {
        e.lines.push(finger_line(finger, &p, mirror));
    }
    Some(SceneUpdate { deletions, entities: vec![e] })
}

/// One finger at pose `p` as a line strip through tip, O22, base, O12, O13, O22 in the
/// hand's plane (`mirror` −1: finger 2, mirrored in x).
fn finger_line(finger: &Finger, p: &crate::model::Pose, mirror: f64) -> LinePrimitive {
    let chain: [V2; 6] = [finger.tip(p), p.o22, finger.o21, p.o12, p.o13, p.o22];
    LinePrimitive {
        r#type: line_primitive::Type::LineStrip as i32,
        pose: at(0.0, 0.0, 0.0),
        thickness: 2.0 * finger.w,
        scale_invariant: false,
        points: chain.iter().map(|v| Point3 { x: q(mirror * v.x), y: q(v.y), z: 0.0 }).collect(),
        color: rgba(0.9, 0.4, 0.1, 1.0),
        ..Default::default()
    }
}

// ---- the free scene (`gripopt verify`'s recording): the hand horizontal, the object a
// ---- rigid body whose pose is the frame `object`

/// `/tf` of the free scene at `t_ns`: with `hand`, `world` (z up, ground at z = 0) →
/// `hand` (the free scene's frame, MODEL.md §14.1: the hand plane z = 0 at h_c above the
/// ground, x along the palm, y toward the object, z up); always `hand` → `object` (origin at
/// G, axes the body's: its axis along z) from the pose sample.
pub fn free_frames(t_ns: u64, sc: &SceneParams, pose: &PoseSample, hand: bool) -> FrameTransforms {
    let mut transforms = Vec::with_capacity(2);
    if hand {
        transforms.push(FrameTransform {
            timestamp: Some(stamp(t_ns)),
            parent_frame_id: "world".into(),
            child_frame_id: "hand".into(),
            translation: Some(Vector3 { x: 0.0, y: 0.0, z: sc.object.grasp_height }),
            rotation: Some(Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }),
        });
    }
    let [w, x, y, z] = pose.q;
    let n = (w * w + x * x + y * y + z * z).sqrt();
    transforms.push(FrameTransform {
        timestamp: Some(stamp(t_ns)),
        parent_frame_id: "hand".into(),
        child_frame_id: "object".into(),
        translation: Some(Vector3 { x: pose.g[0], y: pose.g[1], z: pose.g[2] }),
        rotation: Some(Quaternion { x: x / n, y: y / n, z: z / n, w: w / n }),
    });
    FrameTransforms { transforms }
}

/// `/scene/static` of the free scene at a design's window start: deletes everything, then
/// the ground (frame `world`), the palm (frame `hand`) and the bottle (frame `object`,
/// centred at G, its axis along z).
pub fn free_static_scene(t_ns: u64, id: u64, design: &Design, sc: &SceneParams) -> SceneUpdate {
    let object = object_entity(t_ns, "object", id, sc, at(0.0, 0.0, 0.0));
    SceneUpdate {
        deletions: delete_all(t_ns),
        entities: vec![ground_entity(t_ns, id), palm_entity(t_ns, id, design), object],
    }
}

/// `/scene` of the free scene: both fingers, each at its own angles (`q`: q11, q21 of
/// finger 1, then of finger 2 in its mirrored frame); with `first`, it first deletes the
/// previous design's fingers. `None` when a pose cannot be assembled (then, with `first`,
/// a message that only deletes).
pub fn free_fingers(id: u64, t_ns: u64, finger: Option<&Finger>, q: [f64; 4], first: bool) -> Option<SceneUpdate> {
    let deletions = if first { delete_all(t_ns) } else { vec![] };
    let poses = finger.and_then(|f| Some((f, f.dgm(q[0], q[1]).ok()?, f.dgm(q[2], q[3]).ok()?)));
    let Some((finger, p1, p2)) = poses else {
        return first.then(|| SceneUpdate { deletions, entities: vec![] });
    };
    let mut e = entity(t_ns, "hand", "fingers", id);
    e.lines.push(finger_line(finger, &p1, 1.0));
    e.lines.push(finger_line(finger, &p2, -1.0));
    Some(SceneUpdate { deletions, entities: vec![e] })
}
