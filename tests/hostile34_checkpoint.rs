//! Hostile pass 34 (docs/cli.md "Hostile pass 34"): a checkpoint edited by hand and resumed
//! with `--force` (which passes its content checksum) was refused with a message that named
//! no field ("settings differ from run.json", `run id ""`). Each refusal now names the file,
//! the field and both values, with the same exit code, and changes nothing in the folder.
//! Each test fails without its fix.

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const BASE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-checkpoint");

/// A finished run of `problem` (population 8, 2 generations, seed 1) in a fresh folder `name`.
fn run_folder(name: &str, problem: &Path) -> PathBuf {
    let dir = Path::new(BASE).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(BASE).unwrap();
    let spec = gripopt::run::RunSpec {
        problem_path: problem.to_path_buf(),
        out: dir.clone(),
        pop: 8,
        generations: 2,
        seed: 1,
        threads: Some(1),
        record: gripopt::record::RecordOptions::default(),
    };
    gripopt::run::optimise(&spec).unwrap();
    dir
}

/// Every file under `dir` with its bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            files.extend(snapshot(&p));
        } else {
            files.insert(p.clone(), std::fs::read(&p).unwrap());
        }
    }
    files
}

/// The error of `resume --force` on a run of bottle-1l in folder `name` after `edit` of its
/// checkpoint.json, asserting exit 2 and that the folder (the edited checkpoint included) is
/// left as it was.
fn forced_resume_error(name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    forced_resume_error_of(name, Path::new(BOTTLE_FILE), edit)
}

/// [`forced_resume_error`] on a run of `problem`.
fn forced_resume_error_of(name: &str, problem: &Path, edit: impl FnOnce(&mut serde_json::Value)) -> String {
    let dir = run_folder(name, problem);
    let cp = dir.join("checkpoint.json");
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(&cp).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&cp, serde_json::to_vec(&v).unwrap()).unwrap();
    let before = snapshot(&dir);
    let o = run_gripopt(&["resume", dir.to_str().unwrap(), "--force", "--generations", "3"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(before == snapshot(&dir), "a refused resume changed the folder");
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(stderr.contains(&format!("{}: ", cp.display())), "names the checkpoint: {stderr}");
    stderr
}

/// `options.method` edited: was "settings differ from run.json (the run folder was
/// modified)", which names no field (and run.json's settings hold no method). (bottle-1l.toml
/// names no method: the run's is the default, auto, since session 38.)
#[test]
fn an_edited_method_is_named_with_both_values() {
    let e = forced_resume_error("method", |v| v["options"]["method"] = "radau5".into());
    assert!(e.contains(r#"options.method "radau5" differs from the run's "auto" ("#), "{e}");
    assert!(e.contains("bottle-1l.toml"), "names the problem file the run's method comes from: {e}");
}

/// `options.method` removed from a run whose problem file says `method = "auto"`: named as
/// missing, with the file's method.
#[test]
fn a_removed_method_is_named_as_missing() {
    std::fs::create_dir_all(BASE).unwrap();
    let file = Path::new(BASE).join("auto.toml");
    let text =
        std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("\n[solver]\n", "\n[solver]\nmethod = \"auto\"\n", 1);
    std::fs::write(&file, text).unwrap();
    let e = forced_resume_error_of("method-removed", &file, |v| {
        assert_eq!(v["options"]["method"], "auto", "the run's options state its method");
        v["options"].as_object_mut().unwrap().remove("method");
    });
    assert!(e.contains(&format!(r#"options.method is missing (the run's is "auto", {})"#, file.display())), "{e}");
}

/// `options.rtol` edited or `options.atol` removed: each named, with the problem file's value.
#[test]
fn edited_tolerances_are_named_with_both_values() {
    let e = forced_resume_error("rtol", |v| v["options"]["rtol"] = 1e-5.into());
    assert!(e.contains("options.rtol 0.00001 differs from the run's 1e-6 ("), "{e}");
    let e = forced_resume_error("atol", |v| {
        v["options"].as_object_mut().unwrap().remove("atol");
    });
    assert!(e.contains("options.atol is missing (the run's is 1e-9, "), "{e}");
}

/// An algorithm setting or a recording option edited: named, with run.json's value.
#[test]
fn edited_settings_and_recording_options_name_run_json() {
    let e = forced_resume_error("p-cross", |v| v["settings"]["operators"]["p_cross"] = 0.5.into());
    assert!(e.contains("settings.operators.p_cross 0.5 differs from the run's 0.9 (run.json)"), "{e}");
    let e = forced_resume_error("every", |v| v["options"]["recording"]["every"] = 2.into());
    assert!(e.contains("options.recording.every 2 differs from the run's 1 (run.json)"), "{e}");
}

/// `run_id` removed: was `written by another run (run id "")`.
#[test]
fn a_missing_run_id_is_named_as_missing() {
    let e = forced_resume_error("run-id", |v| {
        v.as_object_mut().unwrap().remove("run_id");
    });
    assert!(e.contains("field `run_id` is missing or empty (run.json's `run_id` is "), "{e}");
    assert!(!e.contains("written by another run"), "{e}");
}
