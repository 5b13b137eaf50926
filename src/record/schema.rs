//! JSON schemas of the recorded channels (jsonschema encoding, so Foxglove plots every
//! numeric field without custom code).

use serde_json::{json, Value};

fn num() -> Value {
    json!({"type": "number"})
}
fn num_or_null() -> Value {
    json!({"type": ["number", "null"]})
}
fn obj(props: Value, required: &[&str]) -> Value {
    json!({"type": "object", "properties": props, "required": required})
}

/// `gripopt.Design` on `/designs`.
pub fn design() -> Value {
    let mut s = obj(
        json!({
            "id": {"type": "integer", "minimum": 0},
            "generation": {"type": "integer", "minimum": 1},
            "problem": {"type": "string"},
            "window_start_s": num(),
            "parameters": obj(json!({"l21": num(), "b": num(), "t22": num(), "r": num(), "p": num(), "psi_deg": num()}), &["l21", "b", "t22", "r", "p", "psi_deg"]),
            "derived": obj(json!({"l11": num_or_null(), "l12": num_or_null(), "l22": num_or_null(), "l_hand": num()}), &["l11", "l12", "l22", "l_hand"]),
            "stages_passed": {"type": "integer", "minimum": 0, "maximum": 4},
            "feasible": {"type": "boolean"},
            "failed_stage": {"type": ["integer", "null"]},
            "reason": {"type": ["string", "null"]},
            "violation": num_or_null(),
            "objectives": obj(json!({"max_offset": num_or_null(), "alpha": num_or_null(), "mean_force": num_or_null(), "t_stab": num_or_null()}), &["max_offset", "alpha", "mean_force", "t_stab"]),
            "stage_seconds": obj(json!({"stages_0_1": num(), "stage_2": num(), "stage_3": num()}), &["stages_0_1", "stage_2", "stage_3"]),
            "sim_steps": {"type": ["integer", "null"]},
            "sim_rhs_evals": {"type": ["integer", "null"]},
            "trajectory_samples": {"type": "integer", "minimum": 0}
        }),
        &["id", "generation", "problem", "window_start_s", "parameters", "derived", "stages_passed", "feasible", "failed_stage", "reason", "violation", "objectives", "stage_seconds", "sim_steps", "sim_rhs_evals", "trajectory_samples"],
    );
    s["title"] = "gripopt.Design".into();
    s
}

fn finger() -> Value {
    obj(json!({"q11": num(), "q21": num(), "q11_dot": num(), "q21_dot": num(), "theta1": num(), "theta2": num()}), &["q11", "q21", "q11_dot", "q21_dot", "theta1", "theta2"])
}

/// `gripopt.Joints` on `/grasp/joints` (local joint coordinates; finger 2 mirrors finger 1).
pub fn joints() -> Value {
    let mut s = obj(json!({"design_id": {"type": "integer"}, "t": num(), "finger1": finger(), "finger2": finger()}), &["design_id", "t", "finger1", "finger2"]);
    s["title"] = "gripopt.Joints".into();
    s
}

fn contact() -> Value {
    obj(json!({"penetration": num(), "normal_force": num(), "friction_force": num()}), &["penetration", "normal_force", "friction_force"])
}

/// `gripopt.Contacts` on `/grasp/contacts`.
pub fn contacts() -> Value {
    let v2 = obj(json!({"x": num(), "y": num()}), &["x", "y"]);
    let mut s = obj(
        json!({"design_id": {"type": "integer"}, "t": num(), "proximal": contact(), "distal": contact(), "hand_force": v2.clone(), "filtered_hand_force": v2}),
        &["design_id", "t", "proximal", "distal", "hand_force", "filtered_hand_force"],
    );
    s["title"] = "gripopt.Contacts".into();
    s
}

/// `gripopt.Energy` on `/grasp/energy`.
pub fn energy() -> Value {
    let mut s = obj(json!({"design_id": {"type": "integer"}, "t": num(), "energy": num(), "energy_excess": num()}), &["design_id", "t", "energy", "energy_excess"]);
    s["title"] = "gripopt.Energy".into();
    s
}

/// The subset of Foxglove's `foxglove.SceneUpdate` JSON schema that the recorder uses
/// (all fields of the primitives written are described; unused primitive lists are empty arrays).
pub fn scene_update() -> Value {
    let vec3 = obj(json!({"x": num(), "y": num(), "z": num()}), &["x", "y", "z"]);
    let quat = obj(json!({"x": num(), "y": num(), "z": num(), "w": num()}), &["x", "y", "z", "w"]);
    let pose = obj(json!({"position": vec3.clone(), "orientation": quat}), &["position", "orientation"]);
    let color = obj(json!({"r": num(), "g": num(), "b": num(), "a": num()}), &["r", "g", "b", "a"]);
    let time = obj(json!({"sec": {"type": "integer"}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}), &["sec", "nsec"]);
    let line = obj(
        json!({"type": {"type": "integer", "enum": [0, 1, 2]}, "pose": pose.clone(), "thickness": num(), "scale_invariant": {"type": "boolean"},
               "points": {"type": "array", "items": vec3.clone()}, "color": color.clone(), "colors": {"type": "array", "items": color.clone()},
               "indices": {"type": "array", "items": {"type": "integer"}}}),
        &["type", "pose", "thickness", "scale_invariant", "points", "color", "colors", "indices"],
    );
    let cyl = obj(json!({"pose": pose.clone(), "size": vec3.clone(), "bottom_scale": num(), "top_scale": num(), "color": color.clone()}), &["pose", "size", "bottom_scale", "top_scale", "color"]);
    let cube = obj(json!({"pose": pose, "size": vec3, "color": color}), &["pose", "size", "color"]);
    let kv = obj(json!({"key": {"type": "string"}, "value": {"type": "string"}}), &["key", "value"]);
    let empty = json!({"type": "array", "maxItems": 0});
    let entity = obj(
        json!({"timestamp": time.clone(), "frame_id": {"type": "string"}, "id": {"type": "string"}, "lifetime": time,
               "frame_locked": {"type": "boolean"}, "metadata": {"type": "array", "items": kv},
               "arrows": empty.clone(), "cubes": {"type": "array", "items": cube}, "spheres": empty.clone(),
               "cylinders": {"type": "array", "items": cyl}, "lines": {"type": "array", "items": line},
               "triangles": empty.clone(), "texts": empty.clone(), "models": empty}),
        &["timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata", "arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"],
    );
    let mut s = obj(json!({"deletions": {"type": "array", "maxItems": 0}, "entities": {"type": "array", "items": entity}}), &["deletions", "entities"]);
    s["title"] = "foxglove.SceneUpdate".into();
    s
}
