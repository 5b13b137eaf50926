//! Issue 21, session 37: what gripopt reads back of its own files (run.json, checkpoints,
//! the MCAP `gripopt.run` metadata) is read into types, and files of older versions still
//! load.

use crate::common::{copy_dir, scratch_dir};
use gripopt::run::{RunFolder, RunHeader};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/recorded-5d2a08e")).join(name)
}

fn write_run_json(dir: &Path, text: &str) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("run.json"), text).unwrap();
}

#[test]
fn run_header_reads_a_5d2a08e_run_json() {
    // written by 5d2a08e: no run_id, the recording's epoch set
    let h = RunHeader::load(&fixture("full")).unwrap();
    assert_eq!(h.run_id(), "", "a run of a gripopt before issue 24 has no run id");
    assert_eq!(h.problem_name.as_deref(), Some("bottle-1l"));
    assert_eq!(h.evaluations, Some(4));
    assert_eq!(h.epoch_s(), 1_795_494_738);
    // and the strict record reads it too
    gripopt::RunInfo::load(&fixture("full")).unwrap();
}

#[test]
fn run_header_tolerates_missing_fields_and_names_a_mistyped_one() {
    let d = scratch_dir("s37-typed", "header");
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

#[test]
fn a_pinned_folder_of_an_old_run_stays_readable_and_notices_a_swap() {
    let d = scratch_dir("s37-typed", "pinned");
    copy_dir(&fixture("centred"), &d);
    let f = RunFolder::open_pinned(&d).unwrap();
    f.check_run().expect("an old run (no run id) pinned as itself");
    let text = std::fs::read_to_string(d.join("run.json")).unwrap();
    let swapped = text.replacen('{', "{\n  \"run_id\": \"0123456789abcdef\",", 1);
    std::fs::write(d.join("run.json"), swapped).unwrap();
    let e = f.check_run().unwrap_err().to_string();
    assert!(e.contains("0123456789abcdef"), "names the run now in the folder: {e}");
}

#[test]
fn replay_of_a_run_without_recording_says_why_from_run_json() {
    let d = scratch_dir("s37-typed", "unrecorded");
    copy_dir(&fixture("centred"), &d);
    std::fs::remove_dir_all(d.join("recording")).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("says the run recorded"), "recording on in run.json: {e}");
    let text = std::fs::read_to_string(d.join("run.json")).unwrap();
    std::fs::write(d.join("run.json"), text.replace("\"enabled\": true", "\"enabled\": false")).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("the run was not recorded"), "recording off in run.json: {e}");
    std::fs::write(d.join("run.json"), "{}").unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("does not say whether"), "{e}");
}
