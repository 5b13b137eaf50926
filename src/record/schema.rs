//! JSON schema of `/designs` (`gripopt.Design`), written so that Foxglove's JSON-schema
//! parser accepts it: one type per field (no union types; values not computed are left
//! out of a message instead of being null), every object with its properties. The other
//! channels are protobuf (see `proto.rs` and the `foxglove` SDK's schemas).

use serde_json::{json, Value};

fn num() -> Value {
    json!({"type": "number"})
}
fn int() -> Value {
    json!({"type": "integer", "minimum": 0})
}
fn obj(props: Value, required: &[&str]) -> Value {
    json!({"type": "object", "properties": props, "required": required})
}

/// `gripopt.Design` on `/designs`.
pub fn design() -> Value {
    let mut s = obj(
        json!({
            "id": int(),
            "generation": int(),
            "problem": {"type": "string"},
            "window_start": obj(json!({"sec": int(), "nsec": int()}), &["sec", "nsec"]),
            "window_start_s": num(),
            "epoch_s": int(),
            "parameters": obj(json!({"l21": num(), "b": num(), "t22": num(), "r": num(), "p": num(), "psi_deg": num()}), &["l21", "b", "t22", "r", "p", "psi_deg"]),
            "derived": obj(json!({"l11": num(), "l12": num(), "l22": num(), "l_hand": num()}), &["l_hand"]),
            "stages_passed": int(),
            "feasible": {"type": "boolean"},
            "form_closed": {"type": "boolean"},
            "failed_stage": int(),
            "reason": {"type": "string"},
            "violation": num(),
            "objectives": obj(json!({"max_offset": num(), "alpha": num(), "mean_force": num(), "t_stab": num()}), &[]),
            "stage_seconds": obj(json!({"stages_0_1": num(), "stage_2": num(), "stage_3": num()}), &["stages_0_1", "stage_2", "stage_3"]),
            "sim_steps": int(),
            "sim_rhs_evals": int(),
            "free_scene": {
                "type": "object",
                "description": "free scene only (MODEL.md §14.4): the object's measured motion, the keys of `simulate --scene free --json` (keys not computed, where the free scene did not run to t_obs, are left out)",
                "properties": {
                    "object_max_displacement": num(), "object_max_dx": num(), "object_max_dy": num(), "object_max_tilt_deg": num(),
                    "object_final_displacement": num(), "object_final_tilt_deg": num(), "object_peak_e_trans": num(), "object_peak_e_rot": num(),
                    "moved": {"type": "boolean"}, "toppled": {"type": "boolean"}, "escaped": {"type": "boolean"}, "rim_contact": {"type": "boolean"},
                    "object_x_off": num(), "free_end": {"type": "string"}, "free_steps": int(), "free_rhs_evals": int()
                }
            },
            "trajectory_samples": int()
        }),
        &[
            "id",
            "generation",
            "problem",
            "window_start",
            "window_start_s",
            "epoch_s",
            "parameters",
            "derived",
            "stages_passed",
            "feasible",
            "objectives",
            "stage_seconds",
            "trajectory_samples",
        ],
    );
    s["title"] = "gripopt.Design".into();
    s
}
