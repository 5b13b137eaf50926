//! Hostile pass 34 (docs/cli.md "Hostile pass 34"): the command-line defects a new user ran
//! into that the CLI itself answers. Each test fails without its fix.

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};

fn json_stdout(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", output_text(o)))
}

/// A seed range too long to hold was an allocation failure (SIGABRT, exit 134, no JSON):
/// now exit 2 with the JSON error naming the flag and the limit.
#[test]
fn a_huge_seed_range_is_bad_input_not_an_abort() {
    let o =
        run_gripopt(&["moo-test", "zdt1", "--seeds", "1-10000000000", "--pop", "4", "--generations", "1", "--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    let e = json_stdout(&o)["error"].as_str().unwrap().to_string();
    assert!(e.contains("--seeds") && e.contains("at most 100000"), "{e}");
}

/// The text report counts the seeds it ran ("1 seed", "2 seeds"), not "seeds  1".
#[test]
fn moo_test_says_how_many_seeds_it_ran() {
    let text = |seeds: &str| {
        let o = run_gripopt(&["moo-test", "zdt1", "--seeds", seeds, "--pop", "8", "--generations", "2"]);
        output_text(&o)
    };
    assert!(text("3-3").contains(" 1 seed: HV median"), "{}", text("3-3"));
    assert!(text("3-4").contains(" 2 seeds: HV median"), "{}", text("3-4"));
}

/// A usage error under `--json` kept only clap's first line ("the following required
/// arguments were not provided:"), not which argument.
#[test]
fn a_json_usage_error_names_what_is_missing_or_wrong() {
    let error = |args: &[&str]| {
        let o = run_gripopt(args);
        assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
        json_stdout(&o)["error"].as_str().unwrap().to_string()
    };
    assert_eq!(error(&["moo-test", "--json"]), "the following required arguments were not provided: <NAME>");
    assert_eq!(
        error(&["optimise", "--json"]),
        "the following required arguments were not provided: --out <OUT>, <PROBLEM>"
    );
    let bad = error(&["simulate", BOTTLE_FILE, "--json", "--method", "foo"]);
    assert!(bad.contains("'foo'") && bad.contains("--method") && bad.contains("auto"), "{bad}");
}

/// Range errors name the admissible range on both sides and write no unit for a
/// dimensionless quantity (was "must be <= 0.1 - (…)" and, below, no range at all).
#[test]
fn range_errors_give_the_range_and_a_unit_only_where_there_is_one() {
    let stderr = |args: &[&str]| {
        let o = run_gripopt(args);
        assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let high = stderr(&["simulate", BOTTLE_FILE, "--rtol", "0.2"]);
    assert!(high.contains("--rtol 0.2: must be <= 0.1 (the admissible range is [1e-12, 0.1])"), "{high}");
    let low = stderr(&["simulate", BOTTLE_FILE, "--rtol", "1e-13"]);
    assert!(low.contains("--rtol 1e-13: must be >= 1e-12 (the admissible range is [1e-12, 0.1])"), "{low}");
    let tau = gripopt::params::limit("hand.tau").check(500.0).unwrap_err();
    assert_eq!(tau, "must be <= 100 N·m (the admissible range is (0, 100] N·m)");
    let mu = gripopt::params::limit("contact.mu_s").check(0.0).unwrap_err();
    assert_eq!(mu, "must be > 0 (the admissible range is (0, 5])");
}

/// TR-BDF2 below atol 1e-11 collapsed its steps (1e-15: "step size underflow" at t = 0) or ran
/// for millions of steps (1e-13, the offset scene): the problem file refuses it, naming
/// `solver.atol` and the method; 1e-11 is taken.
#[test]
fn tr_bdf2_needs_an_atol_its_error_estimate_can_meet() {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-cli"));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    for (atol, code) in [("1e-12", 2), ("1e-11", 0)] {
        let file = dir.join(format!("trbdf2-{atol}.toml"));
        let solver = "\n[solver]\nmethod = \"trbdf2\"\n";
        let edited = text.replacen("\n[solver]\n", solver, 1).replacen("atol = 1e-9", &format!("atol = {atol}"), 1);
        assert!(edited.contains(&format!("atol = {atol}")), "bottle-1l.toml's atol is 1e-9");
        std::fs::write(&file, edited).unwrap();
        let o = run_gripopt(&["evaluate", file.to_str().unwrap(), "--static-only"]);
        assert_eq!(o.status.code(), Some(code), "{atol}: {}", output_text(&o));
        if code == 2 {
            let e = output_text(&o);
            assert!(e.contains("solver.atol") && e.contains(">= 1e-11") && e.contains("trbdf2"), "{e}");
        }
    }
}

/// `simulate --method trbdf2` on a problem written for RADAU5 at atol 1e-13 is refused as
/// the file would be (exit 2, naming the flag, solver.atol and the floor).
#[test]
fn simulate_method_tr_bdf2_checks_the_files_atol() {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-cli"));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("atol = 1e-9", "atol = 1e-13", 1);
    let file = dir.join("radau5-1e-13.toml");
    std::fs::write(&file, text).unwrap();
    let o = run_gripopt(&["simulate", file.to_str().unwrap(), "--method", "trbdf2"]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--method trbdf2") && e.contains("solver.atol 1e-13") && e.contains(">= 1e-11"), "{e}");
}

/// "aborted: step budget exhausted" did not say which setting ran out: the text report names
/// `solver.max_steps` and its value; the record's reason (`--json`, which replay compares)
/// stays the simulator's.
#[test]
fn a_step_budget_discard_names_solver_max_steps_in_the_text() {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-cli"));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let file = dir.join("max-steps-50.toml");
    let edited = text.replacen("max_steps = 200000", "max_steps = 50", 1);
    assert!(edited.contains("max_steps = 50"), "bottle-1l.toml's max_steps is 200000");
    std::fs::write(&file, edited).unwrap();
    let f = file.to_str().unwrap();
    let o = run_gripopt(&["simulate", f]);
    let said = output_text(&o);
    assert!(
        said.contains("step budget exhausted (solver.max_steps = 50; the problem file's [solver] raises it)"),
        "{said}"
    );
    let v = json_stdout(&run_gripopt(&["simulate", f, "--json"]));
    assert_eq!(v["reason"], "aborted: step budget exhausted", "{v}");
}

/// `export --format mjcf --out hand.json` wrote XML under a `.json` name: a format that an
/// extension contradicts is refused naming both; a name whose extension says nothing, or
/// agrees, is written.
#[test]
fn export_refuses_a_format_its_file_name_contradicts() {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-cli/export"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = |name: &str| dir.join(name).display().to_string();
    let o = run_gripopt(&["export", BOTTLE_FILE, "--format", "mjcf", "--out", &out("hand.json")]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("hand.json") && e.contains("says json") && e.contains("--format is mjcf"), "{e}");
    assert!(!dir.join("hand.json").exists());
    for (format, name) in [("mjcf", "hand.xml"), ("mjcf", "hand.model"), ("json", "sheet.json"), ("csv", "sheet.csv")] {
        let o = run_gripopt(&["export", BOTTLE_FILE, "--format", format, "--out", &out(name)]);
        assert_eq!(o.status.code(), Some(0), "{format} {name}: {}", output_text(&o));
        assert!(dir.join(name).exists(), "{name}");
    }
}

/// `--object ''` read `--object : kitchen.toml: no such robust object`: a name that reads as
/// nothing (empty, blanks) is quoted; a plain one is not.
#[test]
fn an_object_name_that_reads_as_nothing_is_quoted() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    for (name, shown) in [("", "--object \"\":"), ("can ", "--object \"can \":"), ("mug", "--object mug:")] {
        let o = run_gripopt(&["simulate", kitchen, "--object", name]);
        let e = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(e.contains(shown) && e.contains("no such robust object"), "{name:?}: {e}");
    }
}

/// `--json=yes` (a flag given a value) printed clap's refusal on stderr only: it asked for
/// JSON, so the refusal is the JSON object too.
#[test]
fn a_json_flag_given_a_value_still_gets_a_json_refusal() {
    let o = run_gripopt(&["evaluate", BOTTLE_FILE, "--json=yes"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    let e = json_stdout(&o)["error"].as_str().unwrap().to_string();
    assert!(e.contains("--json"), "{e}");
}

/// The discard summaries of `optimise` and `show` ("12 % at stage 3 by aborted (1 design):
/// aborted: step budget exhausted; …") name `solver.max_steps` as `evaluate` does; `--json`
/// keeps the run's own text.
#[test]
fn discard_summaries_name_solver_max_steps() {
    let dir = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile34-cli/summaries"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("max-steps-60.toml");
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("max_steps = 200000", "max_steps = 60", 1);
    std::fs::write(&file, text).unwrap();
    let run = dir.join("run").display().to_string();
    let args = ["optimise", file.to_str().unwrap(), "--out", &run, "--pop", "8", "--generations", "1", "--seed", "1"];
    let hint = "step budget exhausted (solver.max_steps = 60; the problem file's [solver] raises it)";
    let o = run_gripopt(&[&args[..], &["--record", "none"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(output_text(&o).contains(hint), "{}", output_text(&o));
    let o = run_gripopt(&["show", &run]);
    assert!(output_text(&o).contains(hint), "{}", output_text(&o));
    let v = json_stdout(&run_gripopt(&["show", &run, "--json"]));
    let lines = v["no_feasible_design"].as_array().expect("no feasible design at max_steps 60");
    assert!(lines.iter().any(|l| l.as_str().unwrap().contains("step budget exhausted;")), "{v}");
}

/// `simulate --json --rtol R` did not carry R: it does, and a run at the problem's rtol
/// prints the record as before (no `rtol` key).
#[test]
fn simulate_json_names_an_rtol_set_on_the_command_line() {
    let v = json_stdout(&run_gripopt(&["simulate", BOTTLE_FILE, "--json", "--rtol", "1e-5"]));
    assert_eq!(v["rtol"].as_f64(), Some(1e-5), "{v}");
    let v = json_stdout(&run_gripopt(&["simulate", BOTTLE_FILE, "--json"]));
    assert!(v.get("rtol").is_none(), "{v}");
}
