//! Recordings written by an older gripopt (tests/fixtures/recorded-5d2a08e: run folders of
//! the 5d2a08e binary, each its problem, run.json, CSVs and MCAP shards) are read and
//! verified by this one: every design replays (the `/designs` record read back typed, the
//! re-evaluation agreeing with it). Issue 23 changed the simulator's arithmetic (block
//! elimination, cheaper right-hand side) within its integration tolerance, so a design that
//! reaches stage 3 no longer replays bit for bit (its steps differ): it must then agree in
//! its verdict (feasibility, failing stage, reason) and in its objectives, violation and the
//! end time of a full-resolution trajectory within [`ACROSS_SIMULATORS`]. Designs discarded
//! before stage 3 still verify exactly; that the sink changes nothing is tests/seams.rs's.

use crate::common::{output_text, run_gripopt};
use gripopt::record::{read_index, AcrossRevisions, Resolution};
use gripopt::sim::SIMULATOR_REVISION;
use gripopt::RunFolder;
use std::path::{Path, PathBuf};

/// A copy of fixture `name` under target/ for the test `test` (replay reads; the copy keeps
/// the fixture clean; one folder per test, as the tests run at the same time).
fn copy(test: &str, name: &str) -> PathBuf {
    let from = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/recorded-5d2a08e")).join(name);
    let to = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/recorded-5d2a08e")).join(test).join(name);
    let _ = std::fs::remove_dir_all(&to);
    std::fs::create_dir_all(to.join("recording")).unwrap();
    for dir in ["", "recording"] {
        for e in std::fs::read_dir(from.join(dir)).unwrap().flatten().filter(|e| e.path().is_file()) {
            std::fs::copy(e.path(), to.join(dir).join(e.file_name())).unwrap();
        }
    }
    to
}

/// Relative agreement of a stage-3 design's values with 5d2a08e's: t_stab moved by at most
/// 1.8e-4 over the 40 designs of the work-precision ensemble (docs/benchmarks.md, issue 23).
const ACROSS_SIMULATORS: f64 = 1e-3;

/// `a` and `b` both absent, or within [`ACROSS_SIMULATORS`] relative.
fn close(a: Option<f64>, b: Option<f64>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => (a - b).abs() <= ACROSS_SIMULATORS * a.abs().max(b.abs()),
        (a, b) => a.is_none() && b.is_none(),
    }
}

/// A design whose exact replay failed because the simulator changed (issue 23): the same
/// verdict, objectives, violation and (full resolution) end time within tolerance.
fn agrees_across_simulators(r: &gripopt::Replay) -> Result<(), String> {
    let (rec, fresh) = (&r.recorded.record, &r.fresh);
    if rec.failed_stage.is_some_and(|s| s < 3) {
        return Err("discarded before stage 3: must replay exactly".into());
    }
    if (rec.feasible, rec.failed_stage, &rec.reason)
        != (fresh.verdict.feasible, fresh.verdict.failed_stage, &fresh.verdict.reason)
    {
        return Err("verdict differs".into());
    }
    let o = fresh.objectives();
    let r_o = &rec.objectives;
    let pairs = [
        ("max_offset", r_o.max_offset.filter(|m| *m >= 0.0), o[0].filter(|m| *m >= 0.0)),
        ("alpha", r_o.alpha, o[1]),
        ("mean_force", r_o.mean_force, o[2]),
        ("t_stab", r_o.t_stab, o[3]),
        ("violation", rec.violation, fresh.verdict.violation),
    ];
    for (what, a, b) in pairs {
        if !close(a, b) {
            return Err(format!("{what}: recorded {a:?}, now {b:?}"));
        }
    }
    if r.recorded.resolution == gripopt::record::Resolution::Full && !r.recorded.samples.is_empty() {
        let t_rec = r.recorded.samples.last().map(|s| s.t);
        if !close(t_rec, fresh.grasp.t_end) {
            return Err(format!("trajectory end: recorded {t_rec:?}, now {:?}", fresh.grasp.t_end));
        }
    }
    Ok(())
}

#[test]
fn designs_recorded_by_5d2a08e_replay_and_verify() {
    let mut full = 0;
    for name in ["centred", "free", "full"] {
        let dir = copy("replay_and_verify", name);
        let run = RunFolder::open(&dir).unwrap();
        let ids: Vec<u64> =
            read_index(&dir.join("recording")).unwrap().iter().flat_map(|e| e.first_id..=e.last_id).collect();
        assert!(ids.len() >= 4, "{name}");
        let mut with_trajectory = 0;
        for id in ids {
            let r = run.replay(id).unwrap_or_else(|e| panic!("{name} design {id}: {e}"));
            assert!(r.compared + r.values_compared > 0, "{name} design {id}: {r:?}");
            if !r.verified {
                agrees_across_simulators(&r).unwrap_or_else(|e| panic!("{name} design {id}: {e}: {r:?}"));
                // and replay itself says so: recorded by revision 1 (no stamp), agreeing
                let a = r.across_revisions.as_ref().unwrap_or_else(|| panic!("{name} design {id}: {r:?}"));
                assert!(a.agrees() && a.recorded == 1 && a.current == SIMULATOR_REVISION, "{name} design {id}: {a:?}");
            }
            assert_eq!(r.recorded.record.id, id);
            assert_eq!(r.recomputed_feasible, r.recorded.record.feasible, "{name} design {id}");
            if r.compared > 0 {
                with_trajectory += 1;
                full += usize::from(r.recorded.resolution == Resolution::Full);
            }
        }
        assert!(with_trajectory > 0, "{name}: a design with a trajectory");
        // the old CSVs read typed, and their front is recorded
        for row in run.front().unwrap() {
            assert!(row.feasible && run.design(row.id).is_ok(), "{name} design {}", row.id);
        }
    }
    assert!(full > 0, "a full-resolution trajectory compared");
}

/// A recording that a re-evaluation by another revision does not reproduce within the
/// tolerance is not verified: an objective moved by 1 %, or the verdict changed.
#[test]
fn a_design_moved_beyond_the_tolerance_is_not_verified_across_revisions() {
    let dir = copy("moved", "centred");
    let run = RunFolder::open(&dir).unwrap();
    let ids =
        read_index(&dir.join("recording")).unwrap().iter().flat_map(|e| e.first_id..=e.last_id).collect::<Vec<_>>();
    let r = ids
        .into_iter()
        .map(|id| run.replay(id).unwrap())
        .find(|r| r.recorded.record.feasible && !r.verified)
        .expect("a feasible stage-3 design");
    assert!(AcrossRevisions::compare(&r.recorded, &r.fresh).agrees());
    let mut moved = r.recorded.clone();
    moved.record.objectives.t_stab = moved.record.objectives.t_stab.map(|t| t * 1.01);
    let a = AcrossRevisions::compare(&moved, &r.fresh);
    assert!(a.differs.as_deref().is_some_and(|d| d.starts_with("t_stab")), "{a:?}");
    assert!(a.max_difference > 9e-3 && a.max_difference < 1.1e-2, "{a:?}");
    let mut flipped = r.recorded.clone();
    flipped.record.feasible = false;
    flipped.record.failed_stage = Some(3);
    let a = AcrossRevisions::compare(&flipped, &r.fresh);
    assert!(a.differs.as_deref().is_some_and(|d| d.starts_with("the verdict differs")), "{a:?}");
}

/// `gripopt replay` on a design recorded by 5d2a08e says it agrees across revisions, exit 0;
/// a design of a run recorded now carries this build's revision and verifies bit for bit.
#[test]
fn replay_cli_reports_a_recording_by_another_revision() {
    let dir = copy("replay_cli", "full");
    let run = RunFolder::open(&dir).unwrap();
    let id = read_index(&dir.join("recording"))
        .unwrap()
        .iter()
        .flat_map(|e| e.first_id..=e.last_id)
        .find(|&id| run.replay(id).is_ok_and(|r| !r.verified))
        .expect("a stage-3 design");
    let o = run_gripopt(&["replay", dir.to_str().unwrap(), "--design", &id.to_string()]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(
        text.contains("verified across simulator revisions (recorded by revision 1, this build is revision"),
        "{text}"
    );
    let o = run_gripopt(&["replay", dir.to_str().unwrap(), "--design", &id.to_string(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["across_revisions"]["agrees"], true, "{v}");
    assert_eq!(v["across_revisions"]["recorded_revision"], 1, "{v}");
}
