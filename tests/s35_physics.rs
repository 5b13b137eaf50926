//! Session 35's physics fixes, against independent values: a robust design's t_stab counts a
//! scenario that never stabilised at t_max (MODEL.md §10's value of a missing t_stab), so a
//! design that never settles cannot score better than one that settles slowly.

use crate::common::{output_text, run_gripopt};
use serde_json::Value;
use std::path::PathBuf;

const KITCHEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch_dir("s35-physics", name)
}

/// kitchen.toml's scene with one robust object (the 1 l bottle), its phalanx friction drawn
/// from `mu` (a list), every scenario run, t_stab aggregated by `t_stab`.
fn robust_bottle(dir: &std::path::Path, mu: &str, t_stab: &str) -> String {
    let text = std::fs::read_to_string(KITCHEN).unwrap();
    let head = &text[..text.find("\n[robust]").unwrap() + 1];
    let robust = format!(
        "[robust]\nsampling = \"random\"\nscenarios = 8\nseed = 1\np_min = 0.25\nconfidence = 0.95\nearly_stop = false\n\
         verify_scenarios = 8\naggregate = {{ max_offset = \"worst\", alpha = \"worst\", mean_force = \"worst\", t_stab = {t_stab} }}\n\n\
         [[robust.objects]]\nname = \"bottle\"\nradius = 0.040\nlength = 0.200\ndensity = 1000.0\ngrasp_height = 0.050\ntau = 0.5\n\n\
         [robust.uncertainty]\nmu_phalanx = {{ list = [{mu}] }}\n"
    );
    let p = dir.join(format!("mu-{}-{}.toml", mu.replace([',', ' '], "_"), t_stab.replace('"', "")));
    std::fs::write(&p, format!("{head}{robust}")).unwrap();
    p.display().to_string()
}

fn evaluate(path: &str) -> Value {
    let o = run_gripopt(&["evaluate", path, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// With friction ×4 in some scenarios the nominal grasp never stabilises there (no t_stab):
/// "worst" is then t_max, and "mean" is the mean with t_max in their place — recomputed here
/// from the per-scenario records.
#[test]
fn a_scenario_that_never_stabilises_counts_at_t_max() {
    let d = scratch("t-max");
    let t_max = 0.3;
    for agg in ["\"worst\"", "\"mean\""] {
        let r = evaluate(&robust_bottle(&d, "1.0, 4.0", agg));
        let rr = &r["robust"];
        let scen = rr["scenarios"].as_array().unwrap();
        assert_eq!(scen.len(), 8);
        let t: Vec<Option<f64>> = scen.iter().map(|s| s["t_stab"].as_f64()).collect();
        assert!(t.iter().any(Option::is_none), "some scenario never stabilises: {t:?}");
        assert!(t.iter().any(Option::is_some), "some scenario stabilises: {t:?}");
        let filled: Vec<f64> = t.iter().map(|v| v.unwrap_or(t_max)).collect();
        let want = if agg == "\"worst\"" { t_max } else { filled.iter().sum::<f64>() / filled.len() as f64 };
        let got = rr["objectives"]["t_stab"].as_f64().unwrap();
        assert!((got - want).abs() <= 1e-15 * want, "{agg}: {got} against {want} from {t:?}");
        assert_eq!(rr["objects"][0]["t_stab"].as_f64(), Some(got), "{agg}: the one object's");
    }
    // friction ×2 everywhere settles slowly but settles: its worst t_stab is below t_max,
    // so the design that never settles (above) is the worse one
    let slow = evaluate(&robust_bottle(&d, "2.0", "\"worst\""));
    let t = slow["robust"]["objectives"]["t_stab"].as_f64().unwrap();
    assert!(t < t_max, "{t}");
}

/// A hand plane above the object's top (the fingers would close on thin air, yet the centred
/// scene rated it feasible) is refused in a single-object file, as it is for a robust object.
#[test]
fn a_hand_above_the_object_is_refused() {
    let d = scratch("above");
    let text = std::fs::read_to_string(crate::common::BOTTLE_FILE).unwrap();
    let line = text.lines().find(|l| l.starts_with("grasp_height ")).unwrap();
    for (h, ok) in [("0.25", false), ("0.2", false), ("0.19", true)] {
        let p = d.join(format!("h{h}.toml"));
        std::fs::write(&p, text.replacen(line, &format!("grasp_height = {h}"), 1)).unwrap();
        let o = run_gripopt(&["evaluate", p.to_str().unwrap(), "--static-only"]);
        let t = output_text(&o);
        if ok {
            assert_eq!(o.status.code(), Some(0), "{h}: {t}");
        } else {
            assert_eq!(o.status.code(), Some(2), "{h}: {t}");
            assert!(t.contains("object.grasp_height") && t.contains("below the object's top"), "{t}");
        }
    }
}

/// A free scene that never started (the open finger already in the object at t = 0: the
/// nominal at x_off = 5 mm, where the object's edge reaches past the open finger) measured
/// nothing: its displacement, tilt, energies and rim contact are null, not zeros that read
/// as "the object did not move" in a sweep or a CSV.
#[test]
fn a_free_scene_that_never_started_measured_nothing() {
    let o = run_gripopt(&["simulate", crate::common::BOTTLE_FILE, "--scene", "free:0.005", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = &v["free_scene"];
    assert_eq!(f["end"], "open finger penetrates the object at t = 0", "{f}");
    assert_eq!(f["steps"], 0);
    for k in [
        "object_max_displacement",
        "object_max_tilt_deg",
        "object_final_displacement",
        "object_peak_e_trans",
        "object_peak_e_rot",
        "rim_contact",
        "max_energy_rise",
    ] {
        assert!(f[k].is_null(), "{k}: {}", f[k]);
    }
    // a scene that ran keeps its measured values
    let o = run_gripopt(&["simulate", crate::common::BOTTLE_FILE, "--scene", "free", "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["free_scene"]["object_max_displacement"].as_f64().is_some_and(|d| d > 1e-4), "{}", v["free_scene"]);
}

/// The offset scene that found no static grasp at its offset never reached an end state:
/// whether the hand force recentres the object is unknown (null), not "no"; where it ran,
/// the flag is the sign test of MODEL.md §14 (hand force against the offset).
#[test]
fn an_offset_scene_that_never_ran_does_not_say_it_fails_to_recentre() {
    let sim = |scene: &str| {
        let o = run_gripopt(&["simulate", crate::common::BOTTLE_FILE, "--scene", scene, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
        serde_json::from_slice::<Value>(&o.stdout).unwrap()["offset_scene"].clone()
    };
    let beyond = sim("offset:0.0045");
    assert!(beyond["hand_x_end"].is_null() && beyond["recentres"].is_null(), "{beyond}");
    let ran = sim("offset:0.002");
    let hx = ran["hand_x_end"].as_f64().unwrap();
    assert_eq!(ran["recentres"].as_bool(), Some(hx * 0.002 < 0.0), "{ran}");
}

/// A free scene observed for less time than the fingers take to reach the object says so,
/// instead of "does not barely move (max displacement 0.000 mm …); escaped".
#[test]
fn an_observation_shorter_than_the_approach_says_no_finger_reached_the_object() {
    let d = scratch("t-obs");
    let text = std::fs::read_to_string(crate::common::BOTTLE_FILE).unwrap();
    let line = text.lines().find(|l| l.starts_with("t_obs ")).unwrap();
    let p = d.join("short.toml");
    std::fs::write(&p, text.replacen(line, "t_obs = 0.004", 1)).unwrap();
    let o = run_gripopt(&["simulate", p.to_str().unwrap(), "--scene", "free", "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["free_scene"]["t_first_contact"].is_null(), "{}", v["free_scene"]);
    let reason = v["reason"].as_str().unwrap();
    assert!(reason.contains("no finger reached the object by t_obs"), "{reason}");
    assert!(!reason.contains("does not barely move"), "{reason}");
}

/// A robust draw whose offset the open hand cannot clear (kitchen.toml with x_off drawn from
/// ±6 mm) is a measured failure counted against P(stay) — cause `initial_penetration`, the
/// design a P(stay) discard with a violation below 1e3 — not a solver failure that stops
/// the design at violation 1e3.
#[test]
fn a_draw_the_open_hand_cannot_clear_is_a_p_stay_failure() {
    let d = scratch("x-off");
    let text = std::fs::read_to_string(KITCHEN).unwrap();
    let wide = text.replacen("x_off = { uniform = [-0.002, 0.002] }", "x_off = { uniform = [-0.006, 0.006] }", 1);
    assert_ne!(wide, text);
    let p = d.join("wide.toml");
    std::fs::write(&p, wide).unwrap();
    let r = evaluate(p.to_str().unwrap());
    let scen = r["robust"]["scenarios"].as_array().unwrap();
    let pen: Vec<&Value> = scen.iter().filter(|s| s["cause"] == "initial_penetration").collect();
    assert!(!pen.is_empty(), "some draw penetrates: {scen:?}");
    for s in &pen {
        assert_eq!(s["stays"], false);
        assert!(s["max_displacement"].is_null(), "{s}");
    }
    assert_eq!(r["cause"], "p_stay", "{}", r["reason"]);
    assert!(r["violation"].as_f64().unwrap() < 1e3, "{}", r["violation"]);
}
