//! The Foxglove layouts written beside the recordings: `foxglove-layout.json` in every run
//! folder (the optimisation shards and their front files `recording/front-NNNNN.mcap`) and
//! `foxglove-verify-layout.json` (`gripopt verify`'s file). Both are the layout JSON of the
//! Foxglove family (`configById`, `layout`, `globalVariables`, `userNodes`,
//! `playbackConfig`), read the same way by Foxglove and Lichtblick (Layouts → Import from
//! file); docs/recording.md says what each panel shows and why its settings are what they are:
//!
//! * 3-D panels follow `world` (z up): both viewers orbit the camera in the followed frame's
//!   axes (`phi` from its +z, `thetaOffset` about it; 0 puts the camera on −y), so the oblique
//!   view looks at the grasp from behind the palm, 40° above the hand plane, and the top view
//!   (orthographic, "2D") looks down on the hand plane with the object's side up;
//! * panel titles under both viewers' keys (`foxglovePanelTitle`, `lichtblickPanelTitle`);
//! * plots with axis labels (`xAxisLabel`, `yAxisLabel`), the legend on the left (it never
//!   covers the curves), x-axis "Path (current)" against the design's own simulated time.

use super::proto::MEAN_FORCE_FIELD;
use crate::error::Result;
use crate::fsutil::write_atomic;
use crate::params::Problem;
use crate::sim::series_field;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// File name of the layout inside a run folder.
pub const LAYOUT_FILE: &str = "foxglove-layout.json";
/// File name of the Foxglove layout for verify recordings inside a run folder.
pub const VERIFY_LAYOUT_FILE: &str = "foxglove-verify-layout.json";

/// Playback speed of both layouts: a grasp of 20–50 ms of simulated time plays in 1–2.5 s
/// (a design's window of 1 s in 50 s).
pub const PLAYBACK_SPEED: f64 = 0.02;

/// `config` with `title` under the key each viewer reads (Foxglove: `foxglovePanelTitle`,
/// packages/studio-base/src/util/layout.ts; Lichtblick: `lichtblickPanelTitle`,
/// packages/suite-base/src/util/layout.ts).
fn titled(mut config: Value, title: &str) -> Value {
    config["foxglovePanelTitle"] = title.into();
    config["lichtblickPanelTitle"] = title.into();
    config
}

/// A 3-D panel following `world`: the oblique view (perspective, from behind the palm, 40°
/// above the hand plane) or the top view (orthographic, looking down the z axis, +y up).
fn three_d(top: bool, frames: &[&str], title: &str) -> Value {
    let camera = if top {
        json!({
            "perspective": false, "distance": 0.26, "phi": 0.0, "thetaOffset": 0.0,
            "targetOffset": [0.0, 0.035, 0.05], "target": [0.0, 0.0, 0.0], "targetOrientation": [0.0, 0.0, 0.0, 1.0],
            "fovy": 45.0, "near": 0.005, "far": 50.0
        })
    } else {
        json!({
            "perspective": true, "distance": 0.38, "phi": 50.0, "thetaOffset": 0.0,
            "targetOffset": [0.0, 0.04, 0.06], "target": [0.0, 0.0, 0.0], "targetOrientation": [0.0, 0.0, 0.0, 1.0],
            "fovy": 45.0, "near": 0.005, "far": 50.0
        })
    };
    let mut transforms = serde_json::Map::new();
    transforms.insert("frame:world".into(), json!({"visible": false}));
    for f in frames {
        transforms.insert(format!("frame:{f}"), json!({"visible": true}));
    }
    titled(
        json!({
            "followTf": "world",
            "followMode": "follow-pose",
            "cameraState": camera,
            "scene": {"enableStats": false, "transforms": {"showLabel": false, "axisScale": 0.3, "enablePreloading": true}},
            "transforms": transforms,
            "topics": {"/scene": {"visible": true}, "/scene/static": {"visible": true}},
            "layers": {"grid": {"layerId": "foxglove.Grid", "visible": true, "frameId": "world", "size": 0.6, "divisions": 12, "lineWidth": 1, "color": "#248eff", "position": [0, 0, 0.0005], "rotation": [0, 0, 0]}}
        }),
        title,
    )
}

/// Colours of a plot's series, in order: every series of the shipped layouts has its own
/// (the viewers' default palette has 7 colours and repeats after them, so a plot of more
/// series drew two in one colour).
const PALETTE: [&str; 10] =
    ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];

/// Width (px) of the plots' legend beside the chart: a label of [`LEGEND_MAX_CHARS`] fits.
const LEGEND_PX: u32 = 200;
/// The most characters of a legend label (about 6.6 px each, and the colour swatch).
pub const LEGEND_MAX_CHARS: usize = 24;

/// A Plot panel of the arrays `columns` (path suffix, legend label) of topic `topic` against
/// its array `t`, x-axis "Path (current)": the arrays of the latest message, i.e. the design
/// under the playhead; each series in its own colour of [`PALETTE`]. A column that parses as
/// a number is a horizontal reference line. `y_range`: fixed limits of the y axis (None:
/// automatic).
fn plot<C: AsRef<str>, L: AsRef<str>>(
    topic: &str,
    title: &str,
    y_label: &str,
    columns: &[(C, L)],
    y_range: Option<(f64, f64)>,
) -> Value {
    let paths: Vec<Value> = columns
        .iter()
        .zip(PALETTE.iter().cycle())
        .map(|((c, label), color)| {
            let (c, label) = (c.as_ref(), label.as_ref());
            let value = if c.parse::<f64>().is_ok() { c.to_string() } else { format!("{topic}.{c}[:]") };
            json!({"value": value, "enabled": true, "timestampMethod": "receiveTime", "label": label, "color": color})
        })
        .collect();
    let mut p = json!({
        "paths": paths,
        "xAxisVal": "currentCustom",
        "xAxisPath": {"value": format!("{topic}.t[:]"), "enabled": true},
        "xAxisLabel": "simulated time t (s)",
        "yAxisLabel": y_label,
        "showLegend": true,
        "legendDisplay": "left",
        "sidebarDimension": LEGEND_PX,
        "showPlotValuesInLegend": false,
        "showXAxisLabels": true,
        "showYAxisLabels": true,
        "isSynced": false
    });
    if let Some((lo, hi)) = y_range {
        p["minYValue"] = lo.into();
        p["maxYValue"] = hi.into();
    }
    titled(p, title)
}

/// A plot of one motion column against its limit `limit` as a horizontal line, the y axis
/// from 0 to 2.5 × the limit (the line at 40 % of the height, not on the plot's edge; a motion
/// far past the limit runs off the top: its maximum is in the record).
fn motion_plot(topic: &str, title: &str, column: &str, label: &str, unit: &str, limit: f64) -> Value {
    let line = format!("{limit}");
    let line_label = format!("limit {line} {unit}");
    plot(
        topic,
        &format!("{title} (y clipped to 0..{} {unit}; the limit {line} {unit} drawn)", 2.5 * limit),
        &format!("{label} ({unit})"),
        &[(column, label), (line.as_str(), line_label.as_str())],
        Some((0.0, 2.5 * limit)),
    )
}

/// The `/grasp/series` field of the trajectory column `name` (the vocabulary of
/// `sim::SAMPLE_COLUMNS`).
fn field(name: &str) -> String {
    series_field(name).unwrap_or_else(|| panic!("{name}: not a trajectory column")).to_string()
}

/// Plot columns (series field, label) of finger 1's trajectory columns `columns` (name,
/// label); with `finger2`, each labelled "F1 …", followed by finger 2's own (its `finger2_`
/// column: the offset scene's series), labelled "F2 …".
fn finger_columns(columns: &[(&str, &str)], finger2: bool) -> Vec<(String, String)> {
    if !finger2 {
        return columns.iter().map(|&(c, l)| (field(c), l.to_string())).collect();
    }
    let ones = columns.iter().map(|&(c, l)| (field(c), format!("F1 {l}")));
    ones.chain(columns.iter().map(|&(c, l)| (field(&format!("finger2_{c}")), format!("F2 {l}")))).collect()
}

fn raw_messages(topic: &str, title: &str) -> Value {
    titled(
        json!({"topicPath": topic, "diffEnabled": false, "diffMethod": "custom", "diffTopicPath": "", "showFullMessageForDiff": false, "expansion": "all"}),
        title,
    )
}

/// Whether the design under the playhead is on the run's final front: `/front` of the shard's
/// front file (`front-NNNNN.mcap`, written when the run ends).
fn front_indicator() -> Value {
    titled(
        json!({
            "path": "/front.on_final_front",
            "style": "background",
            "fallbackColor": "#707070",
            "fallbackLabel": "final front unknown: seek once (after a layout import the viewer redraws at the next seek), or open front-NNNNN.mcap with its shard (written when the run ends)",
            "rules": [
                {"operator": "=", "rawValue": "true", "color": "#2e9c3a", "label": "on the final Pareto front"},
                {"operator": "=", "rawValue": "false", "color": "#505050", "label": "not on the final front"}
            ]
        }),
        "Final front",
    )
}

/// A layout document around `config_by_id` and the mosaic `tree`.
fn document(config_by_id: Value, tree: Value) -> Value {
    json!({
        "configById": config_by_id,
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": PLAYBACK_SPEED},
        "layout": tree
    })
}

/// The layout of a run folder: the oblique and the top 3-D views (left; left out when the
/// recording has no scene channels, `scene` false); on the right whether the design is on
/// the final front (`/front` of the shards' front files), the contact forces at the scale of
/// the holding force, the hand force, the joint angles and the `/designs` record. With
/// `finger2` (the offset scene, whose series carries finger 2's own columns) the contact
/// force and joint angle plots show both fingers.
pub fn layout(scene: bool, finger2: bool) -> Value {
    let s = "/grasp/series";
    let mut forces = finger_columns(
        &[
            ("fn_1", "proximal normal"),
            ("fn_2", "distal normal"),
            ("ft_1", "proximal friction"),
            ("ft_2", "distal friction"),
        ],
        finger2,
    );
    forces.push((MEAN_FORCE_FIELD.into(), "F~ (objective)".into()));
    let angles =
        finger_columns(&[("q11", "q11 (actuated)"), ("q21", "q21 = theta1"), ("theta2", "theta2 (distal)")], finger2);
    let fingers = if finger2 { "both fingers" } else { "finger 1" };
    let contact = plot(
        s,
        &format!("Contact forces of {fingers} near the holding force (y clipped to -5..25 N; impacts run off the top)"),
        &format!("{fingers} contact force (N)"),
        &forces,
        Some((-5.0, 25.0)),
    );
    let hand = plot(
        s,
        "Hand force on the object along y (y clipped to -25..25 N)",
        "F_hand,y (N)",
        &[(field("hand_fy"), "raw"), (field("filtered_fy"), "low-pass T_f")],
        Some((-25.0, 25.0)),
    );
    let joints = plot(s, &format!("Joint angles of {fingers}"), "angle (rad)", &angles, None);
    let mut configs = json!({
        "Indicator!front": front_indicator(),
        "Plot!contact": contact,
        "Plot!hand": hand,
        "Plot!joints": joints,
        "RawMessages!designs": raw_messages("/designs", "Design record (/designs)")
    });
    let right = json!({
        "direction": "column", "splitPercentage": 8, "first": "Indicator!front",
        "second": {
            "direction": "column", "splitPercentage": 30, "first": "Plot!contact",
            "second": {
                "direction": "column", "splitPercentage": 43, "first": "Plot!hand",
                "second": {"direction": "column", "splitPercentage": 57, "first": "Plot!joints", "second": "RawMessages!designs"}
            }
        }
    });
    if !scene {
        return document(configs, right);
    }
    configs["3D!oblique"] = three_d(false, &["hand"], "Grasp: oblique view from behind the palm (world, z up)");
    configs["3D!top"] = three_d(true, &["hand"], "Grasp: top view of the hand plane (x right, object up)");
    document(
        configs,
        json!({
            "direction": "row",
            "splitPercentage": 50,
            "first": {"direction": "column", "splitPercentage": 58, "first": "3D!oblique", "second": "3D!top"},
            "second": right
        }),
    )
}

/// The layout of verify recordings: the oblique and top 3-D views of the free scene (the
/// object's frame shown), the object's displacement and its tilt against simulated time, each
/// in its own plot with the verdict's limit (`dx_max_mm`, `theta_max_deg`) as a line, and the
/// `/verify` record.
pub fn verify_layout(dx_max_mm: f64, theta_max_deg: f64) -> Value {
    let s = "/verify/series";
    let displacement =
        motion_plot(s, "Free object: horizontal displacement of G", "displacement_mm", "displacement", "mm", dx_max_mm);
    let tilt = motion_plot(s, "Free object: tilt", "tilt_deg", "tilt", "deg", theta_max_deg);
    document(
        json!({
            "3D!oblique": three_d(false, &["hand", "object"], "Free scene: oblique view from behind the palm (world, z up)"),
            "3D!top": three_d(true, &["hand", "object"], "Free scene: top view of the hand plane"),
            "Plot!displacement": displacement,
            "Plot!tilt": tilt,
            "RawMessages!verify": raw_messages("/verify", "Verify record (/verify)")
        }),
        json!({
            "direction": "row",
            "splitPercentage": 55,
            "first": {"direction": "column", "splitPercentage": 58, "first": "3D!oblique", "second": "3D!top"},
            "second": {
                "direction": "column", "splitPercentage": 27, "first": "Plot!displacement",
                "second": {"direction": "column", "splitPercentage": 37, "first": "Plot!tilt", "second": "RawMessages!verify"}
            }
        }),
    )
}

/// The layout of a robust run's shards: each design that reached its scenarios is drawn in
/// the scenario that decided its verdict (`/scenario/series`, `/designs` → `shown_scenario`).
/// The oblique and top 3-D views (a free scene's object moves with the frame `object`),
/// whether the design is on the final front, the object's displacement and tilt against the
/// limits (`dx_max_mm`, `theta_max_deg`), both fingers' normal forces and joint angles, the
/// scenario shown (its title names the command that records any other), and the `/designs`
/// record. Without scene channels (`scene` false) no 3-D panel.
pub fn robust_layout(scene: bool, dx_max_mm: f64, theta_max_deg: f64) -> Value {
    let s = "/scenario/series";
    let displacement = motion_plot(
        s,
        "Scenario shown: horizontal displacement of the free object",
        "displacement_mm",
        "displacement",
        "mm",
        dx_max_mm,
    );
    let tilt = motion_plot(s, "Scenario shown: tilt of the free object", "tilt_deg", "tilt", "deg", theta_max_deg);
    let forces = plot(
        s,
        "Scenario shown: normal forces of both fingers (y clipped to -5..25 N; impacts run off the top)",
        "normal force (N)",
        &[
            ("finger1_proximal_normal_force", "F1 proximal"),
            ("finger1_distal_normal_force", "F1 distal"),
            ("finger2_proximal_normal_force", "F2 proximal"),
            ("finger2_distal_normal_force", "F2 distal"),
        ],
        Some((-5.0, 25.0)),
    );
    let joints = plot(
        s,
        "Scenario shown: joint angles of both fingers",
        "angle (rad)",
        &[
            ("finger1_q11", "F1 q11 (actuated)"),
            ("finger1_q21", "F1 q21 = theta1"),
            ("finger2_q11", "F2 q11 (actuated)"),
            ("finger2_q21", "F2 q21 = theta1"),
        ],
        None,
    );
    let mut configs = json!({
        "Indicator!front": front_indicator(),
        "Plot!displacement": displacement,
        "Plot!tilt": tilt,
        "Plot!forces": forces,
        "Plot!joints": joints,
        "RawMessages!scenario": raw_messages(
            "/designs.shown_scenario",
            "Scenario shown (any other: gripopt replay RUN_DIR --design ID --scenario OBJECT:K)"
        ),
        "RawMessages!designs": raw_messages("/designs", "Design record (/designs)")
    });
    let right = json!({
        "direction": "column", "splitPercentage": 7, "first": "Indicator!front",
        "second": {
            "direction": "column", "splitPercentage": 17, "first": "Plot!displacement",
            "second": {
                "direction": "column", "splitPercentage": 20, "first": "Plot!tilt",
                "second": {
                    "direction": "column", "splitPercentage": 25, "first": "Plot!forces",
                    "second": {
                        "direction": "column", "splitPercentage": 33, "first": "Plot!joints",
                        "second": {"direction": "column", "splitPercentage": 35, "first": "RawMessages!scenario", "second": "RawMessages!designs"}
                    }
                }
            }
        }
    });
    if !scene {
        return document(configs, right);
    }
    // the frame `object` exists only in the windows of a free scene (a run may have none):
    // the panels show the hand's axes only
    let frames = ["hand"];
    configs["3D!oblique"] = three_d(false, &frames, "Scenario shown: oblique view from behind the palm (world, z up)");
    configs["3D!top"] = three_d(true, &frames, "Scenario shown: top view of the hand plane (x right, object up)");
    document(
        configs,
        json!({
            "direction": "row",
            "splitPercentage": 50,
            "first": {"direction": "column", "splitPercentage": 58, "first": "3D!oblique", "second": "3D!top"},
            "second": right
        }),
    )
}

/// The layouts gripopt may have written into a run folder of `problem` (None: any
/// single-object one): with and without scene channels, both fingers or not, or a robust
/// problem's.
pub fn run_layouts(problem: Option<&Problem>) -> Vec<Value> {
    let mut out: Vec<Value> = [(true, false), (false, false), (true, true), (false, true)]
        .iter()
        .map(|&(scene, finger2)| layout(scene, finger2))
        .collect();
    if let Some(p) = problem.filter(|p| p.robust.is_some()) {
        let c = &p.scene.criteria;
        out.extend([true, false].map(|scene| robust_layout(scene, c.dx_max * 1e3, c.theta_max.to_degrees())));
    }
    out
}

/// Write [`layout`] for a run of `problem` recorded with `opts` (both fingers plotted in the
/// offset scene; a robust problem's: [`robust_layout`]) to `RUN_DIR/foxglove-layout.json`;
/// returns its path.
pub fn write_layout(run_dir: &Path, opts: &super::RecordOptions, problem: &Problem) -> Result<PathBuf> {
    let path = run_dir.join(LAYOUT_FILE);
    let finger2 = problem.scene.setup.kind.has_finger2();
    let scene = opts.scene_dt > 0.0;
    let c = &problem.scene.criteria;
    let l = match problem.robust {
        Some(_) => robust_layout(scene, c.dx_max * 1e3, c.theta_max.to_degrees()),
        None => layout(scene, finger2),
    };
    let text = serde_json::to_string_pretty(&l).expect("the layout serialises");
    write_atomic(&path, text.as_bytes())?;
    Ok(path)
}

/// Write [`verify_layout`] to `RUN_DIR/foxglove-verify-layout.json`; returns its path.
pub fn write_verify_layout(run_dir: &Path, dx_max_mm: f64, theta_max_deg: f64) -> Result<PathBuf> {
    let path = run_dir.join(VERIFY_LAYOUT_FILE);
    let text = serde_json::to_string_pretty(&verify_layout(dx_max_mm, theta_max_deg)).expect("the layout serialises");
    write_atomic(&path, text.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What both viewers need of every shipped layout (docs/recording.md, "What the viewers
    /// read"): a title under each viewer's key, a playback speed, 3-D panels following the
    /// z-up `world` with the oblique camera above the hand plane on the palm's side, plots with
    /// axis labels and a legend beside the chart, and a mosaic naming exactly the panels.
    #[test]
    fn layouts_are_written_for_both_viewers() {
        for (name, l) in [
            ("run", layout(true, false)),
            ("run without scene", layout(false, false)),
            ("offset run", layout(true, true)),
            ("verify", verify_layout(1.0, 1.0)),
            ("robust", robust_layout(true, 1.0, 1.0)),
            ("robust without scene", robust_layout(false, 1.0, 1.0)),
        ] {
            let configs = l["configById"].as_object().unwrap();
            assert!(l["playbackConfig"]["speed"].as_f64().unwrap() <= 0.05, "{name}: a grasp must be watchable");
            let mut leaves = vec![];
            let mut stack = vec![&l["layout"]];
            while let Some(n) = stack.pop() {
                match n {
                    Value::String(s) => leaves.push(s.clone()),
                    _ => stack.extend([&n["first"], &n["second"]]),
                }
            }
            leaves.sort();
            assert_eq!(leaves, configs.keys().cloned().collect::<Vec<_>>(), "{name}: mosaic and configById");
            for (id, c) in configs {
                assert!(
                    c["foxglovePanelTitle"].is_string() && c["lichtblickPanelTitle"] == c["foxglovePanelTitle"],
                    "{id}"
                );
                if id.starts_with("3D!") {
                    assert_eq!(c["followTf"], "world", "{id}: the viewers orbit in the followed frame's axes");
                    let cam = &c["cameraState"];
                    if cam["perspective"] == true {
                        let phi = cam["phi"].as_f64().unwrap();
                        assert!(phi > 30.0 && phi < 80.0 && cam["thetaOffset"] == 0.0, "{id}: oblique, from −y");
                    }
                }
                if id.starts_with("Plot!") {
                    assert!(
                        c["xAxisLabel"].as_str().unwrap().contains("(s)")
                            && c["yAxisLabel"].as_str().unwrap().contains('(')
                    );
                    assert_ne!(c["legendDisplay"], "floating", "{id}: a floating legend covers the curves");
                }
            }
        }
        assert!(layout(false, false)["configById"].get("3D!oblique").is_none(), "no 3-D panel without scene channels");
    }

    /// The offset scene's layout plots finger 2's own series fields beside finger 1's, each
    /// labelled with its finger; the other scenes' layouts name no finger-2 field (their
    /// series have none: the viewer would plot nothing).
    #[test]
    fn the_offset_layout_plots_both_fingers() {
        let paths = |l: &Value, id: &str| -> Vec<(String, String)> {
            let p = l["configById"][id]["paths"].as_array().unwrap();
            p.iter().map(|v| (v["value"].as_str().unwrap().into(), v["label"].as_str().unwrap().into())).collect()
        };
        let (offset, centred) = (layout(true, true), layout(true, false));
        for id in ["Plot!contact", "Plot!joints"] {
            let (two, one) = (paths(&offset, id), paths(&centred, id));
            let f2: Vec<_> = two.iter().filter(|(v, _)| v.starts_with("/grasp/series.finger2_")).collect();
            assert!(!f2.is_empty() && f2.iter().all(|(_, l)| l.starts_with("F2 ")), "{id}: {two:?}");
            for (v, _) in &f2 {
                let own = v.replace("finger2_", "");
                assert!(one.iter().any(|(w, _)| *w == own), "{id}: {v} has no finger-1 field {own}");
            }
            assert_eq!(two.len(), one.len() + f2.len(), "{id}: finger 1's fields kept");
            assert!(one.iter().all(|(v, _)| !v.contains("finger2_")), "{id}");
        }
    }
}
