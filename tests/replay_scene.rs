//! `gripopt replay RUN_DIR --design ID --scene S`: the run's own scene verifies as without
//! `--scene`; another scene re-simulates the recorded design there, reports exactly what
//! `simulate --scene S` reports for the design read from pareto.csv, says it cannot be
//! verified (`verified: null`) and exits 0; a bad scene is refused with exit 2.

use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_gripopt");

fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "exit {:?}: {}", o.status.code(), String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

/// Drop the keys that are wall-clock timings.
fn untimed(mut v: serde_json::Value) -> serde_json::Value {
    for k in ["cpu_s", "replay_s"] {
        v.as_object_mut().unwrap().remove(k);
    }
    if let Some(f) = v.get_mut("free_scene").and_then(|f| f.as_object_mut()) {
        f.remove("cpu_s");
    }
    v
}

#[test]
fn replay_in_another_scene() {
    let dir = crate::common::tiny_run("replay-scene", std::path::Path::new(crate::common::BOTTLE_FILE), 8, 2);
    let front = gripopt::run::read_design_csv(&dir.join("pareto.csv")).unwrap();
    let (id, x) = front[0];
    let (d, ids) = (dir.display().to_string(), id.to_string());
    let problem = dir.join("problem.toml").display().to_string();
    let design = gripopt::params::DESIGN_NAMES
        .iter()
        .zip(x.to_array())
        .map(|(n, v)| format!("{n}={v}"))
        .collect::<Vec<_>>()
        .join(",");

    // the run's own scene (centred): verification, unchanged by --scene
    let plain = untimed(json(&run(&["replay", &d, "--design", &ids, "--json"])));
    let same = untimed(json(&run(&["replay", &d, "--design", &ids, "--json", "--scene", "centred"])));
    assert_eq!(plain["verified"], serde_json::json!(true));
    assert_eq!(plain, same);

    // another scene: simulate's report of the recorded design, marked as not verifiable
    for scene in ["free", "free:0.001", "offset:0.001"] {
        let r = untimed(json(&run(&["replay", &d, "--design", &ids, "--json", "--scene", scene])));
        let s = untimed(json(&run(&["simulate", &problem, "--design", &design, "--json", "--scene", scene])));
        assert!(r["verified"].is_null(), "{scene}: {r}");
        assert_eq!(r["replay"]["recorded_scene"], "centred");
        assert!(r["note"].as_str().unwrap().contains("cannot be verified"), "{scene}");
        for (k, v) in s.as_object().unwrap() {
            assert_eq!(&r[k], v, "{scene}: key {k}");
        }
    }
    let r = json(&run(&["replay", &d, "--design", &ids, "--json", "--scene", "free"]));
    let f = &r["free_scene"];
    assert!(f["object_max_displacement"].as_f64().is_some() && f["moved"].is_boolean());

    // text output and --csv with the object pose
    let csv = dir.join("replay-free.csv");
    let o = run(&["replay", &d, "--design", &ids, "--scene", "free:0.002", "--csv", &csv.display().to_string()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("cannot be verified against the recording") && text.contains("free:0.002"), "{text}");
    let text = std::fs::read_to_string(&csv).unwrap();
    // after the `#` title and units lines (docs/outputs.md)
    let head = text.lines().find(|l| !l.starts_with('#')).unwrap_or_default();
    assert!(head.starts_with("t,gx,gy,gz,qw,qx,qy,qz"), "{head}");

    // bad scenes: exit 2
    for bad in ["sideways", "offset:abc", "free:9"] {
        let o = run(&["replay", &d, "--design", &ids, "--scene", bad]);
        assert_eq!(o.status.code(), Some(2), "--scene {bad}: {}", String::from_utf8_lossy(&o.stderr));
    }
}
