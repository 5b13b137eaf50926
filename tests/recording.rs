//! MCAP recording: round trip, replay verification, corrupt files, crash/resume without
//! duplicates. Runs are written under target/mcap-check/ so that `make test` also checks
//! every file with the independent Python reader (tools/check_mcap.py).
use gripopt::run::{optimise, resume, RunSpec};
use gripopt::record::{read_design, replay};
use gripopt::record::read_index;
use gripopt::record::RecordOptions;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let base = std::env::var_os("GRIPOPT_MCAP_CHECK_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mcap-check")));
    let d = base.join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn spec(out: &Path, generations: u64) -> RunSpec {
    RunSpec {
        problem_path: PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")),
        out: out.to_path_buf(),
        pop: 12,
        generations,
        seed: 11,
        threads: Some(2),
        progress: false,
        crash_after: None,
        record: RecordOptions::default(),
    }
}

#[test]
fn every_design_is_recorded_and_replays_verified() {
    let d = dir("roundtrip");
    let s = optimise(&spec(&d, 4)).unwrap();
    let idx = read_index(&d.join("recording")).unwrap();
    assert_eq!(idx.len(), 4);
    assert_eq!(idx.iter().map(|e| e.designs).sum::<u64>(), s.evaluations);
    let (mut with_traj, mut discarded, mut feasible) = (0, 0, 0);
    for id in 0..s.evaluations {
        let r = read_design(&d, id).unwrap();
        assert_eq!(r.record["id"].as_u64(), Some(id));
        // the recorded record agrees with its trajectory
        assert_eq!(r.record["trajectory_samples"].as_u64(), Some(r.samples.len() as u64));
        if !r.samples.is_empty() {
            with_traj += 1;
            assert!(r.samples.windows(2).all(|w| w[0].t <= w[1].t), "time runs forward");
            assert_eq!(r.samples[0].t, 0.0);
        }
        if r.record["feasible"].as_bool().unwrap() {
            feasible += 1;
        } else {
            discarded += 1;
            assert!(r.record["reason"].as_str().is_some_and(|s| !s.is_empty()));
        }
    }
    assert!(with_traj > 0 && feasible > 0 && discarded > 0, "{with_traj} {feasible} {discarded}");
    // replay: a feasible design, a stage-3 discard and an early discard all verify
    let pareto = std::fs::read_to_string(d.join("pareto.csv")).unwrap();
    let front_id: u64 = pareto.lines().filter(|l| !l.starts_with('#')).nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    let r = replay(&d, front_id).unwrap();
    assert!(r.verified && r.max_difference == 0.0 && r.compared > 100, "{} {} {}", r.verified, r.max_difference, r.compared);
    for id in 0..s.evaluations {
        let rec = read_design(&d, id).unwrap().record;
        if rec["failed_stage"].as_u64().is_some() {
            let r = replay(&d, id).unwrap();
            assert!(r.verified, "design {id}");
        }
    }
    // a design outside the run
    let e = read_design(&d, 10_000).unwrap_err().to_string();
    assert!(e.contains("not in") && e.contains("index.jsonl"), "{e}");
}

#[test]
fn corrupt_shards_give_clear_errors_and_the_rest_stays_readable() {
    let d = dir("corrupt");
    optimise(&spec(&d, 3)).unwrap();
    let shard = d.join("recording/gen-00002.mcap");
    let bytes = std::fs::read(&shard).unwrap();
    // keep the damaged copy out of the folder the Python checker reads
    let bad_dir = dir("corrupt-shards-not-checked").with_extension("bad");
    std::fs::create_dir_all(&bad_dir).unwrap();
    std::fs::write(&shard, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_design(&d, 14).unwrap_err().to_string();
    assert!(e.contains("gen-00002.mcap") && (e.contains("truncated") || e.contains("corrupt")), "{e}");
    // garbage in the middle (summary intact): either an error naming the file or intact data
    let mut g = bytes.clone();
    for b in g.iter_mut().skip(200).take(400) {
        *b ^= 0x5a;
    }
    std::fs::write(&shard, &g).unwrap();
    if let Err(e) = read_design(&d, 13) {
        assert!(e.to_string().contains("gen-00002.mcap"), "{e}");
    }
    // other shards are intact
    assert!(read_design(&d, 0).is_ok());
    assert!(read_design(&d, 30).is_ok());
    std::fs::write(&shard, &bytes).unwrap();
    let _ = std::fs::remove_dir_all(&bad_dir);
}

#[test]
fn crash_and_resume_records_each_design_once_and_identically() {
    let (full, cut) = (dir("resume-full"), dir("resume-cut"));
    optimise(&spec(&full, 5)).unwrap();
    let mut s = spec(&cut, 5);
    s.crash_after = Some(2);
    assert!(optimise(&s).is_err());
    // a partly written next generation would be left as a temporary file: simulate one
    std::fs::write(cut.join("recording/gen-00003.mcap.tmp"), b"partial").unwrap();
    resume(&cut, None, false, Some(1), false).unwrap();
    let idx = read_index(&cut.join("recording")).unwrap();
    let gens: Vec<u64> = idx.iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1, 2, 3, 4, 5]);
    assert!(!cut.join("recording/gen-00003.mcap.tmp").exists());
    for id in 0..60 {
        let a = read_design(&full, id).unwrap();
        let b = read_design(&cut, id).unwrap();
        assert_eq!(a.record["parameters"], b.record["parameters"], "design {id}");
        assert_eq!(a.record["reason"], b.record["reason"]);
        assert_eq!(a.samples, b.samples, "design {id}: trajectories differ");
    }
    assert!(read_design(&cut, 60).is_err());
}

#[test]
fn recording_options_are_honoured() {
    let d = dir("decimated");
    let mut s = spec(&d, 4);
    s.record = RecordOptions { every: 10, scene_dt: 0.0, ..RecordOptions::default() };
    let r = optimise(&s).unwrap();
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["recording"]["every"], 10);
    let mut any = false;
    for id in 0..r.evaluations {
        let rec = read_design(&d, id).unwrap();
        if rec.samples.len() > 1 {
            any = true;
            let dt_ok = rec.samples.len() < 400;
            assert!(dt_ok, "decimated trajectory has {} samples", rec.samples.len());
            assert!(replay(&d, id).unwrap().verified, "decimated replay of {id}");
        }
    }
    assert!(any);
    // no recording at all
    let d2 = dir("norecord");
    let mut s = spec(&d2, 2);
    s.record = RecordOptions::none();
    optimise(&s).unwrap();
    assert!(!d2.join("recording").exists());
}
