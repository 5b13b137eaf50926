//! MCAP recording: round trip, replay verification, corrupt files, crash/resume without
//! duplicates. Runs are written under target/mcap-check/ so that `make test` also checks
//! every file with the independent Python reader (tools/check_mcap.py).
use crate::common::check_dir;
use gripopt::record::read_design;
use gripopt::record::read_index;
use gripopt::record::{RecordOptions, Resolution};
use gripopt::replay;
use gripopt::run::{optimise, resume, RunSpec};
use std::path::Path;

fn spec(out: &Path, generations: u64) -> RunSpec {
    crate::common::bottle_spec(out, generations, 11, 2)
}

#[test]
fn every_design_is_recorded_and_replays_verified() {
    let d = check_dir("roundtrip");
    let before = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs();
    let s = optimise(&spec(&d, 4)).unwrap();
    let after = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_secs();
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("run.json")).unwrap()).unwrap();
    let epoch = run["recording"]["epoch_s"].as_u64().unwrap();
    assert!(before <= epoch && epoch <= after, "epoch {epoch} is the run's start ({before}..={after})");
    let idx = read_index(&d.join("recording")).unwrap();
    assert_eq!(idx.len(), 4);
    assert_eq!(idx.iter().map(|e| e.designs).sum::<u64>(), s.evaluations);
    let (mut with_traj, mut discarded, mut feasible) = (0, 0, 0);
    for id in 0..s.evaluations {
        let r = read_design(&d, id).unwrap();
        assert_eq!(r.record.id, id);
        assert_eq!(r.simulator_revision, gripopt::sim::SIMULATOR_REVISION, "design {id}: the shard's stamp");
        // the recorded record agrees with its trajectory (compact: a subset of the samples)
        let simulated = r.record.trajectory_samples;
        assert!(r.samples.len() as u64 <= simulated && (simulated == 0) == r.samples.is_empty(), "design {id}");
        // the window starts at the run's start time + id s, and /designs says so
        assert_eq!(r.record.window_start.sec, epoch + id, "design {id}");
        assert_eq!(r.record.window_start.nsec, 0);
        if !r.samples.is_empty() {
            with_traj += 1;
            assert!(r.samples.windows(2).all(|w| w[0].t <= w[1].t), "time runs forward");
            assert_eq!(r.samples[0].t, 0.0);
        }
        // never the optimiser's negative placeholder for max_offset (MODEL.md §6.7)
        match r.record.form_closed {
            Some(true) => {
                assert!(r.record.objectives.max_offset.is_some_and(|m| m >= 0.0), "design {id}")
            }
            Some(false) => assert!(r.record.objectives.max_offset.is_none(), "design {id}: {:?}", r.record),
            None => assert!(r.record.objectives.max_offset.is_none(), "design {id}"),
        }
        if r.record.feasible {
            feasible += 1;
        } else {
            discarded += 1;
            assert!(r.record.reason.as_ref().is_some_and(|s| !s.is_empty()));
        }
    }
    assert!(with_traj > 0 && feasible > 0 && discarded > 0, "{with_traj} {feasible} {discarded}");
    // replay: a feasible design, a stage-3 discard and an early discard all verify
    let pareto = std::fs::read_to_string(d.join("pareto.csv")).unwrap();
    let front_id: u64 =
        pareto.lines().filter(|l| !l.starts_with('#')).nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    let r = replay(&d, front_id).unwrap();
    assert!(r.across_revisions.is_none(), "the same revision: compared bit for bit");
    assert!(
        r.verified && r.max_difference == 0.0 && r.compared > 20,
        "{} {} {}",
        r.verified,
        r.max_difference,
        r.compared
    );
    for id in 0..s.evaluations {
        let rec = read_design(&d, id).unwrap().record;
        if rec.failed_stage.is_some() {
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
    let d = check_dir("corrupt");
    optimise(&spec(&d, 3)).unwrap();
    let shard = d.join("recording/gen-00002.mcap");
    let bytes = std::fs::read(&shard).unwrap();
    // keep the damaged copy out of the folder the Python checker reads
    let bad_dir = check_dir("corrupt-shards-not-checked").with_extension("bad");
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
    let (full, cut) = (check_dir("resume-full"), check_dir("resume-cut"));
    optimise(&spec(&full, 5)).unwrap();
    let s = spec(&cut, 5);
    assert!(crate::common::optimise_crashing_after(&s, 2).is_err());
    // a partly written next generation would be left as a temporary file: simulate one
    std::fs::write(cut.join("recording/gen-00003.mcap.tmp"), b"partial").unwrap();
    resume(&cut, None, false, Some(1)).unwrap();
    let idx = read_index(&cut.join("recording")).unwrap();
    let gens: Vec<u64> = idx.iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1, 2, 3, 4, 5]);
    assert!(!cut.join("recording/gen-00003.mcap.tmp").exists());
    for id in 0..60 {
        let a = read_design(&full, id).unwrap();
        let b = read_design(&cut, id).unwrap();
        assert_eq!(a.record.parameters, b.record.parameters, "design {id}");
        assert_eq!(a.record.reason, b.record.reason);
        assert_eq!(a.samples, b.samples, "design {id}: trajectories differ");
    }
    assert!(read_design(&cut, 60).is_err());
}

#[test]
fn recording_options_are_honoured() {
    let d = check_dir("decimated");
    let mut s = spec(&d, 4);
    s.record = RecordOptions { every: 10, scene_dt: 0.0, resolution: Resolution::Full, ..RecordOptions::default() };
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
    let d2 = check_dir("norecord");
    let mut s = spec(&d2, 2);
    s.record = RecordOptions::none();
    optimise(&s).unwrap();
    assert!(!d2.join("recording").exists());
}

/// A full-resolution recording of a run and the default (compact) one of the same run
/// (same seed, so the same designs): compact keeps every contact onset and separation,
/// every force peak and the final state exactly where they are in the full trajectory,
/// values to f32; full replays bitwise; the layout is in both run folders.
#[test]
fn compact_recording_keeps_contacts_peaks_and_the_final_state() {
    let (full, compact) = (check_dir("full-resolution"), check_dir("compact"));
    let mut s = spec(&full, 4);
    s.record = RecordOptions { resolution: Resolution::Full, ..RecordOptions::default() };
    let n = optimise(&s).unwrap().evaluations;
    optimise(&spec(&compact, 4)).unwrap();
    let (mut contacts, mut peaks, mut with_traj) = (0, 0, 0);
    for id in 0..n {
        let f = read_design(&full, id).unwrap();
        let c = read_design(&compact, id).unwrap();
        assert_eq!(f.resolution, Resolution::Full);
        assert_eq!(c.resolution, Resolution::Compact);
        assert_eq!(f.record.trajectory_samples, f.samples.len() as u64, "full keeps every sample");
        if f.samples.is_empty() {
            assert!(c.samples.is_empty());
            continue;
        }
        with_traj += 1;
        assert!(c.samples.len() < f.samples.len() || f.samples.len() < 10, "design {id}: compact is a subset");
        let find = |t: f64| {
            c.samples
                .iter()
                .find(|x| x.t.to_bits() == t.to_bits())
                .unwrap_or_else(|| panic!("design {id}: sample at t = {t} missing"))
        };
        let same = |a: &gripopt::sim::Sample, b: &gripopt::sim::Sample| {
            let r = |x: f64| x as f32 as f64;
            b.q == a.q.map(r)
                && b.normal == a.normal.map(r)
                && b.delta == a.delta.map(r)
                && b.hand_fy == r(a.hand_fy)
                && b.energy == r(a.energy)
        };
        let m = f.samples.len();
        for i in 0..m {
            let a = &f.samples[i];
            let onset = i > 0 && (0..2).any(|k| (f.samples[i - 1].delta[k] > 0.0) != (a.delta[k] > 0.0));
            let peak = i > 0
                && i + 1 < m
                && (0..2).any(|k| {
                    a.normal[k].abs() > f.samples[i - 1].normal[k].abs()
                        && a.normal[k].abs() >= f.samples[i + 1].normal[k].abs()
                });
            if onset || peak || i + 1 == m || i == 0 {
                assert!(same(a, find(a.t)), "design {id}: sample {i} (t = {}) not kept exactly", a.t);
                contacts += onset as usize;
                peaks += peak as usize;
            }
        }
        // no gap in time larger than the regular spacing
        assert!(c.samples.windows(2).all(|w| w[1].t - w[0].t
            <= gripopt::record::COMPACT_DT + f.samples.windows(2).map(|w| w[1].t - w[0].t).fold(0.0, f64::max)));
    }
    assert!(with_traj > 0 && contacts > 0 && peaks > 0, "{with_traj} {contacts} {peaks}");
    // both verify; the full one bitwise at f64, the compact one bitwise at f32
    let pareto = std::fs::read_to_string(full.join("pareto.csv")).unwrap();
    let id: u64 =
        pareto.lines().filter(|l| !l.starts_with('#')).nth(1).unwrap().split(',').next().unwrap().parse().unwrap();
    for d in [&full, &compact] {
        let r = replay(d, id).unwrap();
        assert!(r.verified && r.max_difference == 0.0, "{}: {} {}", d.display(), r.verified, r.max_difference);
        let layout: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join(gripopt::record::LAYOUT_FILE)).unwrap()).unwrap();
        assert_eq!(layout["configById"]["3D!oblique"]["followTf"], "world");
        assert_eq!(layout["configById"]["Plot!contact"]["xAxisPath"]["value"], "/grasp/series.t[:]");
        assert_eq!(layout["configById"]["RawMessages!designs"]["topicPath"], "/designs");
    }
}
