//! The hostile-user review of the scene commands: a free scene that ends before t_obs gives
//! no verdict (`simulate`, `verify`'s CSV, table and MCAP), flags a scene cannot honour are
//! refused with exit 2 instead of being ignored, `verify` with nothing to verify writes
//! nothing, and `replay --scene` compares the scene's offset numerically (-0 = 0).

use crate::common::{output_text as text, run_gripopt as run, BOTTLE_FILE as BOTTLE};
use std::path::{Path, PathBuf};

/// A tiny run of `problem` (pop `pop`, `generations`, seed 16) under target/mcap-check/.
fn tiny_run(name: &str, problem: &Path, pop: usize, generations: u64) -> PathBuf {
    crate::common::tiny_run(&format!("scene-cli-{name}"), problem, pop, generations)
}

/// On bottle-1l at x_off = 20 mm the open finger (its tip 0.1 m from the palm) already
/// overlaps the object (radius 42.5 mm): the free scene ends at t = 0, before t_obs.
#[test]
fn simulate_free_early_end_has_no_verdict() {
    let o = run(&["simulate", BOTTLE, "--scene", "free:0.02", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = &j["free_scene"];
    assert_ne!(f["end"], "t_obs", "{j}");
    assert!(f["t_end"].as_f64().unwrap() < 0.1, "{j}");
    for k in ["moved", "toppled", "escaped"] {
        assert!(f[k].is_null(), "{k} must be null when nothing was observed: {j}");
    }
    let o = run(&["simulate", BOTTLE, "--scene", "free:0.02"]);
    let t = text(&o);
    assert!(o.status.success() && t.contains("ended early") && t.contains("moved —"), "{t}");
    assert!(!t.contains("Some(") && !t.contains("moved false"), "{t}");
}

#[test]
fn simulate_refuses_flags_it_cannot_honour() {
    let dir = std::env::temp_dir().join(format!("gripopt-scene-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the offset scene records its trajectory (finger 1's samples) like the centred scene
    let csv = dir.join("offset.csv");
    let o = run(&["simulate", BOTTLE, "--scene", "offset:0.002", "--csv", &csv.display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert!(rows > 100, "{rows} rows");
    let o = run(&["simulate", BOTTLE, "--scene", "free", "--plot", &dir.join("free.svg").display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--plot") && !dir.join("free.svg").exists());
    for scene in ["free", "offset:0.002"] {
        let o = run(&["simulate", BOTTLE, "--scene", scene, "--no-contact"]);
        assert_eq!(o.status.code(), Some(2), "{scene}: {}", text(&o));
        assert!(text(&o).contains("--no-contact"), "{}", text(&o));
    }
    // the offset scene without --json: a text report, not a JSON line
    let o = run(&["simulate", BOTTLE, "--scene", "offset:0.002"]);
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success() && t.starts_with("problem ") && t.contains("scene offset") && !t.contains('{'), "{t}");
    // --trace prints the located events of the free scene too (the nominal has 46)
    let o = run(&["simulate", BOTTLE, "--scene", "free", "--trace"]);
    assert!(o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).lines().filter(|l| l.starts_with("event ")).count() > 10,
        "{}",
        text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn verify_without_observation_and_with_nothing_to_verify() {
    let dir = tiny_run("verify", Path::new(BOTTLE), 8, 2);
    let d = dir.display().to_string();
    // --seed without --sample: refused
    let o = run(&["verify", &d, "--seed", "3"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!dir.join("verify.csv").exists());

    // x_off = 20 mm: every design's open finger overlaps the object, nothing is observed
    let o = run(&["verify", &d, "--scene", "free:0.02", "--threads", "1"]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let c = |n: &str| head.iter().position(|h| *h == n).unwrap_or_else(|| panic!("no column {n}"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(!rows.is_empty());
    for r in &rows {
        assert_ne!(r[c("free_end")], "t_obs", "{r:?}");
        for k in ["moved", "toppled", "escaped", "agrees", "peak_e_trans_ratio", "peak_e_rot_ratio"] {
            assert_eq!(r[c(k)], "", "{k} must be empty: {r:?}");
        }
    }
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        t.contains(&format!("not observed (the free scene ended before t_obs; left out of the table): {}", rows.len())),
        "{t}"
    );
    assert!(!t.contains("agreement"), "nothing observed, no agreement: {t}");
    assert!(t.contains(&format!("verified {} design{}", rows.len(), if rows.len() == 1 { "" } else { "s" })), "{t}");
    // the recording: no verdict on /verify, but free_end
    let buf = std::fs::read(dir.join("verify.mcap")).unwrap();
    let recs: Vec<serde_json::Value> = mcap::MessageStream::new(&buf)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/verify")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    assert_eq!(recs.len(), rows.len());
    for v in &recs {
        assert!(
            v.get("moved").is_none()
                && v.get("agrees").is_none()
                && v["free_end"].as_str().is_some_and(|e| e != "t_obs"),
            "{v}"
        );
    }

    // an empty front (a problem no design can meet: stability within 1 ms): refused, naming
    // the checkpoint the designs come from and why none is feasible, nothing written
    let problem = dir.parent().unwrap().join("scene-cli-no-front.toml");
    let text0 = std::fs::read_to_string(BOTTLE).unwrap();
    assert!(text0.contains("t_max = 0.3 "));
    std::fs::write(&problem, text0.replacen("t_max = 0.3 ", "t_max = 0.001 ", 1)).unwrap();
    let none = tiny_run("verify-no-front", &problem, 8, 1);
    let o = run(&["verify", &none.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("checkpoint.json") && text(&o).contains("nothing to verify"), "{}", text(&o));
    assert!(!none.join("verify.csv").exists() && !none.join("verify.mcap").exists());
}

/// An offset-kind run at x_off = 0: `--scene offset:-0` is the run's own scene.
#[test]
fn replay_minus_zero_is_the_recorded_scene() {
    let base = std::env::temp_dir().join(format!("gripopt-scene-cli-offset-{}", std::process::id()));
    std::fs::create_dir_all(&base).unwrap();
    let problem = base.join("offset.toml");
    let src = std::fs::read_to_string(BOTTLE).unwrap();
    assert!(src.contains("kind = \"centred\""));
    std::fs::write(&problem, src.replacen("kind = \"centred\"", "kind = \"offset\"", 1)).unwrap();
    let dir = tiny_run("offset", &problem, 4, 1);
    // any recorded design (feasible or not): the first row of population.csv
    let pop = std::fs::read_to_string(dir.join("population.csv")).unwrap();
    let mut rows = pop.lines().filter(|l| !l.starts_with('#'));
    let id_col = rows.next().unwrap().split(',').position(|h| h == "id").unwrap();
    let id = rows.next().unwrap().split(',').nth(id_col).unwrap().to_string();
    let d = dir.display().to_string();
    for scene in ["offset:0", "offset:-0", "offset:0e0"] {
        let o = run(&["replay", &d, "--design", &id, "--json", "--scene", scene]);
        let j: serde_json::Value =
            serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{scene}: {e}: {}", text(&o)));
        // the replay of the recording (not a re-simulation in "another" scene with its note)
        assert!(
            j.get("note").is_none() && j.get("replay").is_none() && j.get("compared_samples").is_some(),
            "{scene}: {j}"
        );
    }
    // the offset scene records no trajectory: every design verifies by its record's values
    // (stage, reason, violation, objectives, simulation work), exit 0 ...
    let ids: Vec<String> = pop
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').nth(id_col).unwrap().to_string())
        .collect();
    for id in &ids {
        let o = run(&["replay", &d, "--design", id, "--json"]);
        let j: serde_json::Value =
            serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{id}: {e}: {}", text(&o)));
        assert_eq!((o.status.code(), j["verified"].as_bool()), (Some(0), Some(true)), "design {id}: {j}");
        assert!(j["compared_values"].as_u64().unwrap() >= 3, "design {id}: {j}");
    }
    // ... and a run whose problem was changed afterwards is refused, naming the file (exit 2;
    // exit 3 "not verified" before hostile pass 34)
    let p = dir.join("problem.toml");
    let text0 = std::fs::read_to_string(&p).unwrap();
    let tau_line = text0.lines().find(|l| l.trim_start().starts_with("tau")).unwrap().to_string();
    std::fs::write(&p, text0.replacen(&tau_line, "tau = 0.45", 1)).unwrap();
    for id in &ids {
        let o = run(&["replay", &d, "--design", id, "--json"]);
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!((o.status.code(), &j["exit_code"]), (Some(2), &serde_json::json!(2)), "design {id}: {j}");
        assert!(j["error"].as_str().is_some_and(|e| e.contains("problem.toml: edited after the run")), "{j}");
    }
    let _ = std::fs::remove_dir_all(&base);
}
