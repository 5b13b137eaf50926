//! A third hostile-user pass over the CLI: a `verify --sample` beyond memory is refused
//! before the run folder is locked, a write that fails (a full disk, here a file-size
//! limit) leaves no partial file behind and names the file, plotted sweep keys a stage does
//! not compute are refused, a robust run's `verify` refuses the flags it cannot honour, and
//! the smaller points (numbers in warnings, `--plot x.png`, `--csv -`, a missing folder,
//! `optimise --out FILE`, `--bisect-steps 0`, `--hold-l-hand` with `--vary l_hand`); and
//! `bench`'s count flags at 0 and its note on a robust problem.

use crate::common::{output_text as text, run_gripopt as run, BOTTLE_FILE as BOTTLE, GRIPOPT_BIN};
use std::path::{Path, PathBuf};

/// A fresh scratch folder for test `name`.
fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/cli-outputs")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

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
fn verify_sample_beyond_memory_is_refused_before_the_lock() {
    let d = crate::common::tiny_run("cli-outputs-verify-sample", Path::new(BOTTLE), 8, 2);
    let ds = d.display().to_string();
    for record in ["all", "none"] {
        // the old code aborted allocating it (exit 134), leaving RUN/.lock behind
        let o = run(&["verify", &ds, "--sample", "100000000000", "--record", record]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{t}");
        assert!(t.contains("--sample") && t.contains("of memory") && t.contains("at most"), "{t}");
        assert!(!d.join(".lock").exists(), "{t}");
        assert!(!d.join("verify_sample.csv").exists());
    }
    let o = run(&["verify", &ds, "--sample", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    // hidden: --help says nothing of it
    let help = text(&run(&["verify", "--help"]));
    assert!(!help.contains("sample"), "{help}");
}

#[test]
fn a_failed_write_leaves_no_partial_file_and_names_it() {
    let d = scratch("failed-write");
    // simulate --csv and --plot: thousands of samples, beyond the limit
    for (flag, file) in [("--csv", "t.csv"), ("--plot", "p.svg")] {
        let o = run_size_limited(&d, &["simulate", BOTTLE, flag, file]);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{t}");
        assert!(t.contains(file) && t.contains("cannot write"), "{t}");
        assert!(names(&d).is_empty(), "left behind: {:?}", names(&d));
        // the retry is not blocked by a partial file
        let o = run(&["simulate", BOTTLE, flag, &d.join(file).display().to_string()]);
        assert_eq!(o.status.code(), Some(0), "{}", text(&o));
        assert!(std::fs::metadata(d.join(file)).unwrap().len() > 8 << 10);
        std::fs::remove_file(d.join(file)).unwrap();
    }
    // replay --csv of a front design (it has a recorded trajectory)
    let r = crate::common::tiny_run("cli-outputs-replay-csv", Path::new(BOTTLE), 8, 2);
    let pareto = std::fs::read_to_string(r.join("pareto.csv")).unwrap();
    let id = pareto.lines().find(|l| !l.starts_with('#') && !l.starts_with("id")).unwrap().split(',').next().unwrap();
    let rs = r.display().to_string();
    let o = run_size_limited(&d, &["replay", &rs, "--design", id, "--csv", "r.csv"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("r.csv") && t.contains("cannot write"), "{t}");
    assert!(names(&d).is_empty(), "left behind: {:?}", names(&d));
}

#[test]
fn output_files_that_cannot_be_written_as_asked_are_refused() {
    let d = scratch("refused-outputs");
    let at = |f: &str| d.join(f).display().to_string();
    // the plot is SVG: another extension is refused, nothing written
    let o = run(&["simulate", BOTTLE, "--plot", &at("x.png")]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains(".svg"), "{}", text(&o));
    // `-` is not a file name (standard output carries the report)
    let o = std::process::Command::new(GRIPOPT_BIN)
        .current_dir(&d)
        .args(["simulate", BOTTLE, "--csv", "-"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    // a folder that does not exist: bad input, not a failed run
    let o = run(&["simulate", BOTTLE, "--csv", &at("nodir/x.csv")]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("nodir") && text(&o).contains("does not exist"), "{}", text(&o));
    assert!(names(&d).is_empty(), "written: {:?}", names(&d));
    // optimise --out a file: said to be a file
    std::fs::write(d.join("afile"), "mine").unwrap();
    let o = run(&["optimise", BOTTLE, "--out", &at("afile"), "--pop", "4", "--generations", "1"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("is a file, not a folder"), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(d.join("afile")).unwrap(), "mine");
}

#[test]
fn out_of_bounds_warnings_print_numbers_compactly() {
    let design = "l21=1e300,b=0.05,t22=0.05,r=0.6,p=0.5,psi_deg=1e-300";
    let o = run(&["evaluate", BOTTLE, "--design", design, "--static-only"]);
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
    let sweep = |extra: &[&str]| run(&[&["sweep", BOTTLE, "--out", out.as_str()][..], extra].concat());
    let refused = |extra: &[&str], key: &str, listed: &str| {
        let o = sweep(extra);
        let t = text(&o);
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
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
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
        let problem = crate::common::bottle().in_scene(scene, Path::new(BOTTLE)).unwrap();
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

#[test]
fn a_robust_runs_verify_refuses_flags_it_cannot_honour() {
    let d = scratch("robust-verify");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml"), d.join("problem.toml")).unwrap();
    let ds = d.display().to_string();
    for flags in [&["--all"][..], &["--scene", "free:0.001"], &["--scene", "free"], &["--record", "all"]] {
        let o = run(&[&["verify", ds.as_str()][..], flags].concat());
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {t}");
        assert!(t.contains(flags[0]) && t.contains("robust run"), "{flags:?}: {t}");
    }
}

/// `bench`'s count flags refuse 0 naming the flag (exit 2; `bench nsga --reps 0` ran 3,
/// `bench static --n 0` printed "NaN %"), and on a robust problem the one-design benchmarks
/// say they run the reference object only (here before a bad `--design` stops them).
#[test]
fn bench_refuses_zero_counts_and_notes_a_robust_problem() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    let out = scratch("bench-zero");
    let o = out.to_str().unwrap();
    for (args, flag) in [
        (&["bench", "nsga", "--reps", "0"][..], "--reps 0:"),
        (&["bench", "static", BOTTLE, "--n", "0"], "--n 0:"),
        (&["bench", "work-precision", BOTTLE, "--reps", "0", "--out", o], "--reps 0:"),
        (&["bench", "free", BOTTLE, "--reps", "0", "--out", o], "--reps 0:"),
    ] {
        let r = run(args);
        let t = text(&r);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains(flag) && t.contains("at least 1") && !t.contains("NaN"), "{args:?}: {t}");
    }
    for bench in ["work-precision", "free"] {
        let r = run(&["bench", bench, kitchen, "--design", "l21=nonsense", "--out", o]);
        let t = text(&r);
        assert_eq!(r.status.code(), Some(2), "{bench}: {t}");
        assert!(t.contains("[robust]") && t.contains("reference [object]"), "{bench}: {t}");
    }
    assert!(!out.join("work_precision.csv").exists() && !out.join("free_work_precision.csv").exists());
}
