//! The one integration-test binary (one link step in CI instead of nine): one module per
//! area, sharing the test models and helpers of `common`.

// Index loops mirror the formulas of MODEL.md, as in the library.
#![allow(clippy::needless_range_loop)]

mod common;

mod architecture;
mod bench;
mod certification;
mod cli_exit;
mod cli_outputs;
mod constraints;
mod dynamics;
mod event_values;
mod export;
mod export_object;
mod folder_trust;
mod force_model;
mod free_jacobian;
mod free_stage;
mod kinematics;
mod nominal;
mod optimiser;
mod persist;
mod problem_files;
mod properties;
mod recording;
mod recording_metadata;
mod recording_scene;
mod replay;
mod replay_free;
mod replay_recorded;
mod reported_front;
mod robust;
mod robust_runs;
mod robust_verdicts;
mod robustness;
mod robustness_cli;
mod robustness_edges;
mod robustness_folders;
mod run_folder_files;
mod run_state_files;
mod scene_cli;
mod scenes;
mod seams;
mod simulate;
mod solver_method;
mod statics;
mod stiffness_switch;
mod sweep;
mod verify;
mod verify_record;
mod verify_robust;
