//! Why a resumed checkpoint is not the run's: each setting or option that differs from
//! run.json and the problem file, named with both values and where the run's comes from.

use super::checkpoint::{field_differences, settings_hash, sha256_hex, Checkpoint, RunOptions};
use super::gripper::GripperInfo;
use super::info::{RunInfo, RUN_FILE};
use crate::optim::Nsga2Settings;
use crate::params::Problem;
use std::path::{Path, PathBuf};

/// The problem file a run started with, when it is still there (else the run uses its copy).
pub(super) fn original_problem(info: &RunInfo) -> Option<PathBuf> {
    info.problem_path.is_absolute().then(|| info.problem_path.clone()).filter(|p| p.exists())
}

/// Why a checkpoint's `settings` or `options` are not the run's: each field that differs,
/// with the checkpoint's value and the run's (run.json's settings and recording, the
/// problem file's `[solver]` table), or, when none does, its `settings_hash`.
pub(super) fn settings_differences(cp: &Checkpoint<GripperInfo>, info: &RunInfo, dir: &Path) -> Vec<String> {
    let value = |s: &Nsga2Settings| serde_json::to_value(s).unwrap_or_default();
    let mut found = field_differences("settings", &value(&cp.settings), &value(&info.settings), &|_| RUN_FILE.into());
    let problem_path = original_problem(info).unwrap_or_else(|| dir.join("problem.toml"));
    // a checkpoint naming no method ran RADAU5 (a problem without `solver.method` of before
    // session 38); one naming a method is compared with the file's (or the default)
    let legacy = |p: Problem| if cp.options.method.is_none() { p.with_run_method(None) } else { p };
    if let Ok(problem) = Problem::load(&problem_path).map(legacy) {
        let changed = sha256_hex(problem.source_text.as_bytes()) != cp.problem_hash;
        let file = format!("{}{}", problem_path.display(), if changed { ", changed since the checkpoint" } else { "" });
        let source = |f: &str| match f {
            f if f.starts_with("options.recording") => RUN_FILE.to_string(),
            "options.pipeline" => "this gripopt".to_string(),
            _ => file.clone(),
        };
        // the algorithm is the run's own (its first checkpoint's), not the problem file's
        let (survival, variation) = (cp.options.survival, cp.options.variation);
        let expected = RunOptions { survival, variation, ..RunOptions::of(&problem.solver, &info.recording) };
        // the run's options leave out the default method (RADAU5): name it beside a
        // checkpoint's `method`
        let mut named = expected.clone();
        if cp.options.method.is_some() {
            named.method.get_or_insert(problem.solver.method);
        }
        let ours = cp.options.to_value();
        let mut options = field_differences("options", &ours, &named.to_value(), &source);
        if options.is_empty() {
            options = field_differences("options", &ours, &expected.to_value(), &source);
        }
        found.extend(options);
    }
    if found.is_empty() {
        let hash = settings_hash(&cp.settings, &cp.options);
        found.push(format!(
            "field `settings_hash` {:?} is not the hash of its fields `settings` and `options` ({:?})",
            cp.settings_hash, hash
        ));
    }
    found
}
