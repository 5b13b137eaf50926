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

/// Checkpoints written by the gripopt of session 36 (its options an untyped JSON value):
/// a run of bottle-1l (RADAU5, the method not stated) and one with `method = "trbdf2"`.
fn s36_checkpoint(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/checkpoint-s36")).join(name)
}

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

#[test]
fn an_s36_checkpoint_resumes() {
    for name in ["radau5", "trbdf2"] {
        let d = scratch_dir("s37-typed", &format!("resume-{name}"));
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

#[test]
fn a_checkpoint_with_an_unknown_option_is_refused_naming_it() {
    let d = scratch_dir("s37-typed", "unknown-option");
    copy_dir(&s36_checkpoint("radau5"), &d);
    let path = d.join("checkpoint.json");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replacen("\"options\":{", "\"options\":{\"extra\":1,", 1)).unwrap();
    let e = gripopt::run::Checkpoint::<gripopt::run::GripperInfo>::load_unverified(&path).unwrap_err().to_string();
    assert!(e.contains("extra") && e.contains("checkpoint.json"), "{e}");
}

/// Every metadata record (name, key → value) of the MCAP file `path`.
fn metadata_records(path: &Path) -> Vec<(String, std::collections::BTreeMap<String, String>)> {
    let buf = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    summary
        .metadata_indexes
        .iter()
        .map(|i| mcap::read::metadata(&buf, i).unwrap())
        .map(|m| (m.name, m.metadata))
        .collect()
}

#[test]
fn the_metadata_of_5d2a08e_shards_reads_into_run_metadata_and_writes_back_the_same_keys() {
    use gripopt::record::{RunMetadata, RUN_METADATA};
    let mut shards = 0;
    for run in ["centred", "free", "full"] {
        let rec = fixture(run).join("recording");
        for e in std::fs::read_dir(&rec).unwrap().flatten().filter(|e| e.path().extension() == Some("mcap".as_ref())) {
            for (name, map) in metadata_records(&e.path()) {
                assert_eq!(name, RUN_METADATA);
                let m = RunMetadata::from_map(&map).unwrap_or_else(|e| panic!("{run}: {e}"));
                assert!(m.epoch_s.is_some() && m.resolution.is_some() && m.first_id.flatten().is_some(), "{run}");
                // every key the type knows, each value as the old gripopt wrote it
                assert_eq!(m.to_map(), map, "{run}: {}", e.path().display());
                shards += 1;
            }
        }
    }
    assert!(shards >= 5, "the fixtures' shards were read ({shards})");
}

#[test]
fn a_missing_or_unreadable_metadata_key_is_named() {
    use gripopt::record::RunMetadata;
    use gripopt::Resolution;
    let map = |kv: &[(&str, &str)]| kv.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let m = RunMetadata::from_map(&map(&[("resolution", "full")])).unwrap();
    assert_eq!(m.resolution, Some(Resolution::Full));
    let e = m.require_epoch_s().unwrap_err();
    assert!(e.contains("`epoch_s`") && e.contains("missing"), "{e}");
    let e = RunMetadata::from_map(&map(&[("epoch_s", "12")])).unwrap().require_resolution().unwrap_err();
    assert!(e.contains("`resolution`") && e.contains("missing"), "{e}");
    let e = RunMetadata::from_map(&map(&[("resolution", "coarse")])).unwrap_err();
    assert!(e.contains("`resolution`") && e.contains("coarse"), "{e}");
    let e = RunMetadata::from_map(&map(&[("first_id", "-3")])).unwrap_err();
    assert!(e.contains("`first_id`") && e.contains("-3"), "{e}");
    let e = RunMetadata::from_map(&map(&[("scenario_object", "can"), ("scenario_index", "2")])).unwrap_err();
    assert!(e.contains("`object_grasp_height`") && e.contains("missing"), "{e}");
    // the resolution's words, both ways
    for r in [Resolution::Full, Resolution::Compact] {
        assert_eq!(r.to_string().parse::<Resolution>(), Ok(r));
        assert_eq!(serde_json::to_value(r).unwrap(), r.to_string().as_str(), "the word run.json uses");
    }
}

#[test]
fn a_shard_without_its_epoch_is_refused_naming_the_key() {
    // a 5d2a08e shard whose metadata record loses `epoch_s`: replay names the key
    let d = scratch_dir("s37-typed", "no-epoch");
    copy_dir(&fixture("centred"), &d);
    let shard = d.join("recording/gen-00001.mcap");
    let bytes = std::fs::read(&shard).unwrap();
    // rename the key in place (same length, so the file stays a valid MCAP)
    let at = bytes.windows(7).position(|w| w == b"epoch_s").unwrap();
    let mut edited = bytes.clone();
    edited[at..at + 7].copy_from_slice(b"epoch_t");
    std::fs::write(&shard, edited).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("`epoch_s`") && e.contains("gen-00001.mcap"), "{e}");
}
