//! Hostile pass 34, robust design (docs/robust.md): a scenario the solver aborted was
//! counted as "the object did not stay" (a P(stay) discard whose real cause showed only in
//! the per-scenario records), and `simulate` of a robust problem ran the reference
//! `[object]` silently, with no way to simulate one of its objects. Each test fails without
//! its fix.

use crate::common::{output_text, run_gripopt, untimed};
use serde_json::Value;
use std::path::PathBuf;

const KITCHEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34_robust")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// kitchen.toml's text with `edit` applied, written to `dir/name`.
fn kitchen_with(dir: &std::path::Path, name: &str, edit: impl Fn(String) -> String) -> String {
    let path = dir.join(name);
    std::fs::write(&path, edit(std::fs::read_to_string(KITCHEN).unwrap())).unwrap();
    path.display().to_string()
}

/// `text` with its line starting with `key =` replaced by `line` (exactly one such line).
fn set_line(text: String, key: &str, line: &str) -> String {
    let hits = text.lines().filter(|l| l.starts_with(&format!("{key} ="))).count();
    assert_eq!(hits, 1, "one `{key} =` line");
    text.lines().map(|l| if l.starts_with(&format!("{key} =")) { line } else { l }).collect::<Vec<_>>().join("\n")
        + "\n"
}

/// `text` without its `[robust]` sections (they close kitchen.toml): a single-object problem.
fn without_robust(text: String) -> String {
    let at = text.find("\n[robust]").expect("kitchen.toml has [robust]");
    let rest = text[at + 1..].lines().filter(|l| l.starts_with('['));
    assert!(
        rest.clone().all(|l| l.starts_with("[robust") || l.starts_with("[[robust")),
        "{:?}",
        rest.collect::<Vec<_>>()
    );
    text[..at + 1].to_string()
}

fn json_of(args: &[&str]) -> Value {
    let o = run_gripopt(args);
    assert_eq!(o.status.code(), Some(0), "{args:?}: {}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: stdout is one JSON object: {e}"))
}

/// With `[solver] max_steps = 1` every simulation is aborted. The robust kitchen said
/// "object bottle-full: stays (finger criteria met, object barely moves) in 0 of 2 scenarios (P(stay) 0.000 < p_min …)",
/// cause p_stay; now it is the single-object problem's solver failure: cause `aborted`,
/// stage 3, the same violation, the reason naming the object, the scenario and the solver's
/// own message. The per-scenario records stay as they were; the stopping rule stops at the
/// aborted scenario (early stop) and the verdict is the same without early stop.
#[test]
fn an_aborted_scenario_is_a_solver_failure_not_a_p_stay_failure() {
    let d = scratch("aborted");
    let one_step = |t| set_line(t, "max_steps", "max_steps = 1");
    let robust = kitchen_with(&d, "k1s.toml", one_step);
    let single = kitchen_with(&d, "k1s-single.toml", |t| without_robust(one_step(t)));
    let all = kitchen_with(&d, "k1s-all.toml", |t| set_line(one_step(t), "early_stop", "early_stop = false"));

    let s = json_of(&["evaluate", "--json", &single]);
    assert_eq!(s["cause"], "aborted", "{s}");
    let single_reason = s["reason"].as_str().unwrap().to_string();
    assert!(single_reason.contains("step budget"), "{single_reason}");

    for (path, planned_run) in [(&robust, 1), (&all, 32)] {
        let r = json_of(&["evaluate", "--json", path]);
        assert_eq!(r["feasible"], false, "{path}");
        assert_eq!(r["failed_stage"], 3, "{path}");
        assert_eq!(r["cause"], "aborted", "{path}: {}", r["reason"]);
        assert_eq!(r["violation"], s["violation"], "{path}: the single-object violation");
        let reason = r["reason"].as_str().unwrap();
        assert!(reason.starts_with("object bottle-full: scenario 0: "), "{reason}");
        assert!(reason.contains(&single_reason), "{reason} quotes the solver: {single_reason}");
        assert!(!reason.contains("P(stay)"), "{reason}");
        let rr = &r["robust"];
        assert_eq!(rr["scenarios_run"], planned_run, "{path}");
        // the per-scenario records as they were: the cause, not staying
        let first = &rr["scenarios"][0];
        assert_eq!((first["object"].as_u64(), first["k"].as_u64()), (Some(0), Some(0)));
        assert_eq!(first["cause"], "aborted");
        assert_eq!(first["stays"], false);
        assert!(first.get("abort").is_none(), "no new key in a scenario record: {first}");
    }
    let o = run_gripopt(&["evaluate", &robust]);
    let text = output_text(&o);
    assert!(text.contains("DISCARDED at stage 3: object bottle-full: scenario 0: aborted"), "{text}");

    // the optimiser's summary groups the discard by its real cause
    let out = d.join("run");
    let o = run_gripopt(&[
        "optimise",
        &robust,
        "--out",
        out.to_str().unwrap(),
        "--pop",
        "8",
        "--generations",
        "1",
        "--record",
        "none",
        "--seed",
        "1",
    ]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(!text.contains("by p stay"), "{text}");
    assert!(text.contains("at stage 3 by aborted"), "{text}");
}

/// A design whose scenarios all ran to their measurement keeps its P(stay) verdict: the
/// nominal kitchen design, its verdict recomputed here from its scenario records (MODEL.md
/// §10, docs/robust.md: f_max = K − ⌈p_min K⌉, the first object to exceed it in the order
/// run names the reason, violation Σ_o max(0, p_min − P̂_o)).
#[test]
fn a_measured_kitchen_evaluation_keeps_its_p_stay_verdict() {
    let r = json_of(&["evaluate", "--json", KITCHEN]);
    let rr = &r["robust"];
    let scen = rr["scenarios"].as_array().unwrap();
    let names: Vec<&str> = rr["objects"].as_array().unwrap().iter().map(|o| o["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["bottle-full", "bottle-half", "can", "small-bottle"]);
    let (k, p_min) = (8usize, 0.85);
    let fmax = k - (p_min * k as f64).ceil() as usize;
    assert_eq!(fmax, 1);
    let mut fails = [0usize; 4];
    let mut first_out = None;
    for (j, s) in scen.iter().enumerate() {
        assert!(!matches!(s["cause"].as_str(), Some("aborted" | "free_scene_aborted")), "{s}");
        if s["stays"] == false {
            let o = s["object"].as_u64().unwrap() as usize;
            fails[o] += 1;
            if fails[o] > fmax && first_out.is_none() {
                first_out = Some((j, o));
            }
        }
    }
    let (j, o) = first_out.expect("the nominal design fails the kitchen (docs/robust.md)");
    assert_eq!(scen.len(), j + 1, "early stop after the deciding scenario");
    assert_eq!(r["cause"], "p_stay");
    assert_eq!(r["failed_stage"], 3);
    let runs = |o: usize| scen.iter().filter(|s| s["object"] == o).count();
    let stays = |o: usize| scen.iter().filter(|s| s["object"] == o && s["stays"] == true).count();
    let reason = r["reason"].as_str().unwrap();
    let want = format!(
        "object {}: stays (finger criteria met, object barely moves) in {} of {} scenarios",
        names[o],
        stays(o),
        runs(o)
    );
    assert!(reason.starts_with(&want), "{reason} / {want}");
    let violation: f64 =
        (0..4).filter(|&o| runs(o) > 0).map(|o| (p_min - stays(o) as f64 / runs(o) as f64).max(0.0)).sum();
    assert!((r["violation"].as_f64().unwrap() - violation).abs() < 1e-12, "{} vs {violation}", r["violation"]);
}

/// `simulate` of a robust problem ran the reference `[object]` without a word (export and
/// sweep say so) and could not run any of its objects, while docs/robust.md said `file =`
/// objects work for simulate. Now `--object NAME` simulates the design on that object —
/// the same as simulating a single-object problem made of that object — and without it a
/// note on stderr names the objects and the flag (stdout stays one JSON object).
#[test]
fn simulate_object_grasps_the_named_robust_object() {
    let d = scratch("simulate");
    // kitchen's can as the [object] of a problem without [robust] (its tau = [hand] tau)
    let can = kitchen_with(&d, "can-single.toml", |t| {
        let t = without_robust(t);
        let (a, b) = (t.find("[object]\n").unwrap(), t.find("[contact]").unwrap());
        let obj = "[object]\nradius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\n\n";
        format!("{}{obj}{}", &t[..a], &t[b..])
    });
    let mut on_can = json_of(&["simulate", KITCHEN, "--object", "can", "--json"]);
    assert_eq!(on_can["object"], "can");
    on_can.as_object_mut().unwrap().remove("object");
    let single = json_of(&["simulate", &can, "--json"]);
    assert_eq!(untimed(on_can.clone()), untimed(single), "--object can = the can's own problem");

    let o = run_gripopt(&["simulate", KITCHEN, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let reference: Value = serde_json::from_slice(&o.stdout).expect("stdout is one JSON object");
    assert!(reference.get("object").is_none());
    let note = String::from_utf8_lossy(&o.stderr);
    for w in ["note:", "reference [object]", "--object", "bottle-full, bottle-half, can, small-bottle"] {
        assert!(note.contains(w), "{w}: {note}");
    }
    // E_lim = min(μ_g m_c g Δx_max, …): 1.34 mJ for the can, 3.94 mJ for the bottle
    // (docs/robust.md, "The can"); the finger's own impact energy hardly changes
    let e_lim = |v: &Value| v["e_lim"].as_f64().unwrap() * 1e3;
    assert!((e_lim(&on_can) - 1.34).abs() < 0.005, "{}", e_lim(&on_can));
    assert!((e_lim(&reference) - 3.94).abs() < 0.005, "{}", e_lim(&reference));
    assert_ne!(on_can["f0_1"], reference["f0_1"]);
    assert_ne!(on_can["t_first_contact"], reference["t_first_contact"]);

    // --object without a note; the text report names the object
    let o = run_gripopt(&["simulate", KITCHEN, "--object", "can"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note:"), "{}", output_text(&o));
    let first = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
    assert!(first.contains("object can"), "{first}");
}

/// An unknown object, or `--object` on a problem without [robust], is an input error
/// (exit 2) naming the flag, as `export --object`'s.
#[test]
fn simulate_object_refuses_unknown_names() {
    let bottle = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    for (file, says) in [(KITCHEN, "no such robust object"), (bottle, "not robust")] {
        for json in [false, true] {
            let mut args = vec!["simulate", file, "--object", "mug"];
            if json {
                args.push("--json");
            }
            let o = run_gripopt(&args);
            let text = output_text(&o);
            assert_eq!(o.status.code(), Some(2), "{text}");
            assert!(text.contains("--object mug") && text.contains(says), "{text}");
        }
    }
}
