//! The metadata records of gripopt's MCAP files as one type, [`RunMetadata`]: a shard's
//! `gripopt.run`, the front's `gripopt.front` and a verify recording's `gripopt.verify`. MCAP
//! metadata is a map of strings; [`RunMetadata::to_map`] writes it and
//! [`RunMetadata::from_map`] reads it back (a key absent is `None`, a value that does not
//! parse is an error naming the key), so no writer or reader handles the keys by hand.

use super::Resolution;
use crate::params::SceneKind;
use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// Name of a shard's metadata record.
pub const RUN_METADATA: &str = "gripopt.run";

impl Resolution {
    /// The word run.json and the metadata use (`compact`, `full`).
    pub fn as_str(self) -> &'static str {
        match self {
            Resolution::Compact => "compact",
            Resolution::Full => "full",
        }
    }
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "compact" => Ok(Resolution::Compact),
            "full" => Ok(Resolution::Full),
            _ => Err(format!("{s:?} is not a resolution (\"full\" or \"compact\")")),
        }
    }
}

/// Which robust scenario a `replay --scenario` recording holds (its `scenario_*` keys).
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioTag {
    /// The object's name (`scenario_object`).
    pub object: String,
    /// The scenario's index among the object's (`scenario_index`).
    pub index: u64,
    /// The object's grasp height (m; `object_grasp_height`).
    pub grasp_height: f64,
    /// The scenario's drawn height offset (m; `height_offset`): the hand's height is
    /// `grasp_height + height_offset`.
    pub height_offset: f64,
}

/// A metadata record of a gripopt MCAP file, every key typed (`None`: the key is absent; the
/// writers state only what applies to their file). Keys the type does not know are ignored
/// when read (a newer gripopt may add some).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunMetadata {
    /// gripopt version of the writer.
    pub gripopt_version: Option<String>,
    /// Simulator revision of the run (shards; absent in recordings of revision 1).
    pub simulator_revision: Option<u32>,
    /// The run's id (shards; a free-scene replay's recording).
    pub run_id: Option<String>,
    /// The problem's name (shards: `problem`).
    pub problem: Option<String>,
    /// The problem's name (verify recordings: `problem_name`).
    pub problem_name: Option<String>,
    /// SHA-256 of the problem file.
    pub problem_sha256: Option<String>,
    /// The run's algorithm settings as JSON (shards).
    pub settings: Option<String>,
    /// The run's recording options as JSON (shards).
    pub recording: Option<String>,
    /// The run's status when the front was written (`gripopt.front`).
    pub status: Option<String>,
    /// What a verify recording holds (`pareto`, `all`, `sample N seed S`, a replay).
    pub source: Option<String>,
    /// Marks a shard of `gripopt bench replay`'s synthetic run.
    pub synthetic: Option<String>,
    /// The generation of a shard's designs.
    pub generation: Option<u64>,
    /// First design id (`Some(None)`: written empty, a front of no design).
    pub first_id: Option<Option<u64>>,
    /// Last design id (as `first_id`).
    pub last_id: Option<Option<u64>>,
    /// Designs in the file.
    pub designs: Option<u64>,
    /// Designs on the final front (`gripopt.front`).
    pub front_size: Option<u64>,
    /// Generations the run had completed (`gripopt.front`).
    pub generations: Option<u64>,
    /// First window of a verify recording.
    pub first_window: Option<u64>,
    /// Last window of a verify recording.
    pub last_window: Option<u64>,
    /// The design of a free-scene replay's recording (`free_design`).
    pub free_design: Option<u64>,
    /// The scene of stage 3 where not centred (shards: `scene_kind`).
    pub scene_kind: Option<SceneKind>,
    /// The object's offset (m; shards of a non-centred scene).
    pub x_off: Option<f64>,
    /// What a shard's 3-D scene draws (non-centred scenes).
    pub scene_drawn: Option<String>,
    /// A verify recording's free scene and its offset (m; `scene` = `free:X_OFF`).
    pub free_scene_x_off: Option<f64>,
    /// The scenario of a `replay --scenario` recording.
    pub scenario: Option<ScenarioTag>,
    /// Epoch of the time axis, whole seconds since 1970.
    pub epoch_s: Option<u64>,
    /// A verify recording's first window, in seconds after the epoch.
    pub window_base_s: Option<u64>,
    /// Interval of the 3-D scene updates (s of simulated time; verify recordings).
    pub scene_dt: Option<f64>,
    /// Trajectory resolution (shards).
    pub resolution: Option<Resolution>,
    /// How log time maps to designs and simulated time, in words.
    pub time_convention: Option<String>,
}

/// A required key that is absent: the error names it.
fn missing(key: &str) -> String {
    format!("metadata `{key}` is missing (a recording from an older gripopt?)")
}

impl RunMetadata {
    /// The record as MCAP metadata (each value as text: numbers as Rust prints them, which
    /// read back exactly).
    pub fn to_map(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                m.insert(k.to_string(), v);
            }
        };
        let s = |v: &Option<String>| v.clone();
        let n = |v: Option<u64>| v.map(|v| v.to_string());
        let f = |v: Option<f64>| v.map(|v| v.to_string());
        let id = |v: Option<Option<u64>>| v.map(|v| v.map_or(String::new(), |v| v.to_string()));
        put("gripopt_version", s(&self.gripopt_version));
        put("simulator_revision", self.simulator_revision.map(|v| v.to_string()));
        put("run_id", s(&self.run_id));
        put("problem", s(&self.problem));
        put("problem_name", s(&self.problem_name));
        put("problem_sha256", s(&self.problem_sha256));
        put("settings", s(&self.settings));
        put("recording", s(&self.recording));
        put("status", s(&self.status));
        put("source", s(&self.source));
        put("synthetic", s(&self.synthetic));
        put("generation", n(self.generation));
        put("first_id", id(self.first_id));
        put("last_id", id(self.last_id));
        put("designs", n(self.designs));
        put("front_size", n(self.front_size));
        put("generations", n(self.generations));
        put("first_window", n(self.first_window));
        put("last_window", n(self.last_window));
        put("free_design", n(self.free_design));
        put("scene_kind", self.scene_kind.map(|k| k.to_string()));
        put("x_off", f(self.x_off));
        put("scene_drawn", s(&self.scene_drawn));
        put("scene", self.free_scene_x_off.map(|x| format!("free:{x}")));
        if let Some(t) = &self.scenario {
            put("scenario_object", Some(t.object.clone()));
            put("scenario_index", Some(t.index.to_string()));
            put("object_grasp_height", Some(t.grasp_height.to_string()));
            put("height_offset", Some(t.height_offset.to_string()));
        }
        put("epoch_s", n(self.epoch_s));
        put("window_base_s", n(self.window_base_s));
        put("scene_dt", f(self.scene_dt));
        put("resolution", self.resolution.map(|r| r.to_string()));
        put("time_convention", s(&self.time_convention));
        m
    }

    /// Read a metadata record: an absent key is `None`; a value that does not parse is an
    /// error naming the key and the value (a scenario needs all four `scenario_*` keys).
    pub fn from_map(m: &BTreeMap<String, String>) -> Result<Self, String> {
        fn parse<T: FromStr>(m: &BTreeMap<String, String>, k: &str, what: &str) -> Result<Option<T>, String> {
            m.get(k).map(|v| v.parse().map_err(|_| format!("metadata `{k}` is {v:?}, not {what}"))).transpose()
        }
        let s = |k: &str| m.get(k).cloned();
        let n = |k: &str| parse::<u64>(m, k, "a whole number");
        let f = |k: &str| parse::<f64>(m, k, "a number");
        let id = |k: &str| -> Result<Option<Option<u64>>, String> {
            match m.get(k).map(String::as_str) {
                Some("") => Ok(Some(None)),
                _ => n(k).map(|v| v.map(Some)),
            }
        };
        let scenario = match m.get("scenario_object") {
            None => None,
            Some(object) => {
                let need = |r: Result<Option<f64>, String>, k: &str| r?.ok_or_else(|| missing(k));
                Some(ScenarioTag {
                    object: object.clone(),
                    index: n("scenario_index")?.ok_or_else(|| missing("scenario_index"))?,
                    grasp_height: need(f("object_grasp_height"), "object_grasp_height")?,
                    height_offset: need(f("height_offset"), "height_offset")?,
                })
            }
        };
        let free_scene_x_off = match m.get("scene") {
            None => None,
            Some(v) => Some(
                v.strip_prefix("free:")
                    .and_then(|x| x.parse().ok())
                    .ok_or_else(|| format!("metadata `scene` is {v:?}, not `free:` and the object's offset"))?,
            ),
        };
        let resolution = m
            .get("resolution")
            .map(|v| v.parse::<Resolution>().map_err(|e| format!("metadata `resolution`: {e}")))
            .transpose()?;
        Ok(RunMetadata {
            gripopt_version: s("gripopt_version"),
            simulator_revision: parse(m, "simulator_revision", "an integer")?,
            run_id: s("run_id"),
            problem: s("problem"),
            problem_name: s("problem_name"),
            problem_sha256: s("problem_sha256"),
            settings: s("settings"),
            recording: s("recording"),
            status: s("status"),
            source: s("source"),
            synthetic: s("synthetic"),
            generation: n("generation")?,
            first_id: id("first_id")?,
            last_id: id("last_id")?,
            designs: n("designs")?,
            front_size: n("front_size")?,
            generations: n("generations")?,
            first_window: n("first_window")?,
            last_window: n("last_window")?,
            free_design: n("free_design")?,
            scene_kind: m
                .get("scene_kind")
                .map(|v| {
                    v.parse::<SceneKind>()
                        .map_err(|()| format!("metadata `scene_kind` is {v:?}, not centred, offset or free"))
                })
                .transpose()?,
            x_off: f("x_off")?,
            scene_drawn: s("scene_drawn"),
            free_scene_x_off,
            scenario,
            epoch_s: n("epoch_s")?,
            window_base_s: n("window_base_s")?,
            scene_dt: f("scene_dt")?,
            resolution,
            time_convention: s("time_convention"),
        })
    }

    /// The epoch, required (an error naming `epoch_s` where absent).
    pub fn require_epoch_s(&self) -> Result<u64, String> {
        self.epoch_s.ok_or_else(|| missing("epoch_s"))
    }

    /// The resolution, required (an error naming `resolution` where absent).
    pub fn require_resolution(&self) -> Result<Resolution, String> {
        self.resolution.ok_or_else(|| missing("resolution"))
    }
}
