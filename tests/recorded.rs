//! Recordings written by an older gripopt (tests/fixtures/recorded-5d2a08e: run folders of
//! the 5d2a08e binary, each its problem, run.json, CSVs and MCAP shards) are read and
//! verified by this one: every design replays (the `/designs` record read back typed, the
//! re-evaluation agreeing with it), and a full-resolution trajectory recorded by that
//! binary is reproduced bit for bit by the samples the simulation now hands its sink.

use gripopt::record::{read_index, Resolution};
use gripopt::RunFolder;
use std::path::{Path, PathBuf};

/// A copy of fixture `name` under target/ (replay reads; the copy keeps the fixture clean).
fn copy(name: &str) -> PathBuf {
    let from = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/recorded-5d2a08e")).join(name);
    let to = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/recorded-5d2a08e")).join(name);
    let _ = std::fs::remove_dir_all(&to);
    std::fs::create_dir_all(to.join("recording")).unwrap();
    for dir in ["", "recording"] {
        for e in std::fs::read_dir(from.join(dir)).unwrap().flatten().filter(|e| e.path().is_file()) {
            std::fs::copy(e.path(), to.join(dir).join(e.file_name())).unwrap();
        }
    }
    to
}

#[test]
fn designs_recorded_by_5d2a08e_replay_and_verify() {
    let mut bitwise = 0;
    for name in ["centred", "free", "full"] {
        let dir = copy(name);
        let run = RunFolder::open(&dir).unwrap();
        let ids: Vec<u64> =
            read_index(&dir.join("recording")).unwrap().iter().flat_map(|e| e.first_id..=e.last_id).collect();
        assert!(ids.len() >= 4, "{name}");
        let mut with_trajectory = 0;
        for id in ids {
            let r = run.replay(id).unwrap_or_else(|e| panic!("{name} design {id}: {e}"));
            assert!(r.verified && r.compared + r.values_compared > 0, "{name} design {id}: {r:?}");
            assert_eq!(r.recorded.record.id, id);
            assert_eq!(r.recomputed_feasible, r.recorded.record.feasible, "{name} design {id}");
            if r.compared > 0 {
                with_trajectory += 1;
                if r.recorded.resolution == Resolution::Full {
                    // every kept sample, all sixteen values, equal to the last bit
                    assert_eq!(r.max_difference, 0.0, "{name} design {id}");
                    bitwise += 1;
                }
            }
        }
        assert!(with_trajectory > 0, "{name}: a design with a trajectory");
        // the old CSVs read typed, and their front is recorded
        for row in run.front().unwrap() {
            assert!(row.feasible && run.design(row.id).is_ok(), "{name} design {}", row.id);
        }
    }
    assert!(bitwise > 0, "a full-resolution trajectory compared bit for bit");
}
