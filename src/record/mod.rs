//! Recording every evaluated design and its grasp to MCAP, and replaying designs.
//!
//! Layout of `RUN_DIR/recording/`: one MCAP shard per generation (`gen-00001.mcap`, …),
//! written to a temporary file and renamed when complete, so a run killed mid-generation
//! leaves every earlier shard valid, and a resumed run rewrites the unfinished generation
//! (no duplicates); `index.jsonl` maps id ranges to shards. Inside a shard, design k's
//! messages live in the time window [k s, k s + 1 s) (simulated time t is added to the
//! window start, and carried as the field `t`), one zstd chunk per design, with summary,
//! chunk and message indexes, so a replay reads one chunk. See docs/recording.md.
//!
//! This layer sits above the pipeline and the simulator and below the run layer: it never
//! names the optimiser. A design to record is a [`DesignEntry`]; higher layers implement
//! [`Recordable`] for their own types and call [`Recorder::record_generation`].

mod entry;
mod messages;
mod options;
mod recover;
mod replay;
mod schema;
mod writer;

pub use entry::{DesignEntry, Recordable};
pub use messages::{sample_from, window_start_ns, Contacts, Energy, Joints, SceneUpdate};
pub use options::{DEFAULT_ZSTD_LEVEL, DEFAULT_ZSTD_THREADS, RecordOptions, TrajectoryKeep};
pub use recover::{index_entry_from_shard, recover, shard_generation, Recovery};
pub use replay::{Recorded, Replay, read_design, replay};
pub use writer::{Recorder, ShardEntry, read_index, write_shard};
