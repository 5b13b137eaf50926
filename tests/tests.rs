//! The one integration-test binary (one link step in CI instead of nine): one module per
//! area, sharing the test models and helpers of `common`.

// Index loops mirror the formulas of MODEL.md, as in the library.
#![allow(clippy::needless_range_loop)]

mod common;

mod architecture;
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
mod hostile33;
mod hostile34_checkpoint;
mod hostile34_cli;
mod hostile34_files;
mod hostile34_replay;
mod hostile34_robust;
mod kinematics;
mod nominal;
mod optimiser;
mod persist;
mod problem_files;
mod properties;
mod recorded;
mod recording;
mod recording_scene;
mod replay_scene;
mod reported_front;
mod robust;
mod robust_runs;
mod robustness;
mod robustness_cli;
mod robustness_edges;
mod robustness_folders;
mod s34_small;
mod s35_cli_export;
mod s35_cli_runs;
mod s35_csv;
mod s35_physics;
mod s36_auto_events;
mod s36_free_replay;
mod s36_mcap;
mod s36_params;
mod s37_fixes;
mod s37_offset_f2;
mod s37_typed;
mod scene_cli;
mod scenes;
mod seams;
mod solver_method;
mod statics;
mod stiffness_switch;
mod sweep;
mod verify;
mod verify_record;
