//! The Foxglove layout written into every run folder (`foxglove-layout.json`): a 3D panel
//! following the hand, plots of the current design's contact forces and joint angles
//! against its own simulated time, and the `/designs` record. Import it in Foxglove with
//! Layouts → Import from file (see docs/recording.md).

use crate::fsutil::write_atomic;
use crate::Result;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// File name of the layout inside a run folder.
pub const LAYOUT_FILE: &str = "foxglove-layout.json";

/// A Plot panel of `/grasp/series` columns against `/grasp/series.t`, x-axis "Path
/// (current)": the arrays of the latest message, i.e. the design under the playhead.
fn plot(title: &str, columns: &[(&str, &str)]) -> Value {
    let paths: Vec<Value> = columns
        .iter()
        .map(|(c, label)| json!({"value": format!("/grasp/series.{c}[:]"), "enabled": true, "timestampMethod": "receiveTime", "label": label}))
        .collect();
    json!({
        "title": title,
        "paths": paths,
        "xAxisVal": "currentCustom",
        "xAxisPath": {"value": "/grasp/series.t[:]", "enabled": true},
        "showLegend": true,
        "legendDisplay": "floating",
        "showPlotValuesInLegend": true,
        "showXAxisLabels": true,
        "showYAxisLabels": true,
        "isSynced": false
    })
}

/// The layout (Foxglove's layout JSON: `configById`, `layout`, `globalVariables`, …).
pub fn layout() -> Value {
    let three_d = json!({
        // display frame `hand`, followed in position; the world stays z-up. The camera looks
        // horizontally along the bottle's axis at the hand's plane (about 0.4 m away: the
        // 0.2 m hand, the bottle and the ground fill the view).
        "followTf": "hand",
        "followMode": "follow-position",
        "cameraState": {
            "perspective": true, "distance": 0.4, "phi": 85.0, "thetaOffset": 0.0,
            "targetOffset": [0.0, 0.0, -0.04], "target": [0.0, 0.0, 0.0], "targetOrientation": [0.0, 0.0, 0.0, 1.0],
            "fovy": 45.0, "near": 0.005, "far": 50.0
        },
        "scene": {"enableStats": false, "transforms": {"showLabel": false, "axisScale": 0.3}},
        "transforms": {"frame:world": {"visible": false}, "frame:hand": {"visible": true}},
        "topics": {"/scene": {"visible": true}, "/scene/static": {"visible": true}},
        "layers": {"grid": {"layerId": "foxglove.Grid", "visible": true, "frameId": "world", "size": 0.6, "divisions": 12, "lineWidth": 1, "color": "#248eff", "position": [0, 0, 0], "rotation": [0, 0, 0]}}
    });
    let forces = plot(
        "Contact forces (N) vs simulated time (s) of the current design",
        &[
            ("proximal_normal_force", "proximal normal"),
            ("distal_normal_force", "distal normal"),
            ("proximal_friction_force", "proximal friction"),
            ("distal_friction_force", "distal friction"),
            ("filtered_hand_force", "hand (filtered)"),
        ],
    );
    let joints = plot(
        "Joint angles (rad) vs simulated time (s) of the current design",
        &[("q11", "q11"), ("q21", "q21 = θ1"), ("theta2", "θ2")],
    );
    json!({
        "configById": {
            "3D!grasp": three_d,
            "Plot!forces": forces,
            "Plot!joints": joints,
            "RawMessages!designs": {"topicPath": "/designs", "diffEnabled": false, "diffMethod": "custom", "diffTopicPath": "", "showFullMessageForDiff": false, "expansion": "all"}
        },
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 0.1},
        "layout": {
            "direction": "row",
            "splitPercentage": 55,
            "first": "3D!grasp",
            "second": {
                "direction": "column",
                "splitPercentage": 70,
                "first": {"direction": "column", "first": "Plot!forces", "second": "Plot!joints"},
                "second": "RawMessages!designs"
            }
        }
    })
}

/// Write [`layout`] to `RUN_DIR/foxglove-layout.json`; returns its path.
pub fn write_layout(run_dir: &Path) -> Result<PathBuf> {
    let path = run_dir.join(LAYOUT_FILE);
    let text = serde_json::to_string_pretty(&layout()).expect("the layout serialises");
    write_atomic(&path, text.as_bytes())?;
    Ok(path)
}
