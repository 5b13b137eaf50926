//! What a robust evaluation concludes from its scenarios (MODEL.md §10, docs/robust.md),
//! recomputed here from the per-scenario records: t_stab counts a scenario that never
//! stabilised at t_max, a scenario the solver aborted is a solver failure (not a P(stay)
//! failure), a measured evaluation keeps its P(stay) verdict, and a draw the open hand cannot
//! clear is a measured P(stay) failure.

use crate::common::{json_of, kitchen_with, output_text, run_gripopt, scratch, set_line, without_robust, KITCHEN_FILE};
use serde_json::Value;

/// kitchen.toml's scene with one robust object (the 1 l bottle), its phalanx friction drawn
/// from `mu` (a list), every scenario run, t_stab aggregated by `t_stab`.
fn robust_bottle(dir: &std::path::Path, mu: &str, t_stab: &str) -> String {
    let text = std::fs::read_to_string(KITCHEN_FILE).unwrap();
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
/// Origin: session 35's physics fixes.
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

/// A robust draw whose offset the open hand cannot clear (kitchen.toml with x_off drawn from
/// ±6 mm) is a measured failure counted against P(stay) — cause `initial_penetration`, the
/// design a P(stay) discard with a violation below 1e3 — not a solver failure that stops
/// the design at violation 1e3.
/// Origin: session 35's physics fixes.
#[test]
fn a_draw_the_open_hand_cannot_clear_is_a_p_stay_failure() {
    let d = scratch("x-off");
    let text = std::fs::read_to_string(KITCHEN_FILE).unwrap();
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

/// With `[solver] max_steps = 1` every simulation is aborted. The robust kitchen said
/// "object bottle-full: stays (finger criteria met, object barely moves) in 0 of 2 scenarios (P(stay) 0.000 < p_min …)",
/// cause p_stay; now it is the single-object problem's solver failure: cause `aborted`,
/// stage 3, the same violation, the reason naming the object, the scenario and the solver's
/// own message. The per-scenario records stay as they were; the stopping rule stops at the
/// aborted scenario (early stop) and the verdict is the same without early stop.
/// Origin: hostile pass of session 34, robust design.
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
/// Origin: hostile pass of session 34, robust design.
#[test]
fn a_measured_kitchen_evaluation_keeps_its_p_stay_verdict() {
    let r = json_of(&["evaluate", "--json", KITCHEN_FILE]);
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
