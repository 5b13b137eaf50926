//! The MCAP recording of `gripopt verify` (`RUN_DIR/verify.mcap`, `verify_sample.mcap`):
//! one design after another, on the run's epoch but in its own time band after the run's
//! designs (window k = [epoch + (base + k) s, epoch + (base + k + 1) s), simulated time t at
//! its start + t, k the row's index in the verify table; [`band_s`]), so that opened
//! together with the run's shards no two designs share a second. Per design: its verify row
//! on `/verify` (JSON, `gripopt.Verify`), the object's motion as columns on `/verify/series`
//! (JSON, `gripopt.VerifySeries`), and the free scene in 3-D with the official Foxglove
//! schemas, in the frames of every gripopt recording (`scene`): `/tf` (`world` → `hand` and
//! `hand` → `object` following the free object's pose), `/scene/static` (ground, palm, the
//! bottle in the frame `object`, a label) and `/scene` (both fingers). See docs/recording.md.

use super::mcapfile::{add_channels, add_foxglove_schema, add_json_schema, write_designs};
use super::messages::{free_fingers, free_frames, free_static_scene, log_time, window_end_ns, window_start_ns};
use super::metadata::{RunMetadata, ScenarioTag};
use crate::error::Result;
use crate::model::Finger;
use crate::params::{Design, Problem};
use crate::sim::{FreeEnd, PoseSample};
use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Encode;
use mcap::records::Metadata;
use serde::Serialize;
use serde_json::{json, Value};
use std::path::Path;

/// Name of the metadata record of a verify recording.
pub const VERIFY_METADATA: &str = "gripopt.verify";

/// Width (s) of one time band of a run's time axis: its design count rounded up to whole
/// thousands (at least 1000). Band 0, [epoch, epoch + band), holds the run's designs (design
/// k at second k); a study of the run records in a later band: `gripopt verify` in band 1,
/// `verify --sample` in band 2, `replay --scenario` from band 3 on ([`scenario_window`]),
/// a single-object free-kind run's `replay` in band 3 ([`free_window`]).
pub fn band_s(run_designs: u64) -> u64 {
    run_designs.div_ceil(1000).max(1) * 1000
}

/// The window, after the start of band 3, of the recording of scenario `k` of object `o` of
/// design `id` (`gripopt replay --scenario`; `objects` objects of `per_object` scenarios
/// each): its own second, `id · objects · per_object + o · per_object + k`, so that any of
/// a run's scenario recordings opened together never share a window.
pub fn scenario_window(id: u64, o: usize, k: usize, objects: usize, per_object: usize) -> u64 {
    id * (objects * per_object) as u64 + (o * per_object + k) as u64
}

/// Seconds from the epoch to the window of the free-scene recording of design `id` of a
/// single-object free-kind run (`gripopt replay RUN --design ID`, `free-ID.mcap`), `band`
/// being [`band_s`]: band 3's start + `id`, the window a scenario recording would have with
/// one object of one scenario. Scenario files belong to robust runs and free files to
/// single-object ones, so files of one run never share a window.
pub fn free_window(band: u64, id: u64) -> u64 {
    3 * band + scenario_window(id, 0, 0, 1, 1)
}

/// One verified design's centred prediction and free-scene measurement: verify.csv's
/// columns after the id and the design's, in order, and the same fields of its `/verify`
/// message (one type for both). A value not computed (`None`) is an empty cell in the CSV and
/// left out of `/verify` (as on `/designs`); so is, on `/verify`, a number JSON cannot hold
/// (not finite).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerifyMeasure {
    /// Prediction: E_cyl/E_lim at the centred first contact (None: no contact).
    pub impact_ratio: Option<f64>,
    /// Prediction: §9.1's E_trans at the centred first contact (J).
    pub e_trans: Option<f64>,
    /// Prediction: §9.1's E_rot (J).
    pub e_rot: Option<f64>,
    /// Prediction: the smaller of the filtered and static force margins (N).
    pub force_margin: f64,
    /// The centred grasp reached stability.
    pub stable: bool,
    /// The centred criteria predict motion: impact ratio > 1 or force margin < 0.
    pub predicted_moves: bool,
    /// Measured: largest horizontal displacement of G (m).
    pub object_max_displacement: f64,
    /// Measured: largest tilt (°).
    pub object_max_tilt_deg: f64,
    /// Measured: peak translational kinetic energy during the first contact (J).
    pub object_peak_e_trans: f64,
    /// Measured: peak rotational kinetic energy during the first contact (J).
    pub object_peak_e_rot: f64,
    /// How the free scene ended: `t_obs`, or why it stopped early (then no verdict: the
    /// verdict flags, `agrees` and the ratios are None).
    pub free_end: FreeEnd,
    /// §14.4's verdict: the object moved more than Δx_max or θ_max.
    pub moved: Option<bool>,
    /// Tilt above 45°.
    pub toppled: Option<bool>,
    /// No phalanx in contact at t_end.
    pub escaped: Option<bool>,
    /// A phalanx met the rim or a face.
    pub rim_contact: bool,
    /// Prediction and measurement agree.
    pub agrees: Option<bool>,
    /// Object peak E_trans / §9.1's E_trans.
    pub peak_e_trans_ratio: Option<f64>,
    /// Object peak E_rot / §9.1's E_rot.
    pub peak_e_rot_ratio: Option<f64>,
}

/// The scenario of a `/verify` message of a `replay --scenario` recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerifyScenario {
    /// The object's name.
    pub scenario_object: String,
    /// The scenario's index among the object's.
    pub scenario_index: u64,
    /// The scenario's drawn hand height offset (m).
    pub height_offset: f64,
}

impl From<&ScenarioTag> for VerifyScenario {
    fn from(t: &ScenarioTag) -> Self {
        VerifyScenario { scenario_object: t.object.clone(), scenario_index: t.index, height_offset: t.height_offset }
    }
}

/// The `/verify` message of one design: its time window, the design, the verify row's
/// [`VerifyMeasure`] and the free scene's end time (and, in a scenario recording, which
/// scenario). Written with its keys sorted and the values not computed left out.
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
    /// Prediction and measurement.
    #[serde(flatten)]
    pub measure: VerifyMeasure,
    /// Time the free scene reached (s): the last pose drawn.
    pub t_end: f64,
    /// Object poses drawn (`/tf` hand → object messages).
    pub poses: u64,
    /// The scenario (a `replay --scenario` recording).
    #[serde(flatten)]
    pub scenario: Option<VerifyScenario>,
}

impl VerifyRecord {
    /// The message's JSON: keys sorted, values not computed (null: `None` or not finite)
    /// left out.
    pub fn to_json(&self) -> Vec<u8> {
        let mut v = serde_json::to_value(self).expect("records serialise");
        if let Value::Object(m) = &mut v {
            m.retain(|_, v| !v.is_null());
        }
        serde_json::to_vec(&v).expect("records serialise")
    }
}

/// `/verify`'s fields (`gripopt.Verify`): name, JSON type, whether every message has it.
const VERIFY_FIELDS: [(&str, &str, bool); 30] = [
    ("window", "integer", true),
    ("window_start", "object", true),
    ("window_start_s", "number", true),
    ("epoch_s", "integer", true),
    ("id", "integer", true),
    ("parameters", "object", true),
    ("x_off", "number", true),
    ("impact_ratio", "number", false),
    ("e_trans", "number", false),
    ("e_rot", "number", false),
    ("force_margin", "number", false),
    ("stable", "boolean", true),
    ("predicted_moves", "boolean", true),
    ("object_max_displacement", "number", true),
    ("object_max_tilt_deg", "number", true),
    ("object_peak_e_trans", "number", true),
    ("object_peak_e_rot", "number", true),
    ("free_end", "string", true),
    ("moved", "boolean", false),
    ("toppled", "boolean", false),
    ("escaped", "boolean", false),
    ("rim_contact", "boolean", true),
    ("agrees", "boolean", false),
    ("peak_e_trans_ratio", "number", false),
    ("peak_e_rot_ratio", "number", false),
    ("t_end", "number", true),
    ("poses", "integer", true),
    ("scenario_object", "string", false),
    ("scenario_index", "integer", false),
    ("height_offset", "number", false),
];

/// A window start as seconds and nanoseconds since 1970.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct WindowStart {
    /// Seconds.
    pub sec: u64,
    /// Nanoseconds.
    pub nsec: u64,
}

/// The design's parameters, as on `/designs` (the one type of a design as written).
pub use crate::params::DesignParameters as Parameters;

/// JSON schema of `/verify` (`gripopt.Verify`), parsable by Foxglove (one type per field),
/// from [`VERIFY_FIELDS`].
pub fn verify_schema() -> Value {
    let obj = |props: Value, required: &[&str]| json!({"type": "object", "properties": props, "required": required});
    let num = || json!({"type": "number"});
    let int = || json!({"type": "integer", "minimum": 0});
    let names = ["l21", "b", "t22", "r", "p", "psi_deg"];
    let props: serde_json::Map<String, Value> = VERIFY_FIELDS
        .iter()
        .map(|&(name, kind, _)| {
            let v = match (name, kind) {
                ("window_start", _) => obj(json!({"sec": int(), "nsec": int()}), &["sec", "nsec"]),
                ("parameters", _) => obj(names.iter().map(|n| (n.to_string(), num())).collect(), &names),
                (_, "integer") => int(),
                (_, kind) => json!({ "type": kind }),
            };
            (name.to_string(), v)
        })
        .collect();
    let required: Vec<&str> = VERIFY_FIELDS.iter().filter(|f| f.2).map(|f| f.0).collect();
    let mut s = obj(Value::Object(props), &required);
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
    /// Seconds from the epoch to window 0 (the start of the recording's band, [`band_s`]).
    pub window_base_s: u64,
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
const TOPICS: [&str; 5] = ["/verify", "/tf", "/scene/static", "/scene", "/verify/series"];

/// The object's motion of one window as columns against its simulated time, for the Plot
/// panel: the horizontal displacement of G from its start and the tilt, at the drawn poses
/// (the verdict's limits are Δx_max and θ_max; the exact maxima are in `/verify`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerifySeries {
    /// The window index k.
    pub window: u64,
    /// The design id.
    pub id: u64,
    /// Simulated time (s).
    pub t: Vec<f64>,
    /// |G_xy(t) − G_xy(0)| (mm).
    pub displacement_mm: Vec<f64>,
    /// Angle between the object's axis and the vertical (°).
    pub tilt_deg: Vec<f64>,
}

/// JSON schema of `/verify/series` (`gripopt.VerifySeries`).
pub fn verify_series_schema() -> Value {
    let nums = || json!({"type": "array", "items": {"type": "number"}});
    let int = || json!({"type": "integer", "minimum": 0});
    json!({
        "title": "gripopt.VerifySeries", "type": "object",
        "properties": {"window": int(), "id": int(), "t": nums(), "displacement_mm": nums(), "tilt_deg": nums()},
        "required": ["window", "id", "t", "displacement_mm", "tilt_deg"]
    })
}

/// The series of window `k` from its poses (one sample at rest at t = 0 when there is none:
/// an empty message would leave the previous window's curves in the Plot panel).
fn series_of(k: u64, id: u64, poses: &[PoseSample]) -> VerifySeries {
    let mut s = VerifySeries { window: k, id, t: vec![], displacement_mm: vec![], tilt_deg: vec![] };
    let g0 = poses.first().map_or([0.0; 3], |p| p.g);
    for p in poses {
        s.t.push(p.t);
        s.displacement_mm.push((p.g[0] - g0[0]).hypot(p.g[1] - g0[1]) * 1e3);
        s.tilt_deg.push(p.tilt.to_degrees());
    }
    if s.t.is_empty() {
        (s.t, s.displacement_mm, s.tilt_deg) = (vec![0.0], vec![0.0], vec![0.0]);
    }
    s
}

/// The label drawn above the scene: what was predicted and what the free object did (in a
/// scenario recording, which scenario: "68 (bottle-half:0, +4.2 mm): …").
fn verdict(r: &VerifyRecord, scenario: Option<&ScenarioTag>) -> String {
    let m = &r.measure;
    let outcome = match m.moved {
        Some(true) => "moved",
        Some(false) => "barely moved",
        None => "not observed to the end",
    };
    let predicted = if m.predicted_moves { "moves" } else { "stays" };
    let which = match scenario {
        Some(t) => format!("scenario {}:{}, height {:+.1} mm", t.object, t.index, t.height_offset * 1e3),
        None => format!("row {}", r.window),
    };
    format!(
        "{} ({which}): predicted {predicted}; {outcome}: {:.3} mm, {:.3} deg",
        r.id,
        m.object_max_displacement * 1e3,
        m.object_max_tilt_deg
    )
}

/// All messages of design `k` as (channel index into [`TOPICS`], log time, bytes), in
/// time order: at the window start the record, the series, the static scene, the frames and
/// the fingers (deleting the previous design's first); then the frames and the fingers at
/// every further pose; at the window's last nanosecond the frames at the final pose.
fn encode(
    k: u64,
    e: &VerifyEntry,
    problem: &Problem,
    opts: &VerifyRecordOptions,
    scenario: Option<&ScenarioTag>,
) -> Vec<(usize, u64, Vec<u8>)> {
    let t0 = window_start_ns(opts.epoch_s.saturating_mul(1_000_000_000), opts.window_base_s + k);
    let sc = &problem.scene;
    let mut r = e.record.clone();
    r.window = k;
    r.window_start = WindowStart { sec: t0 / 1_000_000_000, nsec: t0 % 1_000_000_000 };
    r.window_start_s = (opts.window_base_s + k) as f64;
    r.epoch_s = opts.epoch_s;
    // one pose at least: a design the free scene ended at its start is drawn at its start
    r.poses = e.poses.len().max(1) as u64;
    let p = &r.parameters;
    let design = Design::from_array(&[p.l21, p.b, p.t22, p.r, p.p, p.psi_deg]);
    let finger = Finger::new(&design, sc).ok();
    let series = serde_json::to_vec(&series_of(k, r.id, &e.poses)).expect("series serialise");
    r.scenario = scenario.map(VerifyScenario::from);
    let mut out = vec![(0, t0, r.to_json()), (4, t0, series)];
    out.push((2, t0, fx(&free_static_scene(t0, r.id, &design, sc, &verdict(&r, scenario)))));
    let end = window_end_ns(t0);
    let Some(last) = e.poses.last() else {
        // nothing simulated (the free scene ended at its start, e.g. an open finger inside the
        // object): the scene at its start, the object standing at x_off, the fingers open, so
        // that every frame drawn has its transform for the whole window
        let g = [sc.setup.x_off, sc.object.radius, sc.object.length / 2.0 - sc.object.grasp_height];
        let q = [1.0, 0.0, 0.0, 0.0];
        let open = finger.as_ref().map_or([0.0; 4], |f| [f.open.q11, f.open.q21, f.open.q11, f.open.q21]);
        out.push((1, t0, fx(&free_frames(t0, sc, g, q))));
        if let Some(m) = free_fingers(r.id, t0, finger.as_ref(), open, true) {
            out.push((3, t0, fx(&m)));
        }
        out.push((1, end, fx(&free_frames(end, sc, g, q))));
        return out;
    };
    for (j, pose) in e.poses.iter().enumerate() {
        let tn = if j == 0 { t0 } else { log_time(t0, pose.t) };
        out.push((1, tn, fx(&free_frames(tn, sc, pose.g, pose.q))));
        if let Some(m) = free_fingers(r.id, tn, finger.as_ref(), pose.fingers, j == 0) {
            out.push((3, tn, fx(&m)));
        }
    }
    out.push((1, end, fx(&free_frames(end, sc, last.g, last.q))));
    out
}

/// Write the verify recording of `entries` (window k = the entry's index) to `path`
/// (through a temporary file renamed when complete; one zstd chunk per design; summary,
/// statistics, chunk and message indexes). Besides `meta`, the `gripopt.verify` metadata
/// record holds `designs`, `first_window`, `last_window`, `epoch_s`, `window_base_s`,
/// `scene_dt` and `time_convention`. Returns the file size in bytes.
pub fn write_verify(
    path: &Path,
    problem: &Problem,
    meta: &RunMetadata,
    entries: &[VerifyEntry],
    opts: &VerifyRecordOptions,
) -> Result<u64> {
    let tmp = super::mcapfile::temporary(path);
    let mc = super::mcapfile::error(&tmp);
    let mut w = super::mcapfile::open(&tmp, opts.zstd_level, 0)?;
    let scenario = meta.scenario.clone();
    let meta = RunMetadata {
        designs: Some(entries.len() as u64),
        first_window: Some(0),
        last_window: Some(entries.len().saturating_sub(1) as u64),
        epoch_s: Some(opts.epoch_s),
        window_base_s: Some(opts.window_base_s),
        scene_dt: Some(opts.scene_dt),
        time_convention: Some("design k (row k of the verify table): log_time in [epoch_s + (window_base_s + k) s, epoch_s + (window_base_s + k + 1) s); simulated time t at its start + t".into()),
        ..meta.clone()
    };
    // metadata before any channel: no empty chunk
    w.write_metadata(&Metadata { name: VERIFY_METADATA.into(), metadata: meta.to_map() }).map_err(mc)?;
    let verify_schema = add_json_schema(&mut w, "gripopt.Verify", &verify_schema(), &tmp)?;
    let tf_schema = add_foxglove_schema(&mut w, FrameTransforms::get_schema(), &tmp)?;
    let scene_schema = add_foxglove_schema(&mut w, SceneUpdate::get_schema(), &tmp)?;
    let series_schema = add_json_schema(&mut w, "gripopt.VerifySeries", &verify_series_schema(), &tmp)?;
    let schema_of = [
        (verify_schema, "json"),
        (tf_schema, "protobuf"),
        (scene_schema, "protobuf"),
        (scene_schema, "protobuf"),
        (series_schema, "json"),
    ];
    let chans = add_channels(&mut w, &TOPICS, &schema_of, &tmp)?;
    let designs = entries.iter().enumerate().map(|(k, e)| encode(k as u64, e, problem, opts, scenario.as_ref()));
    write_designs(&mut w, &chans, designs, &tmp)?;
    super::mcapfile::finish(w, &tmp, path)
}

/// Rebuild the design's parameters record from a design (ψ in degrees).
pub fn parameters(x: &Design) -> Parameters {
    Parameters::from_array(&x.to_array())
}
