//! The scene commands' flags: a free scene that ends before t_obs gives no verdict
//! (`simulate`), flags a scene cannot honour are refused with exit 2 instead of being ignored,
//! and `--scene` names what is wrong with a missing or padded offset. (From the hostile-user
//! review of the scene commands; its `verify` and `replay` tests are in verify.rs and
//! replay.rs.)

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};
use gripopt::params::SceneKind;

/// On bottle-1l at x_off = 20 mm the open finger (its tip 0.1 m from the palm) already
/// overlaps the object (radius 42.5 mm): the free scene ends at t = 0, before t_obs.
#[test]
fn simulate_free_early_end_has_no_verdict() {
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "free:0.02", "--json"]);
    assert!(o.status.success(), "{}", output_text(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = &j["free_scene"];
    assert_ne!(f["end"], "t_obs", "{j}");
    assert!(f["t_end"].as_f64().unwrap() < 0.1, "{j}");
    for k in ["moved", "toppled", "escaped"] {
        assert!(f[k].is_null(), "{k} must be null when nothing was observed: {j}");
    }
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "free:0.02"]);
    let t = output_text(&o);
    assert!(o.status.success() && t.contains("ended early") && t.contains("moved —"), "{t}");
    assert!(!t.contains("Some(") && !t.contains("moved false"), "{t}");
}

#[test]
fn simulate_refuses_flags_it_cannot_honour() {
    let dir = std::env::temp_dir().join(format!("gripopt-scene-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the offset scene records its trajectory (finger 1's samples) like the centred scene
    let csv = dir.join("offset.csv");
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "offset:0.002", "--csv", &csv.display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert!(rows > 100, "{rows} rows");
    let o = run_gripopt(&[
        "simulate",
        BOTTLE_FILE,
        "--scene",
        "free",
        "--plot",
        &dir.join("free.svg").display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("--plot") && !dir.join("free.svg").exists());
    for scene in ["free", "offset:0.002"] {
        let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", scene, "--no-contact"]);
        assert_eq!(o.status.code(), Some(2), "{scene}: {}", output_text(&o));
        assert!(output_text(&o).contains("--no-contact"), "{}", output_text(&o));
    }
    // the offset scene without --json: a text report, not a JSON line
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "offset:0.002"]);
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success() && t.starts_with("problem ") && t.contains("scene offset") && !t.contains('{'), "{t}");
    // --trace prints the located events of the free scene too (the nominal has 46)
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "free", "--trace"]);
    assert!(o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).lines().filter(|l| l.starts_with("event ")).count() > 10,
        "{}",
        output_text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// (4c) `--scene` names what is wrong with a missing or blank-padded offset instead of
/// showing an empty pair of backticks or accepting it silently.
/// Origin: hostile pass of session 37.
#[test]
fn parse_scene_names_a_missing_or_padded_offset() {
    let parse_scene = gripopt::SceneChoice::parse;
    for kind in ["offset", "free"] {
        let missing = parse_scene(&format!("{kind}:")).unwrap_err().to_string();
        assert!(missing.contains(&format!("a number is missing after `{kind}:`")), "{missing}");
        assert!(!missing.contains("``"), "{missing}");
        let padded = parse_scene(&format!("{kind}: 0.01")).unwrap_err().to_string();
        assert!(padded.contains(&format!("write `{kind}:0.01`")), "{padded}");
        assert!(parse_scene(&format!("{kind}:0.01 ")).is_ok(), "a blank after the whole value is the shell's");
    }
    assert_eq!(
        parse_scene("offset:0.002").unwrap(),
        gripopt::SceneChoice { kind: SceneKind::Offset, x_off: Some(0.002) }
    );
    let bad = parse_scene("offset:abc").unwrap_err().to_string();
    assert!(bad.contains("`abc` after `offset:` is not a number"), "{bad}");
}
