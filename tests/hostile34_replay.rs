//! Hostile pass 34, replay and verify of robust designs the solver aborted (docs/robust.md):
//! `replay` of a robust design (or one scenario of it) whose scenario the solver aborted said
//! "NOT verified" (exit 3) although nothing differed — the solver's own account of the abort
//! is not written to the recording, and the re-evaluation's was compared with its absence —
//! and `verify` counted an out-of-sample scenario the solver aborted as "did not stay",
//! keeping a design whose P̂ still reached p_min, with no word of the abort. Each test fails
//! without its fix.

use crate::common::{output_text, run_gripopt};
use serde_json::Value;
use std::path::{Path, PathBuf};

const KITCHEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34_replay")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `text` with its line starting with `key =` replaced by `line` (exactly one such line).
fn set_line(text: &str, key: &str, line: &str) -> String {
    let hits = text.lines().filter(|l| l.starts_with(&format!("{key} ="))).count();
    assert_eq!(hits, 1, "one `{key} =` line");
    text.lines().map(|l| if l.starts_with(&format!("{key} =")) { line } else { l }).collect::<Vec<_>>().join("\n")
        + "\n"
}

/// kitchen.toml with `[solver] max_steps = steps` and, with `small`, only its first object
/// (bottle-full), K = 4, 4 verify scenarios, p_min 0.5 and no certification stage (a quick
/// run with a feasible front: verify then checks the search's front, which certification
/// on fresh scenarios the step budget cuts short would empty).
fn kitchen(steps: u64, small: bool) -> String {
    let mut t = std::fs::read_to_string(KITCHEN).unwrap();
    if small {
        let first = t.find("[[robust.objects]]").unwrap();
        let second = first + 1 + t[first + 1..].find("[[robust.objects]]").unwrap();
        let uncertainty = t.find("[robust.uncertainty]").unwrap();
        t = format!("{}{}", &t[..second], &t[uncertainty..]);
        t = set_line(&t, "scenarios", "scenarios = 4");
        t = set_line(&t, "verify_scenarios", "verify_scenarios = 4");
        t = set_line(&t, "p_min", "p_min = 0.5");
        t.push_str("\n[robust.certify]\nenabled = false\n");
    }
    set_line(&t, "max_steps", &format!("max_steps = {steps}"))
}

fn gripopt(args: &[&str], code: i32) -> String {
    let o = run_gripopt(args);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {text}");
    text
}

fn json(args: &[&str], code: i32) -> Value {
    let o = run_gripopt(args);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: stdout is one JSON object: {e}"))
}

/// The id of the first design of `run`'s population.csv whose reason contains `word`.
fn design_whose_reason_has(run: &Path, word: &str) -> String {
    let text = std::fs::read_to_string(run.join("population.csv")).unwrap();
    let line = text.lines().find(|l| !l.starts_with('#') && l.contains(word)).expect("such a design");
    line.split(',').next().unwrap().to_string()
}

/// `file` with every occurrence of `from` replaced by `to` (bytes), at least one.
fn replace_in(file: &Path, from: &str, to: &str) {
    let b = std::fs::read(file).unwrap();
    let (f, t) = (from.as_bytes(), to.as_bytes());
    assert_eq!(f.len(), t.len());
    let mut out = b.clone();
    let mut n = 0;
    for i in 0..b.len().saturating_sub(f.len() - 1) {
        if &b[i..i + f.len()] == f {
            out[i..i + f.len()].copy_from_slice(t);
            n += 1;
        }
    }
    assert!(n > 0, "{} holds {from}", file.display());
    std::fs::write(file, out).unwrap();
}

fn sha256_of(file: &Path) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(std::fs::read(file).unwrap()).iter().map(|b| format!("{b:02x}")).collect()
}

/// With `[solver] max_steps = 1` the kitchen's designs that reach stage 3 are solver-failure
/// discards (`object bottle-full: scenario 0: aborted: …`). Their replay, and the replay of
/// the aborted scenario, reproduce the record field for field: verified (exit 0). A replay
/// that really differs — the same run, its problem given `max_steps = 2` (its hashes in
/// run.json and in the shard updated, so that the replay uses it and names no other
/// problem) — is not (exit 3): the scenario's steps differ.
#[test]
fn a_robust_design_the_solver_aborted_replays_as_verified() {
    let d = scratch("replay");
    let problem = d.join("k1.toml");
    std::fs::write(&problem, kitchen(1, false)).unwrap();
    let run = d.join("run");
    let (p, r) = (problem.to_str().unwrap(), run.to_str().unwrap());
    gripopt(&["optimise", p, "--out", r, "--pop", "8", "--generations", "1", "--seed", "1"], 0);
    let id = design_whose_reason_has(&run, "scenario 0: aborted");

    let text = gripopt(&["replay", r, "--design", &id], 0);
    assert!(text.contains("verified (no trajectory recorded for this design)"), "{text}");
    let j = json(&["replay", r, "--design", &id, "--json"], 0);
    assert_eq!((&j["verified"], &j["verdict_agrees"]), (&Value::Bool(true), &Value::Bool(true)), "{j}");
    assert_eq!(j["robust"]["scenarios"][0]["cause"], "aborted", "{j}");

    let scenario = ["replay", r, "--design", &id, "--scenario", "bottle-full:0"];
    let text = gripopt(&scenario, 0);
    assert!(text.contains("verified: the re-simulation equals the recorded scenario"), "{text}");
    let j = json(&[&scenario[..], &["--json"]].concat(), 0);
    assert_eq!(j["verified"], true, "{j}");
    assert_eq!(j["scenario"], j["recorded"], "{j}");
    assert_eq!(j["scenario"]["cause"], "aborted", "{j}");
    assert!(j["scenario"].get("abort").is_none(), "{j}");

    // a real difference: the problem changed (max_steps 2), its hashes made the run's
    let other = d.join("other");
    crate::common::copy_dir(&run, &other);
    let was = sha256_of(&other.join("problem.toml"));
    std::fs::write(other.join("problem.toml"), kitchen(2, false)).unwrap();
    let now = sha256_of(&other.join("problem.toml"));
    replace_in(&other.join("run.json"), &was, &now);
    replace_in(&other.join("recording/gen-00001.mcap"), &was, &now);
    let o = other.to_str().unwrap();
    let text = gripopt(&["replay", o, "--design", &id], 3);
    assert!(text.contains("NOT verified"), "{text}");
    let j = json(&["replay", o, "--design", &id, "--json"], 3);
    assert_eq!((&j["verified"], &j["problem_note"]), (&Value::Bool(false), &Value::Null), "{j}");
    let scenario = ["replay", o, "--design", &id, "--scenario", "bottle-full:0", "--json"];
    let j = json(&scenario, 3);
    assert_eq!(j["verified"], false, "{j}");
    assert_eq!((&j["scenario"]["steps"][0], &j["recorded"]["steps"][0]), (&Value::from(2), &Value::from(1)), "{j}");
}

/// A front design whose fresh (out-of-sample) scenarios the solver aborted does not keep
/// P(stay) ≥ p_min on that object, even where its P̂ (which counts the aborted scenarios as
/// not staying) reaches p_min, and verify's report and verify_robust.csv (a `# aborted:`
/// line) say which scenario and the solver's message. The run: the small kitchen (RADAU5)
/// optimised with the default step budget, then resumed (forced) with `max_steps = 2000`, with which
/// 2 of 4 fresh scenarios of designs 0 and 8 end in a free scene the budget cut short and
/// the other 2 stay (P̂ 0.5 = p_min: kept before the fix).
#[test]
fn verify_does_not_keep_a_design_whose_fresh_scenarios_the_solver_aborted() {
    let d = scratch("verify");
    let problem = d.join("small.toml");
    // with RADAU5 (the default before session 38), whose step counts the budget of 2000 cuts
    let radau5 =
        |steps: u64| set_line(&kitchen(steps, true), "max_steps", &format!("max_steps = {steps}\nmethod = \"radau5\""));
    std::fs::write(&problem, radau5(200_000)).unwrap();
    let run = d.join("run");
    let (p, r) = (problem.to_str().unwrap(), run.to_str().unwrap());
    let opt = ["optimise", p, "--out", r, "--pop", "16", "--generations", "2", "--seed", "4", "--record", "none"];
    gripopt(&opt, 0);
    std::fs::write(&problem, radau5(2000)).unwrap();
    gripopt(&["resume", r, "--generations", "3", "--force"], 0);
    let text = gripopt(&["verify", r], 0);
    let csv = std::fs::read_to_string(run.join("verify_robust.csv")).unwrap();
    let rows: Vec<Vec<&str>> =
        csv.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').collect()).collect();
    assert!(!rows.is_empty(), "{csv}");
    let mut kept_before = 0;
    for row in &rows {
        let (id, p_stay_out, keeps) = (row[0], row[4].parse::<f64>().unwrap(), row[10]);
        let said = format!("design {id} on bottle-full: ");
        let line = text.lines().find(|l| l.trim_start().starts_with(&said));
        match line {
            Some(line) => {
                assert!(line.contains("fresh scenarios aborted by the solver (first: scenario "), "{line}");
                assert!(line.contains("step budget exhausted"), "{line}");
                assert!(line.ends_with("so it does not keep"), "{line}");
                assert!(csv.contains(&format!("# aborted: {}\n", line.trim_start())), "{csv}");
                assert_eq!(keeps, "false", "{id}: {csv}");
                kept_before += usize::from(p_stay_out >= 0.5);
            }
            None => assert_eq!(keeps, if p_stay_out >= 0.5 { "true" } else { "false" }, "{id}: {csv}"),
        }
    }
    assert!(kept_before > 0, "a design whose P̂ reaches p_min despite aborted scenarios: {text}\n{csv}");
    let keep_all = rows.iter().filter(|r| r[10] == "true").count();
    assert!(text.contains(&format!("  {keep_all} of {} keep P(stay) >= p_min 0.5", rows.len())), "{text}");
}
