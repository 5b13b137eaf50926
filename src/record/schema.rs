//! `/designs` (`gripopt.Design`, JSON): the typed message ([`DesignMessage`], derived from
//! a design's evaluation record; read back as the same type by replay and the run-folder
//! reader) and its JSON schema, written so that Foxglove's JSON-schema parser accepts it:
//! one type per field (no union types; values not computed are left out of a message
//! instead of being null), every object with its properties. The other channels are
//! protobuf (see `proto.rs` and the `foxglove` SDK's schemas).

use crate::eval::FreeSceneRecord;
pub use crate::eval::{Derived, Objectives};
pub use crate::params::DesignParameters;
use crate::params::Method;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

/// A window start as seconds and nanoseconds since 1970.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Window {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds.
    pub nsec: u64,
}

/// Wall seconds per stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StageSeconds {
    /// Stages 0–1.
    pub stages_0_1: f64,
    /// Stage 2.
    pub stage_2: f64,
    /// Stage 3.
    pub stage_3: f64,
}

/// The `/designs` message of one design.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignMessage {
    /// Design id.
    pub id: u64,
    /// Generation that created it.
    pub generation: u64,
    /// Problem name.
    pub problem: String,
    /// Start of its time window.
    pub window_start: Window,
    /// Its window start in seconds since the epoch (= id).
    pub window_start_s: f64,
    /// The recording's epoch (s since 1970).
    pub epoch_s: u64,
    /// The design.
    pub parameters: DesignParameters,
    /// Derived lengths.
    pub derived: Derived,
    /// Stages passed (4: all).
    pub stages_passed: u8,
    /// No stage discarded it.
    pub feasible: bool,
    /// Form closed at the centred object.
    pub form_closed: Option<bool>,
    /// The stage that discarded it.
    pub failed_stage: Option<u8>,
    /// Why.
    pub reason: Option<String>,
    /// By how much.
    pub violation: Option<f64>,
    /// Objectives (max_offset only when form closed).
    pub objectives: Objectives,
    /// Timings.
    pub stage_seconds: StageSeconds,
    /// Accepted steps of the grasp simulation.
    pub sim_steps: Option<u64>,
    /// Right-hand-side evaluations of the grasp simulation.
    pub sim_rhs_evals: Option<u64>,
    /// The free scene's measurement (free kind; keys not computed left out).
    pub free_scene: Option<FreeSceneRecord>,
    /// A robust problem's design (docs/robust.md): aggregated objectives, per object
    /// P(stay), per scenario its drawn inputs and outcome (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robust: Option<crate::eval::RobustRecord>,
    /// A robust design's window: the scenario drawn (the one that decided its verdict) and
    /// how to record any other (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shown_scenario: Option<super::scenario_scene::ShownScenario>,
    /// Trajectory samples simulated (the recorded ones may be a subset).
    pub trajectory_samples: u64,
}

impl DesignMessage {
    /// The message as written: JSON without its null values (values not computed are left
    /// out, so Foxglove's schema parser needs one type per field, no unions).
    pub fn to_json(&self) -> Vec<u8> {
        fn strip(v: &mut Value) {
            match v {
                Value::Object(m) => {
                    m.retain(|_, x| !x.is_null());
                    m.values_mut().for_each(strip);
                }
                Value::Array(a) => a.iter_mut().for_each(strip),
                _ => {}
            }
        }
        // a message of plain numbers, texts and options always serialises
        let mut v = serde_json::to_value(self).expect("a design message serialises");
        strip(&mut v);
        serde_json::to_vec(&v).expect("a JSON value serialises")
    }
}

fn num() -> Value {
    json!({"type": "number"})
}
fn int() -> Value {
    json!({"type": "integer", "minimum": 0})
}
fn obj(props: Value, required: &[&str]) -> Value {
    json!({"type": "object", "properties": props, "required": required})
}

/// The JSON type of every key of the free scene's record with `method`'s work counters
/// (the switching method's two more: `switches`, `explicit_steps`), asked of the record type
/// itself: the key set to 0.5, 1, true or [0.5, 0.5] in turn, the first value the type reads
/// is the key's type (a number, a count, a boolean, an array of numbers; text otherwise).
fn free_scene_properties(method: Method) -> Value {
    let mut every = FreeSceneRecord::default();
    if method == Method::Auto {
        (every.work.switches, every.work.explicit_steps) = (Some(0), Some(0));
    }
    let keys = serde_json::to_value(every).expect("records serialise");
    let reads = |k: &str, v: Value| serde_json::from_value::<FreeSceneRecord>(json!({ k: v })).is_ok();
    let type_of = |k: &str| {
        if reads(k, json!(0.5)) {
            num()
        } else if reads(k, json!(1)) {
            int()
        } else if reads(k, json!(true)) {
            json!({"type": "boolean"})
        } else if reads(k, json!([0.5, 0.5])) {
            json!({"type": "array", "items": num()})
        } else {
            json!({"type": "string"})
        }
    };
    keys.as_object().expect("an object").keys().map(|k| (k.clone(), type_of(k))).collect()
}

/// An object of numbers with `keys`.
fn nums(keys: &[&str]) -> Value {
    Value::Object(keys.iter().map(|k| (k.to_string(), num())).collect())
}

/// The robust sub-record (issue 22): one type per key, arrays with typed items.
fn robust_schema() -> Value {
    let pair = json!({"type": "array", "items": int()});
    let keys =
        crate::eval::objective_names().into_iter().chain(["p_stay", "p_stay_lo", "p_stay_hi", "max_displacement"]);
    let mut object = nums(&keys.collect::<Vec<_>>());
    object["name"] = json!({"type": "string"});
    object["scenarios"] = int();
    object["stays"] = int();
    object["meets_p_min"] = json!({"type": "boolean"});
    let mut scenario = nums(&["t_stab", "max_displacement", "max_tilt_deg"]);
    scenario["object"] = int();
    scenario["k"] = int();
    let inputs: Vec<&str> = crate::params::INPUTS.iter().map(|r| r.name).collect();
    scenario["inputs"] = obj(nums(&inputs), &[]);
    scenario["stays"] = json!({"type": "boolean"});
    scenario["cause"] = json!({"type": "string"});
    scenario["rhs_evals"] = pair.clone();
    scenario["steps"] = pair.clone();
    json!({
        "type": "object",
        "description": "robust problems only (docs/robust.md): the aggregated objectives, per object P(stay) and its Clopper-Pearson interval, per scenario (object, k) its drawn inputs and outcome",
        "properties": {
            "objectives": obj(nums(&crate::eval::objective_names()), &[]),
            "objects": {"type": "array", "items": obj(object, &[])},
            "scenarios_planned": int(),
            "scenarios_run": int(),
            "scenarios_saved": int(),
            "rhs_evals": pair.clone(),
            "steps": pair,
            "scenarios": {"type": "array", "items": obj(scenario, &[])}
        }
    })
}

/// The scenario a robust design's window draws (`shown_scenario`).
fn shown_scenario_schema() -> Value {
    let mut props = nums(&["max_displacement", "height_offset", "x_off"]);
    for k in ["object", "why", "replay"] {
        props[k] = json!({"type": "string"});
    }
    props["k"] = int();
    props["free_scene"] = json!({"type": "boolean"});
    props["stays"] = json!({"type": "boolean"});
    let mut s = obj(props, &["object", "k", "why", "free_scene", "stays", "replay"]);
    s["description"] = "robust problems only (docs/recording.md): the scenario drawn in the design's window (the one that decided its verdict), and the command that records any other".into();
    s
}

/// `gripopt.Design` on `/designs`, of a problem integrated with `method` (the free scene's
/// keys of the switching method's work are listed only for it: the schema of every other
/// method's recording is as before).
pub fn design(method: Method) -> Value {
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
            "objectives": obj(nums(&crate::eval::objective_names()), &[]),
            "stage_seconds": obj(json!({"stages_0_1": num(), "stage_2": num(), "stage_3": num()}), &["stages_0_1", "stage_2", "stage_3"]),
            "sim_steps": int(),
            "sim_rhs_evals": int(),
            "free_scene": {
                "type": "object",
                "description": "free scene only (MODEL.md §14.4): the object's measured motion, the keys of `evaluate --json` for the free scene (keys not computed, e.g. the verdict flags where the free scene did not run to t_obs, are left out)",
                "properties": free_scene_properties(method)
            },
            "robust": robust_schema(),
            "shown_scenario": shown_scenario_schema(),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The switching method's work counters are listed for its recordings only (a RADAU5
    /// recording's schema is as before), as counts.
    #[test]
    fn the_switching_counters_are_in_the_auto_schema_only() {
        let keys = |m: Method| design(m)["properties"]["free_scene"]["properties"].clone();
        let (radau, auto) = (keys(Method::Radau5), keys(Method::Auto));
        for k in ["switches", "explicit_steps"] {
            assert!(radau.get(k).is_none(), "{k} in {radau}");
            assert_eq!(auto[k], int(), "{k}");
        }
        assert_eq!(radau["steps"], int());
    }
}
