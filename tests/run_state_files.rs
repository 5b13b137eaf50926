//! A run folder's state files (run.json, checkpoint.json): read back into types, files of
//! older versions (5d2a08e, session 36) still load and resume, and a checkpoint edited by hand
//! and resumed with `--force` is refused naming the file, the field and both values, with the
//! folder left as it was.

use crate::common::{copy_dir, output_text, recorded_fixture, run_gripopt, scratch, BOTTLE_FILE};
use gripopt::run::{RunFolder, RunHeader};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn write_run_json(dir: &Path, text: &str) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("run.json"), text).unwrap();
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn run_header_reads_a_5d2a08e_run_json() {
    // written by 5d2a08e: no run_id, the recording's epoch set
    let h = RunHeader::load(&recorded_fixture("full")).unwrap();
    assert_eq!(h.run_id(), "", "a run of a gripopt before issue 24 has no run id");
    assert_eq!(h.problem_name.as_deref(), Some("bottle-1l"));
    assert_eq!(h.evaluations, Some(4));
    assert_eq!(h.epoch_s(), 1_795_494_738);
    // and the strict record reads it too
    gripopt::RunInfo::load(&recorded_fixture("full")).unwrap();
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn run_header_tolerates_missing_fields_and_names_a_mistyped_one() {
    let d = scratch("header");
    write_run_json(&d, "{}");
    let h = RunHeader::load(&d).unwrap();
    assert_eq!((h.run_id(), h.epoch_s(), h.evaluations), ("", 0, None));
    write_run_json(&d, r#"{"run_id": null, "recording": null, "evaluations": null, "extra": [1]}"#);
    let h = RunHeader::load(&d).unwrap();
    assert_eq!((h.run_id(), h.epoch_s(), h.evaluations), ("", 0, None));
    write_run_json(&d, r#"{"recording": {"epoch_s": 1.5}}"#);
    let e = RunHeader::load(&d).unwrap_err().to_string();
    assert!(e.contains("recording.epoch_s") && e.contains("run.json"), "{e}");
    write_run_json(&d, r#"{"evaluations": "many"}"#);
    let e = RunHeader::load(&d).unwrap_err().to_string();
    assert!(e.contains("`evaluations`") && e.contains("run.json"), "{e}");
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn a_pinned_folder_of_an_old_run_stays_readable_and_notices_a_swap() {
    let d = scratch("pinned");
    copy_dir(&recorded_fixture("centred"), &d);
    let f = RunFolder::open_pinned(&d).unwrap();
    f.check_run().expect("an old run (no run id) pinned as itself");
    let text = std::fs::read_to_string(d.join("run.json")).unwrap();
    let swapped = text.replacen('{', "{\n  \"run_id\": \"0123456789abcdef\",", 1);
    std::fs::write(d.join("run.json"), swapped).unwrap();
    let e = f.check_run().unwrap_err().to_string();
    assert!(e.contains("0123456789abcdef"), "names the run now in the folder: {e}");
}

/// Checkpoints written by the gripopt of session 36 (its options an untyped JSON value):
/// a run of bottle-1l (RADAU5, the method not stated) and one with `method = "trbdf2"`.
fn s36_checkpoint(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/checkpoint-s36")).join(name)
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn an_s36_checkpoint_reads_into_typed_options_and_writes_back_its_own_bytes() {
    use gripopt::run::{settings_hash, Checkpoint, GripperInfo, PIPELINE};
    for (name, method) in [("radau5", None), ("trbdf2", Some(gripopt::sim::Method::TrBdf2))] {
        let path = s36_checkpoint(name).join("checkpoint.json");
        let cp = Checkpoint::<GripperInfo>::load(&path).unwrap();
        assert_eq!(cp.options.pipeline.as_deref(), Some(PIPELINE), "{name}");
        assert_eq!(cp.options.method, method, "{name}: `method` only where not the default");
        let o = &cp.options;
        assert_eq!((o.rtol, o.atol, o.max_steps), (Some(1e-6), Some(1e-9), Some(200_000)), "{name}");
        assert!(!o.recording.unwrap().enabled, "{name}: run with --record none");
        // the hash over the typed options is the one the old gripopt wrote over its JSON value
        assert_eq!(cp.settings_hash, settings_hash(&cp.settings, &cp.options), "{name}");
        let bytes = std::fs::read(&path).unwrap();
        assert!(cp.to_bytes(&path).unwrap() == bytes, "{name}: the checkpoint written back is not the file's bytes");
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn an_s36_checkpoint_resumes() {
    for name in ["radau5", "trbdf2"] {
        let d = scratch(&format!("resume-{name}"));
        copy_dir(&s36_checkpoint(name), &d);
        let s = gripopt::run::resume(&d, Some(2), false, Some(1)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.generations, 2, "{name}");
        let cp = gripopt::run::Checkpoint::<gripopt::run::GripperInfo>::load(&d.join("checkpoint.json")).unwrap();
        let old =
            gripopt::run::Checkpoint::<gripopt::run::GripperInfo>::load(&s36_checkpoint(name).join("checkpoint.json"))
                .unwrap();
        assert_eq!(cp.options, old.options, "{name}: the resumed run states the options it started with");
        assert_eq!(cp.settings_hash, old.settings_hash, "{name}");
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn a_checkpoint_with_an_unknown_option_is_refused_naming_it() {
    let d = scratch("unknown-option");
    copy_dir(&s36_checkpoint("radau5"), &d);
    let path = d.join("checkpoint.json");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replacen("\"options\":{", "\"options\":{\"extra\":1,", 1)).unwrap();
    let e = gripopt::run::Checkpoint::<gripopt::run::GripperInfo>::load_unverified(&path).unwrap_err().to_string();
    assert!(e.contains("extra") && e.contains("checkpoint.json"), "{e}");
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn discard_causes_read_and_write_their_words() {
    use gripopt::run::Discards;
    use gripopt::Cause;
    // as run.json states them: a cause's word, or `unknown` for a discard without one
    let text = r#"{"evaluated":5,"causes":[{"stage":1,"cause":"no_closed_pose","count":3,"closest":2,"violation":0.5,"reason":"r","detail":null},{"stage":3,"cause":"unknown","count":1,"closest":4,"violation":null,"reason":"","detail":"d"}]}"#;
    let d: Discards = serde_json::from_str(text).unwrap();
    assert_eq!(d.causes[0].cause, Some(Cause::NoClosedPose));
    assert_eq!(d.causes[1].cause, None);
    assert_eq!(serde_json::to_string(&d).unwrap(), text, "written back word for word");
    let bad = text.replace("no_closed_pose", "no_such_cause");
    let e = serde_json::from_str::<Discards>(&bad).unwrap_err().to_string();
    assert!(e.contains("no_such_cause"), "{e}");
}

/// A finished run of `problem` (population 8, 2 generations, seed 1) in a fresh folder `name`.
fn edited_run_folder(name: &str, problem: &Path) -> PathBuf {
    let dir = scratch(name).join("run");
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
    let dir = edited_run_folder(name, problem);
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
/// Origin: hostile pass of session 34, a checkpoint edited by hand and resumed with --force.
#[test]
fn an_edited_method_is_named_with_both_values() {
    let e = forced_resume_error("method", |v| v["options"]["method"] = "radau5".into());
    assert!(e.contains(r#"options.method "radau5" differs from the run's "auto" ("#), "{e}");
    assert!(e.contains("bottle-1l.toml"), "names the problem file the run's method comes from: {e}");
}

/// `options.method` removed from a run whose problem file says `method = "auto"`: named as
/// missing, with the file's method.
/// Origin: hostile pass of session 34, a checkpoint edited by hand and resumed with --force.
#[test]
fn a_removed_method_is_named_as_missing() {
    let file = scratch("auto-problem").join("auto.toml");
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
/// Origin: hostile pass of session 34, a checkpoint edited by hand and resumed with --force.
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
/// Origin: hostile pass of session 34, a checkpoint edited by hand and resumed with --force.
#[test]
fn edited_settings_and_recording_options_name_run_json() {
    let e = forced_resume_error("p-cross", |v| v["settings"]["operators"]["p_cross"] = 0.5.into());
    assert!(e.contains("settings.operators.p_cross 0.5 differs from the run's 0.9 (run.json)"), "{e}");
    let e = forced_resume_error("every", |v| v["options"]["recording"]["every"] = 2.into());
    assert!(e.contains("options.recording.every 2 differs from the run's 1 (run.json)"), "{e}");
}

/// `run_id` removed: was `written by another run (run id "")`.
/// Origin: hostile pass of session 34, a checkpoint edited by hand and resumed with --force.
#[test]
fn a_missing_run_id_is_named_as_missing() {
    let e = forced_resume_error("run-id", |v| {
        v.as_object_mut().unwrap().remove("run_id");
    });
    assert!(e.contains("field `run_id` is missing or empty (run.json's `run_id` is "), "{e}");
    assert!(!e.contains("written by another run"), "{e}");
}
