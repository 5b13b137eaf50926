//! The one integration-test binary (one link step in CI instead of nine): one module per
//! area, sharing the test models and helpers of `common`.

mod common;

mod architecture;
mod constraints;
mod dynamics;
mod force_model;
mod free_jacobian;
mod free_stage;
mod replay_scene;
mod kinematics;
mod nominal;
mod optimiser;
mod persist;
mod problem_files;
mod properties;
mod scenes;
mod scene_cli;
mod recording;
mod statics;
mod sweep;
mod verify;
mod verify_record;
mod robustness;
