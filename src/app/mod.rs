//! The application layer: what a user asks of gripopt, as typed requests and results —
//! evaluate designs, simulate one in a scene (on any object), optimise or resume a run, read a
//! run folder back, replay a recorded design, verify a run on another study, show a run,
//! export a design, sweep a grid, time the benchmarks. The CLI (parses and renders) and the
//! Python binding (converts, owns the GIL, signals and the fork-safe pool) use this layer and
//! nothing else of the library: its re-exports below are the types its requests and results
//! are made of, so a front end never names a path inside the layers.
//!
//! Files: `evaluate` (one design, a batch, a batch as a run's rows) · `simulate` (one design
//! in a scene, on the reference or a robust object) · `runs` (the [`Optimiser`] builder, a run
//! of a problem held in memory, recording options by field) · `replay` (a recorded design
//! re-run through its study and compared; another scene) ← `scenario` (one scenario of a
//! robust design) · `free_scene` (a free-kind design's free scene recorded by its replay) ·
//! `verify` (a run's designs on another study) · `show` (a run's state and designs) · `export`
//! (the design and scene to export) · `sweep` (a parameter study) · `folder` (a run folder
//! opened only where it holds a run; its design tables as the checkpoint holds them) ·
//! `portable` (a problem's text with its object files written inline, for a pickle).

mod evaluate;
mod export;
mod folder;
mod free_scene;
mod portable;
mod replay;
mod runs;
mod scenario;
mod show;
mod simulate;
mod sweep;
mod verify;

pub use evaluate::{
    evaluate, evaluate_batch, evaluate_into, evaluate_rows, evaluation_record, random_designs, row_template,
    EvaluatedRow, Stages,
};
pub use export::{check_open_hand, exported_design, run_design};
pub use folder::{design_table, open_run};
pub use free_scene::{free_file_name, record_free_scene, FreeRecording};
pub use portable::{from_inlined, inlined_text};
pub use replay::{design_in_scene, replay, DesignInScene, Replay, ReplayInScene, ReplaySource};
pub use runs::{record_options, Optimiser, ProblemRun};
pub use scenario::{parse_scenario, replay_scenario, ScenarioReplay};
pub use show::{objective_named, row_objectives, show_design, show_run, DesignView, RunView, ShowRequest};
pub use simulate::{
    check_rtol, object_index, simulate, simulate_into, NoSuchObject, SimulateRequest, Simulated, Simulation,
};
pub use sweep::{
    empty_plots, open_sweep_folder, run_sweep, sweep_spec, unused_names, write_sweep, SweepRequest, Swept,
};
pub use verify::{verify, Verified, VerifyRequest};

// What the requests and results are made of (the layers' own types, re-exported as the face).
pub use crate::error::{cap_lines, counted, exact_num, printable, shell_quote, short_num, Error, Result};
pub use crate::eval::{
    objective_names, robust_summary, Cause, EvaluationRecord, FreeSceneRecord, GraspRecord, ImpactRecord,
    KinematicsRecord, Objective, Objectives, Record, ScenarioRecord, Sense, SimulationRecord, StaticsRecord,
    WorkRecord, OBJECTIVES,
};
pub use crate::export::{write_file as write_export, ExportedDesign};
pub use crate::fsutil::lock::RunLock;
pub use crate::fsutil::{
    check_new_file, check_output_file, run_folder_around, run_folder_file, set_aside, write_atomic, AtomicFile,
    SET_ASIDE_DIR,
};
pub use crate::optim::{Batch, Evaluations, Evaluator, Infeasibility};
pub use crate::params::{
    fmt_num, limit, Bounds, Design, DesignParameters, Problem, SceneChoice, SceneKind, DESIGN_NAMES,
};
pub use crate::record::{
    design_schema, AcrossRevisions, DesignMessage, RecordOptions, Recorded, Resolution, TrajectoryKeep,
    DEFAULT_SCENE_DT, DEFAULT_ZSTD_LEVEL, DEFAULT_ZSTD_THREADS, VERIFY_LAYOUT_FILE,
};
pub use crate::run::{
    check_population, check_threads, grasp_plot, is_robust_run, robust_unit, CertificationSummary, CheckpointTables,
    Column, Confusion, DesignRow, GenerationReport, GripperProblem, HistoryRow, Progress, RobustColumns,
    RobustVerifySummary, RunFolder, RunInfo, RunState, RunSummary, VerifiedGeneration, VerifyRow, VerifySource,
    VerifySummary, DESIGN_COLUMNS, HISTORY_COLUMNS, MAX_THREADS, OBJECT_COLUMNS, PROBLEM_FILE, ROBUST_COLUMNS,
    SEARCH_FRONT_FILE,
};
pub use crate::sim::{
    pose_values, sample_values, series_field, trajectory_columns, trajectory_row, Controls, EventNote, FingerSample,
    Integration, Method, Mode, Point, PoseSample, Sample, Sink, Trajectory, ACROSS_REVISIONS_RTOL, FINGER2_COLUMNS,
    POSE_COLUMNS, SAMPLE_COLUMNS,
};

/// `gripopt bench`: the speed figures (the benchmark layer's entry points and settings), and
/// the replay benchmark timing this layer's replay.
pub mod bench {
    pub use crate::bench::{
        accuracy, check_atol, free_scene, nsga, scaling, static_pipeline, work_precision, work_precision_ensemble,
        AccuracyBench, BenchProgress, Candidate, EnsembleBench, FreeBench, Out, ReplayBench, ScalingBench,
        WorkPrecision, FREE_RTOLS, RTOLS,
    };
    use crate::error::Result;
    use crate::params::Problem;

    /// `gripopt bench replay`: finding, reading and replaying designs of a large synthetic
    /// recorded run, each replay [`super::replay`]'s.
    pub fn replay(
        problem: &Problem,
        b: &ReplayBench,
        out_text: Out,
        progress: &dyn BenchProgress,
    ) -> Result<serde_json::Value> {
        let one = |dir: &std::path::Path, id: u64| Ok(super::replay(dir, id)?.verified);
        crate::bench::replay(problem, b, &one, out_text, progress)
    }
}

/// `gripopt moo-test`: the optimiser on standard problems.
pub mod moo {
    pub use crate::optim::{run_test, TestProblem, TestRun};
}

/// The sweep layer's types a sweep request and its results are made of.
pub mod sweeps {
    pub use crate::sweep::{Boundary, Row, Stage, SweepSpec};
}
