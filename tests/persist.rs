//! The background persister (src/run/persist.rs): a failed write is reported (never lost)
//! and nothing is persisted after it; the
//! evaluation order (most expensive first) does not change results (see also
//! optimiser::results_do_not_depend_on_the_thread_count).
use gripopt::run::{optimise, RunSpec};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/persist-tests")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn spec(out: &Path, generations: u64, threads: usize) -> RunSpec {
    crate::common::bottle_spec(out, generations, 5, threads)
}

#[test]
fn a_failed_checkpoint_is_reported_and_nothing_is_persisted_after_it() {
    let bad = tmp("bad");
    // a folder where checkpoint 1's temporary file must go: writing checkpoint 1 fails,
    // after shard 1 (shard k is always durable before checkpoint k)
    std::fs::create_dir_all(bad.join(".checkpoint.json.tmp/x")).unwrap();
    let e = optimise(&spec(&bad, 5, 2)).unwrap_err().to_string();
    assert!(e.contains(".checkpoint.json.tmp"), "the error names the file: {e}");
    // nothing to resume: the message says so instead of advising `gripopt resume`
    assert!(e.contains("before its first checkpoint") && !e.contains("gripopt resume"), "{e}");
    assert!(!bad.join("checkpoint.json").exists());
    let run: serde_json::Value = serde_json::from_slice(&std::fs::read(bad.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["status"], "interrupted");
    let gens: Vec<u64> =
        gripopt::record::read_index(&bad.join("recording")).unwrap().iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1], "the persister stops at its first error");
    // the folder can be given to `optimise` again once the obstacle is gone
    std::fs::remove_dir_all(bad.join(".checkpoint.json.tmp")).unwrap();
    let s = optimise(&spec(&bad, 2, 2)).unwrap();
    assert_eq!(s.generations, 2);
    let gens: Vec<u64> =
        gripopt::record::read_index(&bad.join("recording")).unwrap().iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1, 2]);
}
