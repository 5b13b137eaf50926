//! The MCAP recording of `gripopt verify` (`RUN_DIR/verify.mcap`, `verify_sample.mcap`):
//! one design after another on the time convention of the optimisation recording (window k
//! = [epoch + k s, epoch + k s + 1 s), simulated time t at epoch + k s + t), k the row's
//! index in the verify table. Per design: its verify row on `/verify` (JSON,
//! `gripopt.Verify`), and the free scene in 3-D with the official Foxglove schemas: `/tf`
//! (`world` → `hand`, `hand` → `object` following the free object's pose), `/scene/static`
//! (ground, palm, and the bottle in the frame `object`) and `/scene` (both fingers). See
//! docs/recording.md.

use super::messages::{free_fingers, free_frames, free_static_scene, log_time, window_start_ns};
use crate::fsutil::write_atomic;
use crate::model::Finger;
use crate::params::{Design, Problem};
use crate::sim::PoseSample;
use crate::Result;
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Encode;
use mcap::records::{MessageHeader, Metadata};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Name of the metadata record of a verify recording.
pub const VERIFY_METADATA: &str = "gripopt.verify";
/// File name of the Foxglove layout for verify recordings inside a run folder.
pub const VERIFY_LAYOUT_FILE: &str = "foxglove-verify-layout.json";

/// The `/verify` message of one design: the columns of verify.csv (values not computed are
/// left out, as on `/designs`), its time window and the free scene's end time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerifyRecord {
    /// The window index k (the row's index in the verify table).
    pub window: u64,
    /// The window start (s, ns since 1970).
    pub window_start: WindowStart,
    /// k: seconds since the epoch.
    pub window_start_s: f64,
    /// The recording's epoch (s since 1970).
    pub epoch_s: u64,
    /// The design id (the run's id, or the draw's index for `--sample`).
    pub id: u64,
    /// The design (l21, b, t22, r, p in m or 1; ψ in degrees).
    pub parameters: Parameters,
    /// Object offset of the free scene (m).
    pub x_off: f64,
    /// Prediction: E_cyl/E_lim at the centred first contact.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub impact_ratio: Option<f64>,
    /// Prediction: §9.1's E_trans (J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub e_trans: Option<f64>,
    /// Prediction: §9.1's E_rot (J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub e_rot: Option<f64>,
    /// Prediction: the smaller of the filtered and static force margins (N).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub force_margin: Option<f64>,
    /// The centred grasp reached stability.
    pub stable: bool,
    /// The centred criteria predict motion.
    pub predicted_moves: bool,
    /// Measured: largest horizontal displacement of G (m).
    pub object_max_displacement: f64,
    /// Measured: largest tilt (°).
    pub object_max_tilt_deg: f64,
    /// Measured: peak translational kinetic energy during the first contact (J).
    pub object_peak_e_trans: f64,
    /// Measured: peak rotational kinetic energy during the first contact (J).
    pub object_peak_e_rot: f64,
    /// How the free scene ended: "t_obs", or why it stopped early (then no verdict: the
    /// verdict flags, `agrees` and the ratios are left out).
    pub free_end: String,
    /// §14.4's verdict.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moved: Option<bool>,
    /// Tilt above 45°.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub toppled: Option<bool>,
    /// No phalanx in contact at t_end.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub escaped: Option<bool>,
    /// A phalanx met the rim or a face.
    pub rim_contact: bool,
    /// Prediction and measurement agree.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agrees: Option<bool>,
    /// Object peak E_trans / §9.1's E_trans.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_e_trans_ratio: Option<f64>,
    /// Object peak E_rot / §9.1's E_rot.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_e_rot_ratio: Option<f64>,
    /// Time the free scene reached (s): the last pose drawn.
    pub t_end: f64,
    /// Object poses drawn (`/tf` hand → object messages).
    pub poses: u64,
}

/// A window start as seconds and nanoseconds since 1970.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct WindowStart {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds.
    pub nsec: u64,
}

/// The design's parameters, as on `/designs`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Parameters {
    /// l21 (m).
    pub l21: f64,
    /// b (m).
    pub b: f64,
    /// t22 (m).
    pub t22: f64,
    /// r.
    pub r: f64,
    /// p.
    pub p: f64,
    /// ψ (°).
    pub psi_deg: f64,
}

/// JSON schema of `/verify` (`gripopt.Verify`), parsable by Foxglove (one type per field).
pub fn verify_schema() -> Value {
    let num = || json!({"type": "number"});
    let int = || json!({"type": "integer", "minimum": 0});
    let boolean = || json!({"type": "boolean"});
    let obj = |props: Value, required: &[&str]| json!({"type": "object", "properties": props, "required": required});
    let mut s = obj(
        json!({
            "window": int(), "window_start": obj(json!({"sec": int(), "nsec": int()}), &["sec", "nsec"]), "window_start_s": num(), "epoch_s": int(), "id": int(),
            "parameters": obj(json!({"l21": num(), "b": num(), "t22": num(), "r": num(), "p": num(), "psi_deg": num()}), &["l21", "b", "t22", "r", "p", "psi_deg"]),
            "x_off": num(), "impact_ratio": num(), "e_trans": num(), "e_rot": num(), "force_margin": num(), "stable": boolean(), "predicted_moves": boolean(),
            "object_max_displacement": num(), "object_max_tilt_deg": num(), "object_peak_e_trans": num(), "object_peak_e_rot": num(), "free_end": json!({"type": "string"}),
            "moved": boolean(), "toppled": boolean(), "escaped": boolean(), "rim_contact": boolean(), "agrees": boolean(),
            "peak_e_trans_ratio": num(), "peak_e_rot_ratio": num(), "t_end": num(), "poses": int()
        }),
        &[
            "window",
            "window_start",
            "window_start_s",
            "epoch_s",
            "id",
            "parameters",
            "x_off",
            "stable",
            "predicted_moves",
            "object_max_displacement",
            "object_max_tilt_deg",
            "object_peak_e_trans",
            "object_peak_e_rot",
            "free_end",
            "rim_contact",
            "t_end",
            "poses",
        ],
    );
    s["title"] = "gripopt.Verify".into();
    s
}

/// One verified design to record: its `/verify` message (window fields are set by the
/// writer) and the free scene's poses to draw (see [`keep_poses`]).
#[derive(Debug, Clone)]
pub struct VerifyEntry {
    /// The message.
    pub record: VerifyRecord,
    /// The object's pose and the fingers' angles to draw, in time order.
    pub poses: Vec<PoseSample>,
}

/// Settings of a verify recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifyRecordOptions {
    /// Interval of the scene updates in simulated seconds (> 0).
    pub scene_dt: f64,
    /// Epoch of the time axis, whole seconds since 1970 (the run's start time, so the file
    /// does not depend on when verify ran).
    pub epoch_s: u64,
    /// zstd level of the chunks.
    pub zstd_level: u32,
}

/// The poses drawn of a free-scene trajectory: the first, then the first at least
/// `scene_dt` after the previously drawn one, and the last (the final state; it replaces
/// a drawn pose less than 1 µs before it, so log times stay distinct).
pub fn keep_poses(poses: &[PoseSample], scene_dt: f64) -> Vec<PoseSample> {
    let mut out: Vec<PoseSample> = Vec::new();
    let n = poses.len();
    for (k, p) in poses.iter().enumerate() {
        let last = k + 1 == n;
        if out.last().is_none_or(|l| p.t >= l.t + scene_dt || last) {
            if last && out.len() > 1 && out.last().is_some_and(|l| p.t - l.t < 1e-6) {
                out.pop();
            }
            out.push(*p);
        }
    }
    out
}

fn fx<T: Encode>(m: &T) -> Vec<u8> {
    let mut b = Vec::with_capacity(m.encoded_len().unwrap_or(256));
    // encoding into a growable Vec cannot run out of space
    m.encode(&mut b).expect("protobuf encoding into a Vec");
    b
}

/// Channels, in the order of the encoded messages' first field.
const TOPICS: [&str; 4] = ["/verify", "/tf", "/scene/static", "/scene"];

/// All messages of design `k` as (channel index into [`TOPICS`], log time, bytes), in
/// time order: at the window start the record, both frames, the static scene and the
/// fingers (deleting the previous design's first); then the object's frame and the fingers
/// at every further pose.
fn encode(k: u64, e: &VerifyEntry, problem: &Problem, opts: &VerifyRecordOptions) -> Vec<(usize, u64, Vec<u8>)> {
    let t0 = window_start_ns(opts.epoch_s.saturating_mul(1_000_000_000), k);
    let sc = &problem.scene;
    let mut r = e.record.clone();
    r.window = k;
    r.window_start = WindowStart { sec: t0 / 1_000_000_000, nsec: t0 % 1_000_000_000 };
    r.window_start_s = k as f64;
    r.epoch_s = opts.epoch_s;
    r.poses = e.poses.len() as u64;
    let p = &r.parameters;
    let design = Design::from_array(&[p.l21, p.b, p.t22, p.r, p.p, p.psi_deg]);
    let finger = Finger::new(&design, sc).ok();
    let mut out = vec![(0, t0, serde_json::to_vec(&r).expect("records serialise"))];
    out.push((2, t0, fx(&free_static_scene(t0, r.id, &design, sc))));
    if e.poses.is_empty() {
        if let Some(m) = free_fingers(r.id, t0, None, [0.0; 4], true) {
            out.push((3, t0, fx(&m)));
        }
        return out;
    }
    for (j, pose) in e.poses.iter().enumerate() {
        let tn = if j == 0 { t0 } else { log_time(t0, pose.t) };
        out.push((1, tn, fx(&free_frames(tn, sc, pose, j == 0))));
        if let Some(m) = free_fingers(r.id, tn, finger.as_ref(), pose.fingers, j == 0) {
            out.push((3, tn, fx(&m)));
        }
    }
    out
}

/// Write the verify recording of `entries` (window k = the entry's index) to `path`
/// (through a temporary file renamed when complete; one zstd chunk per design; summary,
/// statistics, chunk and message indexes). Besides `meta`, the `gripopt.verify` metadata
/// record holds `designs`, `first_window`, `last_window`, `epoch_s`, `scene_dt` and
/// `time_convention`. Returns the file size in bytes.
pub fn write_verify(
    path: &Path,
    problem: &Problem,
    meta: &BTreeMap<String, String>,
    entries: &[VerifyEntry],
    opts: &VerifyRecordOptions,
) -> Result<u64> {
    let tmp = super::mcapfile::temporary(path);
    let mc = super::mcapfile::error(&tmp);
    let mut w = super::mcapfile::open(&tmp, opts.zstd_level, 0)?;
    let mut meta = meta.clone();
    meta.insert("designs".into(), entries.len().to_string());
    meta.insert("first_window".into(), "0".into());
    meta.insert("last_window".into(), entries.len().saturating_sub(1).to_string());
    meta.insert("epoch_s".into(), opts.epoch_s.to_string());
    meta.insert("scene_dt".into(), opts.scene_dt.to_string());
    meta.insert("time_convention".into(), "design k (row k of the verify table): log_time in [epoch_s + k s, epoch_s + k s + 1 s); simulated time t at epoch_s + k s + t".into());
    // metadata before any channel: no empty chunk
    w.write_metadata(&Metadata { name: VERIFY_METADATA.into(), metadata: meta }).map_err(mc)?;
    let none = BTreeMap::new();
    let verify_schema = w
        .add_schema("gripopt.Verify", "jsonschema", &serde_json::to_vec(&verify_schema()).expect("schema serialises"))
        .map_err(mc)?;
    let mut fox = |s: Option<foxglove::Schema>| -> Result<u16> {
        let s = s.expect("the SDK's message types have schemas");
        w.add_schema(&s.name, &s.encoding, &s.data).map_err(mc)
    };
    let (tf_schema, scene_schema) = (fox(FrameTransforms::get_schema())?, fox(SceneUpdate::get_schema())?);
    let schema_of =
        [(verify_schema, "json"), (tf_schema, "protobuf"), (scene_schema, "protobuf"), (scene_schema, "protobuf")];
    let mut chans = [0u16; 4];
    for (k, topic) in TOPICS.iter().enumerate() {
        chans[k] = w.add_channel(schema_of[k].0, topic, schema_of[k].1, &none).map_err(mc)?;
    }
    let mut seq = [0u32; 4];
    for (k, e) in entries.iter().enumerate() {
        for (c, t_ns, data) in encode(k as u64, e, problem, opts) {
            seq[c] += 1;
            w.write_to_known_channel(
                &MessageHeader { channel_id: chans[c], sequence: seq[c], log_time: t_ns, publish_time: t_ns },
                &data,
            )
            .map_err(mc)?;
        }
        w.flush().map_err(mc)?; // one chunk per design
    }
    super::mcapfile::finish(w, &tmp, path)
}

/// The Foxglove layout for verify recordings: the 3-D scene following the hand, and the
/// current design's `/verify` record.
pub fn verify_layout() -> Value {
    let three_d = json!({
        "followTf": "hand",
        "followMode": "follow-position",
        "cameraState": {
            "perspective": true, "distance": 0.45, "phi": 55.0, "thetaOffset": -30.0,
            "targetOffset": [0.0, 0.04, -0.03], "target": [0.0, 0.0, 0.0], "targetOrientation": [0.0, 0.0, 0.0, 1.0],
            "fovy": 45.0, "near": 0.005, "far": 50.0
        },
        "scene": {"enableStats": false, "transforms": {"showLabel": false, "axisScale": 0.3}},
        "transforms": {"frame:world": {"visible": false}, "frame:hand": {"visible": true}, "frame:object": {"visible": true}},
        "topics": {"/scene": {"visible": true}, "/scene/static": {"visible": true}},
        "layers": {"grid": {"layerId": "foxglove.Grid", "visible": true, "frameId": "world", "size": 0.6, "divisions": 12, "lineWidth": 1, "color": "#248eff", "position": [0, 0, 0], "rotation": [0, 0, 0]}}
    });
    json!({
        "configById": {
            "3D!verify": three_d,
            "RawMessages!verify": {"topicPath": "/verify", "diffEnabled": false, "diffMethod": "custom", "diffTopicPath": "", "showFullMessageForDiff": false, "expansion": "all"}
        },
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 0.1},
        "layout": {"direction": "row", "splitPercentage": 62, "first": "3D!verify", "second": "RawMessages!verify"}
    })
}

/// Write [`verify_layout`] to `RUN_DIR/foxglove-verify-layout.json`; returns its path.
pub fn write_verify_layout(run_dir: &Path) -> Result<PathBuf> {
    let path = run_dir.join(VERIFY_LAYOUT_FILE);
    write_atomic(&path, serde_json::to_string_pretty(&verify_layout()).expect("the layout serialises").as_bytes())?;
    Ok(path)
}

/// Rebuild the design's parameters record from a design (ψ in degrees).
pub fn parameters(x: &Design) -> Parameters {
    let a = x.to_array();
    Parameters { l21: a[0], b: a[1], t22: a[2], r: a[3], p: a[4], psi_deg: a[5] }
}
