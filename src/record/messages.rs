//! Building the JSON messages of one design.

use crate::math::V2;
use crate::model::Finger;
use super::entry::DesignEntry;
use crate::params::{Design, SceneParams};
use crate::sim::Sample;
use serde_json::{json, Value};

/// Nanoseconds of the time window of design `id`: design k lives in [k s, k s + 1 s).
pub fn window_start_ns(id: u64) -> u64 {
    id * 1_000_000_000
}

/// `/designs` message.
pub fn design(i: &DesignEntry<'_>, problem: &str) -> Value {
    let x = &i.parameters;
    let l = i.lengths;
    let stages_passed = i.failed_stage.unwrap_or(4);
    json!({
        "id": i.id,
        "generation": i.generation,
        "problem": problem,
        "window_start_s": i.id as f64,
        "parameters": {"l21": x[0], "b": x[1], "t22": x[2], "r": x[3], "p": x[4], "psi_deg": x[5]},
        "derived": {"l11": l.map(|v| v[0]), "l12": l.map(|v| v[1]), "l22": l.map(|v| v[2]), "l_hand": i.l_hand},
        "stages_passed": stages_passed,
        "feasible": i.failed_stage.is_none(),
        "failed_stage": i.failed_stage,
        "reason": i.reason,
        "violation": i.violation,
        "objectives": {"max_offset": i.objectives[0], "alpha": i.objectives[1], "mean_force": i.objectives[2], "t_stab": i.objectives[3]},
        "stage_seconds": {"stages_0_1": i.stage_seconds[1], "stage_2": i.stage_seconds[2], "stage_3": i.stage_seconds[3]},
        "sim_steps": i.sim_work.map(|w| w[0]),
        "sim_rhs_evals": i.sim_work.map(|w| w[1]),
        "trajectory_samples": i.trajectory.map_or(0, |t| t.samples.len()),
    })
}

#[derive(serde::Serialize)]
struct FingerState {
    q11: f64,
    q21: f64,
    q11_dot: f64,
    q21_dot: f64,
    theta1: f64,
    theta2: f64,
}

/// `/grasp/joints` message (typed: this is the hot path of recording).
#[derive(serde::Serialize)]
pub struct Joints {
    design_id: u64,
    t: f64,
    finger1: FingerState,
    finger2: FingerState,
}

/// Build a `/grasp/joints` message.
pub fn joints(id: u64, s: &Sample) -> Joints {
    let f = || FingerState { q11: s.q[0], q21: s.q[1], q11_dot: s.qd[0], q21_dot: s.qd[1], theta1: s.q[1], theta2: s.theta2 };
    Joints { design_id: id, t: s.t, finger1: f(), finger2: f() }
}

#[derive(serde::Serialize)]
struct ContactState {
    penetration: f64,
    normal_force: f64,
    friction_force: f64,
}

#[derive(serde::Serialize)]
struct Xy {
    x: f64,
    y: f64,
}

/// `/grasp/contacts` message.
#[derive(serde::Serialize)]
pub struct Contacts {
    design_id: u64,
    t: f64,
    proximal: ContactState,
    distal: ContactState,
    hand_force: Xy,
    filtered_hand_force: Xy,
}

/// Build a `/grasp/contacts` message.
pub fn contacts(id: u64, s: &Sample) -> Contacts {
    let c = |k: usize| ContactState { penetration: s.delta[k], normal_force: s.normal[k], friction_force: s.friction[k] };
    Contacts { design_id: id, t: s.t, proximal: c(0), distal: c(1), hand_force: Xy { x: 0.0, y: s.hand_fy }, filtered_hand_force: Xy { x: 0.0, y: s.filtered_fy } }
}

/// `/grasp/energy` message.
#[derive(serde::Serialize)]
pub struct Energy {
    design_id: u64,
    t: f64,
    energy: f64,
    energy_excess: f64,
}

/// Build a `/grasp/energy` message.
pub fn energy(id: u64, s: &Sample) -> Energy {
    Energy { design_id: id, t: s.t, energy: s.energy, energy_excess: s.energy_excess }
}

/// Rebuild a trajectory sample from the three recorded messages (replay).
pub fn sample_from(j: &Value, c: &Value, e: &Value) -> Option<Sample> {
    let f = |v: &Value| v.as_f64();
    let g = &j["finger1"];
    Some(Sample {
        t: f(&j["t"])?,
        q: [f(&g["q11"])?, f(&g["q21"])?],
        qd: [f(&g["q11_dot"])?, f(&g["q21_dot"])?],
        theta2: f(&g["theta2"])?,
        delta: [f(&c["proximal"]["penetration"])?, f(&c["distal"]["penetration"])?],
        normal: [f(&c["proximal"]["normal_force"])?, f(&c["distal"]["normal_force"])?],
        friction: [f(&c["proximal"]["friction_force"])?, f(&c["distal"]["friction_force"])?],
        hand_fy: f(&c["hand_force"]["y"])?,
        filtered_fy: f(&c["filtered_hand_force"]["y"])?,
        energy: f(&e["energy"])?,
        energy_excess: f(&e["energy_excess"])?,
    })
}

#[derive(serde::Serialize, Clone, Copy)]
struct P3 {
    x: f64,
    y: f64,
    z: f64,
}
#[derive(serde::Serialize, Clone, Copy)]
struct Quat {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}
#[derive(serde::Serialize, Clone, Copy)]
struct Pose {
    position: P3,
    orientation: Quat,
}
#[derive(serde::Serialize, Clone, Copy)]
struct Rgba {
    r: f64,
    g: f64,
    b: f64,
    a: f64,
}
#[derive(serde::Serialize, Clone, Copy)]
struct Time {
    sec: u64,
    nsec: u64,
}
#[derive(serde::Serialize)]
struct Line {
    r#type: u8,
    pose: Pose,
    thickness: f64,
    scale_invariant: bool,
    points: Vec<P3>,
    color: Rgba,
    colors: [Rgba; 0],
    indices: [u32; 0],
}
#[derive(serde::Serialize)]
struct Cylinder {
    pose: Pose,
    size: P3,
    bottom_scale: f64,
    top_scale: f64,
    color: Rgba,
}
#[derive(serde::Serialize)]
struct Cube {
    pose: Pose,
    size: P3,
    color: Rgba,
}
#[derive(serde::Serialize)]
struct KeyValue {
    key: &'static str,
    value: String,
}
#[derive(serde::Serialize)]
struct Entity {
    timestamp: Time,
    frame_id: &'static str,
    id: &'static str,
    lifetime: Time,
    frame_locked: bool,
    metadata: Vec<KeyValue>,
    arrows: [u8; 0],
    cubes: Vec<Cube>,
    spheres: [u8; 0],
    cylinders: Vec<Cylinder>,
    lines: Vec<Line>,
    triangles: [u8; 0],
    texts: [u8; 0],
    models: [u8; 0],
}

/// `/scene` message (foxglove.SceneUpdate).
#[derive(serde::Serialize)]
pub struct SceneUpdate {
    deletions: [u8; 0],
    entities: Vec<Entity>,
}

fn pose(x: f64, y: f64, z: f64) -> Pose {
    Pose { position: P3 { x, y, z }, orientation: Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 } }
}

/// `/scene` message drawing both fingers at a sample (and, with `with_static`, the palm and
/// the object, which persist); `None` if the pose cannot be assembled.
pub fn scene(id: u64, t_ns: u64, design: &Design, finger: &Finger, sc: &SceneParams, s: &Sample, with_static: bool) -> Option<SceneUpdate> {
    let p = finger.dgm(s.q[0], s.q[1]).ok()?;
    let tip = finger.tip(&p);
    let base = finger.o21;
    let segs = [(base, p.o12), (p.o12, p.o13), (base, p.o22), (p.o22, p.o13), (p.o22, tip)];
    let mut pts = Vec::with_capacity(20);
    for mirror in [1.0, -1.0] {
        for (a, b) in segs {
            for v in [a, b] {
                let v: V2 = v;
                pts.push(P3 { x: mirror * v.x, y: v.y, z: 0.0 });
            }
        }
    }
    let timestamp = Time { sec: t_ns / 1_000_000_000, nsec: t_ns % 1_000_000_000 };
    let zero = Time { sec: 0, nsec: 0 };
    let entity = |eid: &'static str, cubes: Vec<Cube>, cylinders: Vec<Cylinder>, lines: Vec<Line>| Entity {
        timestamp,
        frame_id: "hand",
        id: eid,
        lifetime: zero,
        frame_locked: false,
        metadata: vec![KeyValue { key: "design_id", value: id.to_string() }],
        arrows: [],
        cubes,
        spheres: [],
        cylinders,
        lines,
        triangles: [],
        texts: [],
        models: [],
    };
    let mut entities = vec![entity(
        "fingers",
        vec![],
        vec![],
        vec![Line { r#type: 2, pose: pose(0.0, 0.0, 0.0), thickness: 2.0 * finger.w, scale_invariant: false, points: pts, color: Rgba { r: 0.9, g: 0.4, b: 0.1, a: 1.0 }, colors: [], indices: [] }],
    )];
    if with_static {
        let palm = Cube { pose: pose(0.0, -0.005, 0.0), size: P3 { x: design.b + 0.02, y: 0.01, z: 0.04 }, color: Rgba { r: 0.5, g: 0.5, b: 0.5, a: 1.0 } };
        let object = Cylinder { pose: pose(0.0, sc.object.radius, 0.0), size: P3 { x: 2.0 * sc.object.radius, y: 2.0 * sc.object.radius, z: sc.object.length }, bottom_scale: 1.0, top_scale: 1.0, color: Rgba { r: 0.2, g: 0.5, b: 0.9, a: 0.5 } };
        entities.push(entity("palm", vec![palm], vec![], vec![]));
        entities.push(entity("object", vec![], vec![object], vec![]));
    }
    Some(SceneUpdate { deletions: [], entities })
}
