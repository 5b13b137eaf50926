//! `gripopt verify`: verify.csv holds one row per Pareto design whose measured motion equals
//! an independent `gripopt simulate --scene free --json` of the design read from pareto.csv
//! (verify itself takes the designs from the checkpoint: an edited pareto.csv changes nothing),
//! the printed confusion table adds up to the rows and matches the CSV, the CSV does not
//! depend on the thread count, and bad folders are refused with exit 2, nothing deleted.

use gripopt::run::RunLock;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_gripopt");

/// A tiny run (pop 8, 2 generations; seed 16 has 4 designs on its front) under
/// target/mcap-check/ so that `make test` checks its recording.
fn tiny_run(name: &str) -> PathBuf {
    crate::common::tiny_run(&format!("verify-{name}"), std::path::Path::new(crate::common::BOTTLE_FILE), 8, 2)
}

fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// (header, rows) of a CSV with `#` lines, split on commas (pareto.csv's quoted `reason`
/// holds no comma for feasible designs: it is empty).
fn table(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    (head, lines.map(|l| l.split(',').map(String::from).collect()).collect())
}

fn col(head: &[String], name: &str) -> usize {
    head.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn verify_matches_simulate_and_threads() {
    let dir = tiny_run("front");
    let d = dir.display().to_string();
    let out = run(&["verify", &d, "--threads", "1"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let csv1 = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let out2 = run(&["verify", &d, "--threads", "2"]);
    assert!(out2.status.success());
    assert_eq!(
        csv1,
        std::fs::read_to_string(dir.join("verify.csv")).unwrap(),
        "verify.csv depends on the thread count"
    );

    let (ph, prow) = table(&dir.join("pareto.csv"));
    let (vh, vrow) = table(&dir.join("verify.csv"));
    let prow: Vec<_> = prow.into_iter().filter(|r| r[col(&ph, "feasible")] == "true").collect();
    assert!(!prow.is_empty(), "the tiny run has no front");
    assert_eq!(vrow.len(), prow.len(), "one verify row per Pareto design");
    let mut ids: Vec<u64> = prow.iter().map(|r| r[col(&ph, "id")].parse().unwrap()).collect();
    ids.sort();
    let vids: Vec<u64> = vrow.iter().map(|r| r[col(&vh, "id")].parse().unwrap()).collect();
    assert_eq!(ids, vids, "rows in id order");

    let problem = dir.join("problem.toml").display().to_string();
    let mut counts = [0usize; 4];
    for r in &prow {
        let id = &r[col(&ph, "id")];
        let design = gripopt::params::DESIGN_NAMES
            .iter()
            .map(|n| format!("{n}={}", r[col(&ph, n)]))
            .collect::<Vec<_>>()
            .join(",");
        let o = run(&["simulate", &problem, "--scene", "free", "--json", "--design", &design]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let v = vrow.iter().find(|v| &v[0] == id).unwrap();
        let f = |name: &str| -> f64 { v[col(&vh, name)].parse().unwrap() };
        let b = |name: &str| -> bool { v[col(&vh, name)].parse().unwrap() };
        for k in ["object_max_displacement", "object_max_tilt_deg", "object_peak_e_trans", "object_peak_e_rot"] {
            assert_eq!(f(k), j["free_scene"][k].as_f64().unwrap(), "design {id}: {k}");
        }
        for k in ["moved", "toppled", "escaped", "rim_contact"] {
            assert_eq!(b(k), j["free_scene"][k].as_bool().unwrap(), "design {id}: {k}");
        }
        // the prediction from simulate's centred keys
        let ratio = j["e_cyl"].as_f64().unwrap() / j["e_lim"].as_f64().unwrap();
        assert_eq!(f("impact_ratio"), ratio, "design {id}: impact ratio");
        let margin = j["min_force_margin"].as_f64().unwrap().min(j["static_force_margin"].as_f64().unwrap());
        assert_eq!(f("force_margin"), margin, "design {id}: force margin");
        let pred = ratio > 1.0 || margin < 0.0;
        assert_eq!(b("predicted_moves"), pred);
        assert_eq!(b("agrees"), pred == b("moved"));
        counts[match (pred, b("moved")) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        }] += 1;
    }
    // the printed table: two rows of two counts, adding up to the rows
    let text = String::from_utf8_lossy(&out.stdout);
    let nums = |prefix: &str| -> Vec<usize> {
        let l = text
            .lines()
            .find(|l| l.trim_start().starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in {text}"));
        l.split_whitespace().filter_map(|w| w.parse().ok()).collect()
    };
    let (a, b) = (nums("predicted moves"), nums("predicted stays"));
    assert_eq!([a[0], a[1], b[0], b[1]], counts, "{text}");
    assert_eq!(a[0] + a[1] + b[0] + b[1], vrow.len());
}

/// `--all`: one row per distinct feasible id of population.csv and archive.csv; `--sample`:
/// N designs, each passing stage 2 (checked independently with `evaluate --static-only`),
/// identical for 1 and 2 threads.
#[test]
fn verify_all_and_sample() {
    let dir = tiny_run("all");
    let d = dir.display().to_string();
    let o = run(&["verify", &d, "--all"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut ids = std::collections::BTreeSet::new();
    for f in ["population.csv", "archive.csv"] {
        let (h, rows) = table(&dir.join(f));
        for r in rows.iter().filter(|r| r[col(&h, "feasible")] == "true") {
            ids.insert(r[col(&h, "id")].parse::<u64>().unwrap());
        }
    }
    let (vh, vrow) = table(&dir.join("verify.csv"));
    let vids: Vec<u64> = vrow.iter().map(|r| r[col(&vh, "id")].parse().unwrap()).collect();
    assert_eq!(vids, ids.into_iter().collect::<Vec<_>>());

    assert!(run(&["verify", &d, "--sample", "6", "--seed", "3", "--threads", "1"]).status.success());
    let s1 = std::fs::read_to_string(dir.join("verify_sample.csv")).unwrap();
    assert!(run(&["verify", &d, "--sample", "6", "--seed", "3", "--threads", "2"]).status.success());
    assert_eq!(s1, std::fs::read_to_string(dir.join("verify_sample.csv")).unwrap());
    let (sh, srow) = table(&dir.join("verify_sample.csv"));
    assert_eq!(srow.len(), 6);
    let problem = dir.join("problem.toml").display().to_string();
    for r in &srow {
        let design = gripopt::params::DESIGN_NAMES
            .iter()
            .map(|n| format!("{n}={}", r[col(&sh, n)]))
            .collect::<Vec<_>>()
            .join(",");
        let o = run(&["evaluate", &problem, "--static-only", "--json", "--design", &design]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(j["failed_stage"].is_null(), "sample design {} fails stage {}", r[0], j["failed_stage"]);
    }
}

#[test]
fn verify_refuses_bad_folders() {
    let dir = tiny_run("bad");
    let d = dir.display().to_string();
    // not a folder, not a run
    assert_eq!(run(&["verify", &format!("{d}/nothing-here")]).status.code(), Some(2));
    let not_run = dir.join("not-a-run");
    std::fs::create_dir_all(&not_run).unwrap();
    std::fs::write(not_run.join("keep.txt"), "x").unwrap();
    let o = run(&["verify", &not_run.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run.json"));
    assert!(not_run.join("keep.txt").exists());
    // a locked run folder
    {
        let _lock = RunLock::acquire(&dir).unwrap();
        let o = run(&["verify", &d]);
        assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stderr).contains("in use"));
    }
    // a bad scene
    assert_eq!(run(&["verify", &d, "--scene", "centred"]).status.code(), Some(2));
    // the designs come from the checkpoint, not from the CSV views: a pareto.csv edited by
    // hand (a design's l21 changed) or deleted changes nothing verify.csv says
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let reference = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let pareto = std::fs::read_to_string(dir.join("pareto.csv")).unwrap();
    let (ph, prow) = table(&dir.join("pareto.csv"));
    let l21 = &prow[0][col(&ph, "l21")];
    let edited = pareto.replacen(&format!(",{l21},"), ",0.0432,", 1);
    assert_ne!(edited, pareto, "the edit took");
    std::fs::write(dir.join("pareto.csv"), edited).unwrap();
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("verify.csv")).unwrap(), reference, "verify took an edited pareto.csv");
    std::fs::remove_file(dir.join("pareto.csv")).unwrap();
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("verify.csv")).unwrap(), reference);
    // a missing checkpoint.json: refused naming it, the rest of the run kept
    std::fs::remove_file(dir.join("verify.csv")).unwrap();
    std::fs::rename(dir.join("checkpoint.json"), dir.join("checkpoint.json.away")).unwrap();
    let before: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    let o = run(&["verify", &d]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("checkpoint.json"), "{}", String::from_utf8_lossy(&o.stderr));
    for f in before {
        assert!(dir.join(&f).exists(), "{f:?} deleted");
    }
    assert!(!dir.join("verify.csv").exists());
}
