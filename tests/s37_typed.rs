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

fn verify_row(observed: bool) -> gripopt::run::VerifyRow {
    use gripopt::sim::FreeEnd;
    gripopt::run::VerifyRow {
        id: 7,
        design: crate::common::nominal(),
        impact_ratio: Some(0.5),
        e_trans_rot: Some((2e-3, 0.0)),
        force_margin: f64::INFINITY,
        stable: true,
        predicted_moves: false,
        max_displacement: 1e-4,
        max_tilt_deg: 0.25,
        peak_e: (1e-3, 2e-4),
        moved: observed.then_some(false),
        toppled: observed.then_some(false),
        escaped: observed.then_some(false),
        rim_contact: false,
        end: if observed { FreeEnd::Observed } else { FreeEnd::StepBudget },
        t_end: 0.1,
    }
}

#[test]
fn verify_csv_columns_are_the_column_table() {
    use gripopt::run::{verify_csv, VERIFY_COLUMNS};
    let csv = verify_csv(&[verify_row(true), verify_row(false)], 0.0);
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let names: Vec<&str> = VERIFY_COLUMNS.iter().map(|c| c.0).collect();
    assert_eq!(header, names, "the units table lists verify.csv's columns in order");
    let cell = |line: &str, col: &str| {
        let k = names.iter().position(|n| *n == col).unwrap();
        line.split(',').nth(k).unwrap().to_string()
    };
    let (seen, unseen) = (lines.next().unwrap(), lines.next().unwrap());
    assert_eq!(cell(seen, "free_end"), "t_obs");
    assert_eq!(cell(unseen, "free_end"), "aborted: step budget exhausted", "the enum's words");
    assert_eq!(cell(seen, "force_margin"), "inf", "the CSV writes every number");
    // E_rot = 0: the rotational ratio is infinite, the translational 0.5
    assert_eq!((cell(seen, "peak_e_trans_ratio").as_str(), cell(seen, "peak_e_rot_ratio").as_str()), ("0.5", "inf"));
    for col in ["moved", "agrees", "peak_e_trans_ratio"] {
        assert_eq!(cell(unseen, col), "", "{col}: not observed, an empty cell");
    }
}

#[test]
fn a_verify_message_leaves_out_what_was_not_computed_and_its_schema_names_every_field() {
    use gripopt::record::{verify_parameters, verify_schema, VerifyRecord, VerifyScenario, WindowStart};
    let rec = |row: &gripopt::run::VerifyRow, scenario: Option<VerifyScenario>| VerifyRecord {
        window: 1,
        window_start: WindowStart { sec: 5, nsec: 0 },
        window_start_s: 1.0,
        epoch_s: 4,
        id: row.id,
        parameters: verify_parameters(&row.design),
        x_off: 0.0,
        measure: row.measure(),
        t_end: row.t_end,
        poses: 3,
        scenario,
    };
    let json = |r: &VerifyRecord| -> serde_json::Map<String, serde_json::Value> {
        let bytes = r.to_json();
        let text = String::from_utf8(bytes).unwrap();
        let keys: Vec<String> = serde_json::from_str::<serde_json::Map<_, _>>(&text).unwrap().keys().cloned().collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted, "keys written sorted");
        serde_json::from_str(&text).unwrap()
    };
    let seen = json(&rec(&verify_row(true), None));
    assert!(!seen.contains_key("force_margin"), "not finite: left out");
    assert!(!seen.contains_key("peak_e_rot_ratio"), "not finite: left out");
    assert_eq!(seen["peak_e_trans_ratio"], 0.5);
    assert_eq!(seen["free_end"], "t_obs");
    assert!(!seen.contains_key("scenario_object"));
    let s = VerifyScenario { scenario_object: "can".into(), scenario_index: 2, height_offset: -0.004 };
    let unseen = json(&rec(&verify_row(false), Some(s)));
    for k in ["moved", "toppled", "escaped", "agrees", "peak_e_trans_ratio"] {
        assert!(!unseen.contains_key(k), "{k}: not observed, left out");
    }
    assert_eq!((unseen["scenario_object"].as_str(), unseen["scenario_index"].as_u64()), (Some("can"), Some(2)));
    // the schema names every field a message can have, and requires those every one has
    let schema = verify_schema();
    let props = schema["properties"].as_object().unwrap();
    for k in seen.keys().chain(unseen.keys()) {
        assert!(props.contains_key(k), "{k} is in the schema");
    }
    for k in schema["required"].as_array().unwrap() {
        let k = k.as_str().unwrap();
        assert!(seen.contains_key(k) && unseen.contains_key(k), "required {k} is in every message");
    }
}
