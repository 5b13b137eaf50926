//! What the CLI writes and says: a write that fails (a full disk, here a file-size limit)
//! leaves no partial file behind and names the file, plotted sweep keys a stage does not
//! compute are refused, the smaller points (numbers in warnings, `--plot x.png`, `--csv -`, a
//! missing folder, `optimise --out FILE`, `--bisect-steps 0`, `--hold-l-hand` with `--vary
//! l_hand`), `show`'s id range, the step budget named in discard texts and summaries, and a
//! criterion never checked reported as null. The tests of the third hostile pass over the
//! CLI carry no origin line; the later regression tests do.

use crate::common::{cli_tiny_run, json_of, json_stdout, output_text, run_gripopt, scratch, BOTTLE_FILE, GRIPOPT_BIN};
use std::path::Path;

/// Run gripopt in `dir` under a file-size limit of 8 blocks (4–8 KiB, as a full disk would
/// stop it; SIGXFSZ ignored so that the write fails with EFBIG instead of killing it).
fn run_size_limited(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new("sh")
        .current_dir(dir)
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 8; exec \"$0\" \"$@\"")
        .arg(GRIPOPT_BIN)
        .args(args)
        .output()
        .unwrap()
}

/// The files of `dir` (temporary files included).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn a_failed_write_leaves_no_partial_file_and_names_it() {
    let d = scratch("failed-write");
    // simulate --csv and --plot: thousands of samples, beyond the limit
    for (flag, file) in [("--csv", "t.csv"), ("--plot", "p.svg")] {
        let o = run_size_limited(&d, &["simulate", BOTTLE_FILE, flag, file]);
        let t = output_text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(t.contains(file) && t.contains("cannot write"), "{t}");
        assert!(names(&d).is_empty(), "left behind: {:?}", names(&d));
        // the retry is not blocked by a partial file
        let o = run_gripopt(&["simulate", BOTTLE_FILE, flag, &d.join(file).display().to_string()]);
        assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
        assert!(std::fs::metadata(d.join(file)).unwrap().len() > 8 << 10);
        std::fs::remove_file(d.join(file)).unwrap();
    }
    // replay --csv of a front design (it has a recorded trajectory)
    let r = crate::common::tiny_run("cli-outputs-replay-csv", Path::new(BOTTLE_FILE), 8, 2);
    let pareto = std::fs::read_to_string(r.join("pareto.csv")).unwrap();
    let id = pareto.lines().find(|l| !l.starts_with('#') && !l.starts_with("id")).unwrap().split(',').next().unwrap();
    let rs = r.display().to_string();
    let o = run_size_limited(&d, &["replay", &rs, "--design", id, "--csv", "r.csv"]);
    let t = output_text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("r.csv") && t.contains("cannot write"), "{t}");
    assert!(names(&d).is_empty(), "left behind: {:?}", names(&d));
}

#[test]
fn output_files_that_cannot_be_written_as_asked_are_refused() {
    let d = scratch("refused-outputs");
    let at = |f: &str| d.join(f).display().to_string();
    // the plot is SVG: another extension is refused, nothing written
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--plot", &at("x.png")]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains(".svg"), "{}", output_text(&o));
    // `-` is not a file name (standard output carries the report)
    let o = std::process::Command::new(GRIPOPT_BIN)
        .current_dir(&d)
        .args(["simulate", BOTTLE_FILE, "--csv", "-"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    // a folder that does not exist: bad input, not a failed run
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--csv", &at("nodir/x.csv")]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("nodir") && output_text(&o).contains("does not exist"), "{}", output_text(&o));
    assert!(names(&d).is_empty(), "written: {:?}", names(&d));
    // optimise --out a file: said to be a file
    std::fs::write(d.join("afile"), "mine").unwrap();
    let o = run_gripopt(&["optimise", BOTTLE_FILE, "--out", &at("afile"), "--pop", "4", "--generations", "1"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("is a file, not a folder"), "{}", output_text(&o));
    assert_eq!(std::fs::read_to_string(d.join("afile")).unwrap(), "mine");
}

#[test]
fn out_of_bounds_warnings_print_numbers_compactly() {
    let design = "l21=1e300,b=0.05,t22=0.05,r=0.6,p=0.5,psi_deg=1e-300";
    let o = run_gripopt(&["evaluate", BOTTLE_FILE, "--design", design, "--static-only"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(err.contains("l21 = 1e300 is outside"), "{err}");
    assert!(err.contains("psi_deg = 1e-300 is outside"), "{err}");
    assert!(err.lines().all(|l| l.len() < 200), "{err}");
    // the report too: the design and its lengths in scientific notation, not 300 digits
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(out.contains("design l21=1e300 "), "{out}");
    assert!(out.lines().all(|l| l.len() < 200), "{out}");
}

#[test]
fn sweep_plot_keys_must_be_computed_by_the_stage() {
    let d = scratch("sweep-keys");
    let out = d.join("s").display().to_string();
    let sweep = |extra: &[&str]| run_gripopt(&[&["sweep", BOTTLE_FILE, "--out", out.as_str()][..], extra].concat());
    let refused = |extra: &[&str], key: &str, listed: &str| {
        let o = sweep(extra);
        let t = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {t}");
        assert!(t.contains(key) && t.contains(listed), "{extra:?}: {t}");
        assert!(!d.join("s").exists(), "{extra:?}: a sweep ran");
    };
    let one = ["--vary", "l21=0.04:0.05:2"];
    let two = ["--vary", "l21=0.04:0.05:2", "--vary", "b=0.06:0.07:2"];
    refused(&[&one[..], &["--y", "nope"]].concat(), "`nope`", "t_stab");
    refused(&[&one[..], &["--y", "e_cyl+nope"]].concat(), "`nope`", "e_lim");
    refused(&[&two[..], &["--color", "tstab"]].concat(), "`tstab`", "t_stab");
    // a key the stage does not compute, with the keys it does
    refused(&[&one[..], &["--stage", "kinematics", "--y", "t_stab"]].concat(), "`t_stab`", "min_margin_deg");
    refused(&[&one[..], &["--stage", "static", "--y", "e_cyl"]].concat(), "`e_cyl`", "mean_force");
    // a flag for plots this grid does not draw
    refused(&[&one[..], &["--color", "alpha"]].concat(), "--color", "line plots");
    refused(&[&two[..], &["--y", "alpha"]].concat(), "--y", "maps");
    // bisection and l_hand
    refused(&[&one[..], &["--bisect", "l21", "--bisect-steps", "0"]].concat(), "--bisect-steps 0", "1 to 60");
    refused(&[&one[..], &["--bisect-steps", "5"]].concat(), "--bisect-steps 5", "--bisect");
    refused(&["--vary", "l_hand=0.2:0.24:2", "--hold-l-hand"], "--hold-l-hand", "l_hand");
    refused(&["--vary", "t22=0.03:0.04:2", "--hold-l-hand"], "--hold-l-hand", "t22");
    refused(&["--vary", "tau=0.3:0.4:2", "--hold-l-hand"], "--hold-l-hand", "neither");
    // a key the stage computes is plotted
    let o = sweep(&[&one[..], &["--stage", "kinematics", "--y", "min_margin_deg"]].concat());
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(d.join("s/line_min_margin_deg.svg").is_file());
}

/// The keys `--y` and `--color` accept are those the stage's evaluation fills: every
/// numeric cell of a real row of each stage (and scene) is accepted (the nominal reaches
/// every stage), and every accepted key is a column of a row of that stage; the default
/// plots' keys are among them.
#[test]
fn plot_keys_are_the_numeric_cells_each_stage_fills() {
    use gripopt::params::SceneKind;
    use gripopt::sweep::{eval_row, out::plot_keys, Stage, SweepSpec, Vary};
    let cases = [
        (Stage::Kinematics, SceneKind::Centred, &["min_margin_deg"][..]),
        (Stage::Static, SceneKind::Centred, &["alpha", "mean_force", "max_offset"][..]),
        (Stage::Dynamic, SceneKind::Centred, &["e_cyl", "e_lim", "t_stab"][..]),
        (Stage::Dynamic, SceneKind::Free, &["free_scene.object_max_displacement"][..]),
    ];
    for (stage, kind, defaults) in cases {
        let scene = gripopt::SceneChoice { kind, x_off: None };
        let problem = crate::common::bottle().in_scene(scene, Path::new(BOTTLE_FILE)).unwrap();
        let vary = vec![Vary::parse("tau=0.35:0.35:1").unwrap()];
        let spec = SweepSpec { design: problem.nominal, problem, vary, stage, hold_l_hand: false, psi_rule: false };
        let keys = plot_keys(&spec);
        let row = eval_row(&spec, &[spec.problem.scene.hand.tau]).unwrap();
        let reached = match stage {
            Stage::Kinematics => "min_margin_deg",
            Stage::Static => "alpha",
            Stage::Dynamic => "e_cyl",
        };
        assert!(row.num(reached).is_some(), "{stage:?} {kind:?}: not reached: {:?}", row.cells);
        let mut numeric = 0;
        for (k, v) in &row.cells {
            if v.parse::<f64>().is_ok() {
                numeric += 1;
                assert!(keys.contains(k), "{stage:?} {kind:?}: numeric cell {k} = {v} not accepted");
            }
        }
        assert!(numeric > 10, "{stage:?}: {numeric}");
        for k in &keys {
            assert!(row.cells.iter().any(|(c, _)| c == k), "{stage:?} {kind:?}: {k} accepted but not a column");
        }
        for k in defaults {
            assert!(keys.iter().any(|x| x == k), "{stage:?} {kind:?}: {k} missing from {keys:?}");
        }
        if stage != Stage::Dynamic {
            assert!(!keys.iter().any(|k| k == "t_stab" || k == "e_cyl"), "{stage:?}: {keys:?}");
        }
    }
}

/// `show RUN --design 999` (the run's ids are 0 to 3) suggested `gripopt replay RUN --design
/// 999`, which fails: it now says the id range, and suggests replay only for an id the run has.
/// Origin: hostile pass of session 35 on the CLI.
#[test]
fn show_names_the_id_range_for_an_id_the_run_never_had() {
    let d = scratch("show");
    let run = cli_tiny_run(&d);
    let r = run.to_str().unwrap();
    for id in ["999", "4"] {
        let o = run_gripopt(&["show", r, "--design", id]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{text}");
        assert!(text.contains(&format!("has no design {id}: its ids are 0 to 3")), "{text}");
        assert!(!text.contains("replay"), "no replay suggested: {text}");
        // and replay agrees that the run has no such design
        assert_ne!(run_gripopt(&["replay", r, "--design", id]).status.code(), Some(0));
    }
    // an id the run has: shown, its replay command works
    let o = run_gripopt(&["show", r, "--design", "3"]);
    assert!(o.status.success(), "{}", output_text(&o));
    assert!(run_gripopt(&["replay", r, "--design", "3"]).status.success());
}

/// "aborted: step budget exhausted" did not say which setting ran out: the text report names
/// `solver.max_steps` and its value; the record's reason (`--json`, which replay compares)
/// stays the simulator's.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn a_step_budget_discard_names_solver_max_steps_in_the_text() {
    let dir = scratch("max-steps-50");
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

/// The discard summaries of `optimise` and `show` ("12 % at stage 3 by aborted (1 design):
/// aborted: step budget exhausted; …") name `solver.max_steps` as `evaluate` does; `--json`
/// keeps the run's own text.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn discard_summaries_name_solver_max_steps() {
    let dir = scratch("summaries");
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

/// A pipeline evaluation that stops at the first impact never watches the hand force: its
/// `force_ok` is null (it said `true`), while `simulate`, which runs on, finds the force
/// criterion failing (a negative margin) for the same design.
/// Origin: session 36's numerics review.
#[test]
fn a_force_criterion_never_checked_is_null() {
    let design = "l21=0.04103939773437472,b=0.05002286401733649,t22=0.03245362484540232,r=0.7485046506912487,p=0.9171893488299596,psi_deg=112.6123374607984";
    let ev = json_of(&["evaluate", BOTTLE_FILE, "--design", design, "--json"]);
    assert_eq!(ev["cause"], "impact", "{ev}");
    assert!(ev["force_ok"].is_null() && ev["min_force_margin"].is_null(), "{ev}");
    let sim = json_of(&["simulate", BOTTLE_FILE, "--design", design, "--json"]);
    assert!(sim["min_force_margin"].as_f64().unwrap() < 0.0, "{sim}");
    assert_eq!(sim["force_ok"], false, "{sim}");
    // the nominal design's diagnostic grasp: watched to the end, and it holds
    let nominal = json_of(&["simulate", BOTTLE_FILE, "--json"]);
    assert!(nominal["min_force_margin"].as_f64().unwrap() >= 0.0 && nominal["force_ok"] == true, "{nominal}");
}
