//! Optimisation runs: the gripper design problem as a [`crate::optim::MooProblem`]
//! (`gripper`), run folders with exact resume (`rundir`), checkpoint files
//! (`checkpoint`), the argmin observers that report progress, write checkpoints and
//! record designs (`observers`), the result CSVs (`outputs`) and plots (`plots`).
//!
//! This layer sits on top: it uses the pure optimiser ([`crate::optim`]) and the recorder
//! ([`crate::record`]); neither of them names it.

mod archive;
mod attribution;
mod certify;
mod certify_stage;
mod checkpoint;
mod checkpoint_json;
mod contents;
mod differences;
mod folder;
mod grasp_plot;
mod gripper;
mod info;
mod invariants;
mod limits;
mod lock;
mod observers;
mod outputs;
mod persist;
mod plots;
mod problems;
mod robust_columns;
mod rundir;
mod scheduler;
mod tables;
mod verify;
mod verify_rec;
mod verify_robust;
mod verify_run;

pub use crate::error::{cap_lines, counted, exact_num, hidden, printable, shell_quote, short_num};
pub use archive::{front_cap, reported_front, Archive, DiscardCause, Discards};
pub use certify::{
    certification_study, certified_row, certify_front, read_certification, write_certification, CertificationFile,
    CertifiedFront, CERTIFICATION_FILE,
};
pub use certify_stage::{certify_run, checkpoint_front, CertificationSummary, SEARCH_FRONT_FILE};
pub use checkpoint::{settings_hash, sha256_hex, Checkpoint, ChecksumMismatch, RunOptions, FORMAT, PIPELINE, VERSION};
pub use folder::{read_table, RunFolder, RunState};
pub use grasp_plot::grasp_plot;
pub use gripper::{GripperInfo, GripperProblem, TrajectoryKeep};
pub use info::{new_run_id, RecordingHeader, Resume, RunHeader, RunInfo, RunStatus, RUN_FILE};
pub use limits::{
    check_population, check_record_size, check_sample, check_threads, sample_bytes_recorded, scenario_records,
    threads_note, BYTES_PER_DESIGN, BYTES_PER_SCENARIO_JSON, MAX_THREADS, MIN_DESIGNS_PER_THREAD,
    SAMPLE_BYTES_PER_DESIGN,
};
pub use lock::{LockHolder, RunLock, LOCK_FILE};
pub use observers::{GenerationReport, OutputsObserver, Progress};
pub use outputs::{
    header, write_outputs, write_tables, Column, DesignRow, HistoryRow, TimingRow, DESIGN_COLUMNS, HISTORY_COLUMNS,
};
pub use persist::{CheckpointSpec, Committed, PersistHooks, PersistStats, Persister, VIEWS_MIN_INTERVAL};
pub use plots::{hypervolume, pareto_matrix};
pub use problems::PROBLEM_FILE;
pub use robust_columns::{
    is_robust_column, robust_unit, RobustColumns, CERTIFIED_COLUMNS, CERTIFIED_OBJECT_COLUMNS, OBJECT_COLUMNS,
    ROBUST_COLUMNS,
};
pub use rundir::{optimise, optimise_with, resume, resume_with, RunHooks, RunSpec, RunSummary};
pub use scheduler::StudyScheduled;
pub use tables::CheckpointTables;
pub(crate) use verify::row_of;
pub use verify::{
    checkpoint_designs, read_design_csv, read_design_rows, sample_designs, verify_csv, verify_design,
    verify_design_poses, verify_designs, verify_designs_poses, Confusion, VerifiedGeneration, VerifyRow, VerifySource,
    VerifySummary, VERIFY_COLUMNS, VERIFY_FILE, VERIFY_SAMPLE_FILE,
};
pub(crate) use verify_rec::VerifyRecording;
pub use verify_rec::{VERIFY_MCAP, VERIFY_SAMPLE_MCAP};
pub use verify_robust::{
    is_robust_run, verify_robust, AbortedOutOfSample, RobustVerifyRow, RobustVerifySummary, VERIFY_ROBUST_FILE,
};
pub use verify_run::verify;
