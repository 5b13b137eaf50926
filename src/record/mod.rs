//! Recording every evaluated design and its grasp to MCAP, and reading designs back (`read`)
//! and comparing them, typed, with a re-evaluation (`compare`; the replay itself, which
//! re-runs a design through its study, is the app layer's).
//!
//! Layout of `RUN_DIR/recording/`: one MCAP shard per generation (`gen-00001.mcap`, …),
//! written to a temporary file and renamed when complete, so a run killed mid-generation
//! leaves every earlier shard valid, and a resumed run rewrites the unfinished generation
//! (no duplicates); `index.jsonl` maps id ranges to shards. Inside a shard, design k's
//! messages live in the time window [epoch + k s, epoch + k s + 1 s) (epoch = the run's
//! start time; simulated time t is added to the window start), one zstd chunk per design,
//! with summary, chunk and message indexes, so a replay reads one chunk. Foxglove channels
//! use the official schemas of the `foxglove` SDK (protobuf); gripopt's own are
//! `/designs` (JSON) and `/grasp/series` (protobuf). See docs/recording.md.
//!
//! This layer sits above the pipeline and the simulator and below the run layer: it never
//! names the optimiser. A design to record is a [`DesignEntry`]; higher layers implement
//! [`Recordable`] for their own types and hand the recorder's shard tasks their designs.
//!
//! `gripopt verify` records too ([`write_verify`]): one file per verify run, the free
//! scene's object pose as a moving frame (see `verify_rec`), in a time band after the run's
//! designs. When the run ends, `recording/front-NNNNN.mcap` for each shard says which
//! of its designs are on the final front ([`write_front`]). Every recording draws one physical scene (`scene`: `world` z up,
//! the hand horizontal at the grasp height, the object standing on the ground).

mod compare;
mod entry;
mod front;
mod index;
mod kept;
mod layout;
mod mcapfile;
mod messages;
mod metadata;
mod options;
mod proto;
mod read;
mod recover;
mod scenario_kept;
mod scenario_scene;
mod scenario_series;
mod scene;
mod schema;
mod verify_rec;
mod writer;

pub use compare::{compare_grasp, compare_robust, AcrossRevisions, Comparison};
pub use entry::{DesignEntry, Recordable};
pub use front::{front_file, front_schema, write_front, FrontRecord, FRONT_FILE, FRONT_METADATA};
pub use index::{read_index, ProblemUse, ShardEntry};
pub use kept::{scene_samples, KeptTrajectory};
pub use layout::{
    layout, robust_layout, run_layouts, verify_layout, write_layout, write_verify_layout, LAYOUT_FILE,
    LEGEND_MAX_CHARS, PLAYBACK_SPEED, VERIFY_LAYOUT_FILE,
};
pub use messages::{samples_from, window_start_ns, Finger2Columns};
pub use metadata::{RunMetadata, ScenarioTag, RUN_METADATA};
pub use options::{
    RecordOptions, Resolution, TrajectoryKeep, COMPACT_DT, DEFAULT_SCENE_DT, DEFAULT_ZSTD_LEVEL, DEFAULT_ZSTD_THREADS,
};
pub use proto::{GraspSeries, SERIES_NAME};
pub use read::{problem_of_generation, read_design, run_recording, Recorded, RunProblem};
pub use recover::{
    index_entry_from_shard, index_or_rebuilt, recover, recover_run, shard_generation, shard_metadata, Recovery,
};
pub use scenario_kept::{ScenarioMotion, ScenarioScene, SCENARIO_DT};
pub use scenario_scene::{SceneMessage, ShownScenario};
pub use scenario_series::{scenario_series_descriptor, ScenarioSeries, SCENARIO_FIELDS, SCENARIO_SERIES_NAME};
pub use scene::{HAND, OBJECT, WORLD};
pub use schema::design as design_schema;
pub use schema::{Derived, DesignMessage, DesignParameters, Objectives, StageSeconds, Window};
pub use verify_rec::{
    band_s, free_window, keep_poses, parameters as verify_parameters, scenario_window, verify_schema,
    verify_series_schema, write_verify, Parameters, VerifyEntry, VerifyMeasure, VerifyRecord, VerifyRecordOptions,
    VerifyScenario, VerifySeries, WindowStart, VERIFY_METADATA,
};
pub use writer::{write_shard, Recorder, ShardTask};
