//! `gripopt replay RUN --design ID` of a single-object free-kind run records the design's
//! free scene to `RUN/free-ID.mcap` (docs/recording.md, "Replay"): checked with the mcap
//! crate and the Foxglove SDK's decoder against the run's own recording (the shards' log
//! times, the record's measured final displacement), never against the writer's numbers.

use crate::common::{check_dir, output_text, run_gripopt, scratch, tiny_run_in, BOTTLE_FILE};
use foxglove::messages::FrameTransforms;
use foxglove::Decode;
use std::path::{Path, PathBuf};

/// bottle-1l with `[scene] kind = "free"`, written into the scratch folder `name`.
fn free_problem(name: &str) -> PathBuf {
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let text = text.replacen("kind = \"centred\"", "kind = \"free\"", 1);
    assert!(text.contains("kind = \"free\""));
    let dir = scratch(name);
    let path = dir.join("bottle-free.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `replay RUN --design ID --json`: exit code and JSON.
fn replay_json(run: &Path, id: u64) -> (i32, serde_json::Value, String) {
    let o = run_gripopt(&["replay", run.to_str().unwrap(), "--design", &id.to_string(), "--json"]);
    let v = serde_json::from_slice(&o.stdout).unwrap_or(serde_json::Value::Null);
    (o.status.code().unwrap(), v, output_text(&o))
}

/// (first, last) log time of every message of the MCAP at `path`.
fn log_range(path: &Path) -> (u64, u64) {
    let buf = std::fs::read(path).unwrap();
    let ts: Vec<u64> = mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap().log_time).collect();
    (*ts.iter().min().unwrap(), *ts.iter().max().unwrap())
}

/// The `gripopt.verify` metadata of the MCAP at `path`.
fn verify_metadata(path: &Path) -> std::collections::BTreeMap<String, String> {
    let buf = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    let mi = summary.metadata_indexes.iter().find(|m| m.name == "gripopt.verify").unwrap();
    mcap::read::metadata(&buf, mi).unwrap().metadata
}

/// The horizontal displacement of the drawn object (`/tf` hand → object) from its first to
/// its last pose (m).
fn drawn_final_displacement(path: &Path) -> f64 {
    let buf = std::fs::read(path).unwrap();
    let mut xy = vec![];
    for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
        if m.channel.topic == "/tf" {
            let f = FrameTransforms::decode(&m.data[..]).unwrap();
            let o = f.transforms.iter().find(|t| t.child_frame_id == "object").unwrap();
            let v = o.translation.as_ref().unwrap();
            xy.push((m.log_time, v.x, v.y));
        }
    }
    xy.sort_by_key(|p| p.0);
    let (a, b) = (xy.first().unwrap(), xy.last().unwrap());
    (b.1 - a.1).hypot(b.2 - a.2)
}

/// Origin: session 36, replay of a free-kind run.
#[test]
fn free_kind_replay_records_the_free_scene_in_its_own_window() {
    let problem = free_problem("free-window");
    let run = tiny_run_in(check_dir("s36-free-replay"), &problem, 8, 1);
    let ids: Vec<u64> = (0..8).collect();
    let recs: Vec<_> = ids.iter().map(|id| gripopt::record::read_design(&run, *id).unwrap()).collect();
    // a design that reached the free scene (its record holds the measured final displacement)
    let reached =
        recs.iter().find(|r| r.record.free_scene.as_ref().is_some_and(|f| f.object_final_displacement.is_some()));
    let rec = reached.expect("seed 16, pop 8: some design reaches the free scene");
    let id = rec.record.id;
    let (code, v, text) = replay_json(&run, id);
    assert_eq!(code, 0, "{text}");
    let file = run.join(format!("free-{id}.mcap"));
    assert_eq!(v["free_recording"].as_str(), Some(file.to_str().unwrap()), "{text}");
    assert!(file.is_file());

    // its window: after every shard message, one second of its own
    let (lo, hi) = log_range(&file);
    for e in gripopt::record::read_index(&run.join("recording")).unwrap() {
        let (slo, shi) = log_range(&run.join("recording").join(&e.file));
        assert!(hi < slo || lo > shi, "free-{id}.mcap [{lo}, {hi}] overlaps {} [{slo}, {shi}]", e.file);
    }
    assert!(hi - lo < 1_000_000_000, "one window of one second");

    // metadata: which design, which scene, which run
    let m = verify_metadata(&file);
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    assert_eq!(m.get("free_design").map(String::as_str), Some(id.to_string().as_str()));
    assert_eq!(m.get("scene").map(String::as_str), Some("free:0"));
    assert_eq!(m.get("run_id").map(String::as_str), info["run_id"].as_str());

    // the drawn object at the end is where the recorded free scene left it
    let recorded = rec.record.free_scene.as_ref().unwrap().object_final_displacement.unwrap();
    let drawn = drawn_final_displacement(&file);
    assert!((drawn - recorded).abs() <= 1e-9 + 1e-6 * recorded.abs(), "drawn {drawn} m, recorded {recorded} m");

    // a second replay replaces it (a new file renamed into place, the same bytes)
    use std::os::unix::fs::MetadataExt;
    let (ino, bytes) = (std::fs::metadata(&file).unwrap().ino(), std::fs::read(&file).unwrap());
    let (code, _, text) = replay_json(&run, id);
    assert_eq!(code, 0, "{text}");
    assert_ne!(std::fs::metadata(&file).unwrap().ino(), ino, "replaced");
    assert_eq!(std::fs::read(&file).unwrap(), bytes, "deterministic");

    // a design discarded before the free scene: no file, and why
    let early = recs.iter().find(|r| r.record.failed_stage.is_some_and(|s| s < 3)).unwrap();
    let (code, v, text) = replay_json(&run, early.record.id);
    assert_eq!(code, 0, "{text}");
    assert!(v["free_not_recorded"].as_str().unwrap().contains("discarded before it"), "{text}");
    assert!(v.get("free_recording").is_none());
    assert!(!run.join(format!("free-{}.mcap", early.record.id)).exists());

    // the same design's file of another run (its run id) and a file that is no MCAP: refused, kept
    let other = tiny_run_in(check_dir("s36-free-replay-other"), &problem, 8, 1);
    assert_eq!(replay_json(&other, id).0, 0);
    for foreign in [std::fs::read(other.join(format!("free-{id}.mcap"))).unwrap(), b"not an mcap".to_vec()] {
        std::fs::write(&file, &foreign).unwrap();
        let (code, _, text) = replay_json(&run, id);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains(file.to_str().unwrap()) && text.contains("not a free-scene recording"), "{text}");
        assert_eq!(std::fs::read(&file).unwrap(), foreign, "kept");
    }
    std::fs::write(&file, &bytes).unwrap(); // the run folder as the replay left it, for check_mcap
}

/// Origin: session 36, replay of a free-kind run.
#[test]
fn centred_kind_replay_writes_no_free_file() {
    let run = tiny_run_in(check_dir("s36-free-replay-centred"), Path::new(BOTTLE_FILE), 8, 1);
    for id in 0..8 {
        let (code, v, text) = replay_json(&run, id);
        assert!(code == 0 || code == 3, "{text}");
        assert!(v.get("free_recording").is_none() && v.get("free_not_recorded").is_none(), "{text}");
        assert!(!run.join(format!("free-{id}.mcap")).exists());
    }
}

/// Origin: issue 44 class 7: `replay` of a free-kind run in a read-only folder failed with
/// exit 1 and no verdict, because free-ID.mcap could not be written. The free scene's
/// recording is a side effect: where it cannot be written the replay's verdict comes first,
/// with exit 0, and says why the free scene was not recorded (as when another process holds
/// the folder). The folder is made read-only, and (for a test run as root, whom permissions
/// do not stop) a folder stands at the file's temporary name (`.free-ID.mcap.tmp`), so the
/// write fails either way.
/// Origin: session 36, replay of a free-kind run.
#[test]
fn a_free_scene_that_cannot_be_written_leaves_the_verdict() {
    use std::os::unix::fs::PermissionsExt;
    let problem = free_problem("unwritable");
    let run = tiny_run_in(check_dir("s36-free-replay-readonly"), &problem, 8, 1);
    let reached = (0..8).find(|id| {
        gripopt::record::read_design(&run, *id)
            .is_ok_and(|r| r.record.free_scene.is_some_and(|f| f.object_final_displacement.is_some()))
    });
    let id = reached.expect("seed 16, pop 8: some design reaches the free scene");
    let file = run.join(format!("free-{id}.mcap"));
    let tmp = run.join(format!(".free-{id}.mcap.tmp"));
    std::fs::create_dir_all(&tmp).unwrap();
    let mode = std::fs::metadata(&run).unwrap().permissions().mode();
    std::fs::set_permissions(&run, std::fs::Permissions::from_mode(0o555)).unwrap();
    let (code, v, text) = replay_json(&run, id);
    let plain = run_gripopt(&["replay", run.to_str().unwrap(), "--design", &id.to_string()]);
    std::fs::set_permissions(&run, std::fs::Permissions::from_mode(mode)).unwrap();
    assert_eq!(code, 0, "{text}");
    assert_eq!(v["verified"], true, "{text}");
    let why = v["free_not_recorded"].as_str().unwrap_or_else(|| panic!("no reason: {text}"));
    assert!(why.starts_with("free scene not recorded: "), "{why}");
    assert!(v.get("free_recording").is_none() && !file.exists(), "{text}");
    let said = output_text(&plain);
    assert_eq!(plain.status.code(), Some(0), "{said}");
    let verdict = said.find("verified").unwrap_or_else(|| panic!("no verdict: {said}"));
    assert!(verdict < said.find("free scene not recorded").unwrap(), "the verdict first: {said}");
    std::fs::remove_dir(&tmp).unwrap();
}
