//! `gripopt verify` of a robust run: the front's designs on fresh scenarios of every object
//! (docs/robust.md). A scenario the solver aborted is no "did not stay", a run without a
//! feasible design lists its discards, and flags a robust verify cannot honour are refused.

use crate::common::{gripopt_exits, kitchen_with_max_steps, output_text, run_gripopt, scratch, set_line};
use crate::robust::{tmp, BOTTLE};
use std::path::Path;

/// A front design whose fresh (out-of-sample) scenarios the solver aborted does not keep
/// P(stay) ≥ p_min on that object, even where its P̂ (which counts the aborted scenarios as
/// not staying) reaches p_min, and verify's report and verify_robust.csv (a `# aborted:`
/// line) say which scenario and the solver's message. The run: the small kitchen (RADAU5)
/// optimised with the default step budget, then resumed (forced) with `max_steps = 2000`, with which
/// 2 of 4 fresh scenarios of designs 0 and 8 end in a free scene the budget cut short and
/// the other 2 stay (P̂ 0.5 = p_min: kept before the fix).
/// Origin: hostile pass of session 34, replay and verify of robust designs the solver aborted.
#[test]
fn verify_does_not_keep_a_design_whose_fresh_scenarios_the_solver_aborted() {
    let d = scratch("verify");
    let problem = d.join("small.toml");
    // with RADAU5 (the default before session 38), whose step counts the budget of 2000 cuts
    let radau5 = |steps: u64| {
        set_line(kitchen_with_max_steps(steps, true), "max_steps", &format!("max_steps = {steps}\nmethod = \"radau5\""))
    };
    std::fs::write(&problem, radau5(200_000)).unwrap();
    let run = d.join("run");
    let (p, r) = (problem.to_str().unwrap(), run.to_str().unwrap());
    let opt = ["optimise", p, "--out", r, "--pop", "16", "--generations", "2", "--seed", "4", "--record", "none"];
    gripopt_exits(&opt, 0);
    std::fs::write(&problem, radau5(2000)).unwrap();
    gripopt_exits(&["resume", r, "--generations", "3", "--force"], 0);
    let text = gripopt_exits(&["verify", r], 0);
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

/// `verify` on a robust run without a feasible design says why, as for a single-object run
/// (docs/cli.md: the discard causes), not only that there is nothing to verify.
/// Origin: hostile pass 32b.
#[test]
fn verify_of_a_robust_run_without_a_feasible_design_lists_the_discards() {
    let dir = tmp("verify-none-feasible");
    let _ = std::fs::remove_dir_all(&dir);
    let kitchen = Path::new(BOTTLE).with_file_name("kitchen.toml");
    let run = |args: &[&str]| crate::robustness::cli(args);
    let d = dir.display().to_string();
    let k = kitchen.display().to_string();
    let o = run(&["optimise", &k, "--out", &d, "--pop", "8", "--generations", "1", "--seed", "1", "--threads", "1"]);
    assert_eq!(crate::robustness::code(&o), 0, "{}", crate::robustness::stderr(&o));
    let shown: serde_json::Value = serde_json::from_slice(&run(&["show", &d, "--json"]).stdout).unwrap();
    assert!(shown["no_feasible_design"].is_array(), "the run has a feasible design: {shown}");
    let o = run(&["verify", &d]);
    let e = crate::robustness::stderr(&o);
    assert_eq!(crate::robustness::code(&o), 2, "{e}");
    assert!(e.contains("nothing written") && e.contains("were discarded") && e.contains("at stage"), "{e}");
    assert!(!dir.join("verify_robust.csv").exists());
}

/// Origin: the third hostile pass over the CLI.
#[test]
fn a_robust_runs_verify_refuses_flags_it_cannot_honour() {
    let d = scratch("robust-verify");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml"), d.join("problem.toml")).unwrap();
    let ds = d.display().to_string();
    for flags in [&["--all"][..], &["--scene", "free:0.001"], &["--scene", "free"], &["--record", "all"]] {
        let o = run_gripopt(&[&["verify", ds.as_str()][..], flags].concat());
        let t = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {t}");
        assert!(t.contains(flags[0]) && t.contains("robust run"), "{flags:?}: {t}");
    }
}
