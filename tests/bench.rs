//! `gripopt bench`: each bench names the scene and the method it times and the stream it
//! failed to write, `--reps` is a maximum honoured, the median and the ensemble's p90 are the
//! conventional ones, a bench that rewrites its earlier files says so, and bench folders are
//! removed only when the bench made them.

use crate::common::{output_text, run_gripopt, scratch, with_solver_method, BOTTLE_FILE};
use crate::robustness::{cli, code, read, stderr, tmp, PROBLEM};

/// bottle-1l.toml with `[scene] kind = "offset"`, `x_off = 3 mm`, written into `dir`.
fn offset_problem(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let text =
        text.replacen("kind = \"centred\"", "kind = \"offset\"", 1).replacen("x_off = 0.0 ", "x_off = 0.003 ", 1);
    assert!(text.contains("kind = \"offset\"") && text.contains("x_off = 0.003 "));
    let path = dir.join("offset.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The JSON of `gripopt bench work-precision FILE --json` at one coarse rtol.
fn work_precision_json(problem: &std::path::Path, out: &std::path::Path) -> (serde_json::Value, String) {
    let args = ["bench", "work-precision", problem.to_str().unwrap(), "--out", out.to_str().unwrap()];
    let o = run_gripopt(&[&args[..], &["--reps", "1", "--rtols", "0.001", "--json"]].concat());
    assert!(o.status.success(), "{}", output_text(&o));
    (serde_json::from_slice(&o.stdout).unwrap(), String::from_utf8_lossy(&o.stderr).into())
}

/// (2) `bench work-precision` on an offset-kind problem names the scene it simulates: the
/// centred one (its rows are the centred problem's: same steps and RHS counts at every
/// method), says plainly that the problem's own scene is not it, and the whole staged
/// evaluation names the problem's scene it runs.
/// Origin: hostile pass of session 37.
#[test]
fn work_precision_names_the_scene_it_simulates() {
    let dir = scratch("work_precision_scene");
    let off = offset_problem(&dir);
    let (centred, centred_text) = work_precision_json(std::path::Path::new(BOTTLE_FILE), &dir.join("c"));
    let (offset, offset_text) = work_precision_json(&off, &dir.join("o"));
    assert_eq!(centred["scene"], "centred");
    assert_eq!(offset["scene"], "centred");
    assert_eq!(centred["problem_scene"], "centred");
    assert_eq!(offset["problem_scene"], "offset");
    assert_eq!(offset["whole_evaluation_ms"]["scene"], "offset");
    assert_eq!(offset["whole_evaluation_ms"]["x_off"], 0.003);
    let counts = |v: &serde_json::Value| -> Vec<(serde_json::Value, serde_json::Value)> {
        v["rows"].as_array().unwrap().iter().map(|r| (r["steps"].clone(), r["rhs"].clone())).collect()
    };
    assert_eq!(counts(&centred), counts(&offset), "the table is the centred grasp's in both");
    assert!(centred_text.contains("scene: centred") && !centred_text.contains("does NOT simulate"), "{centred_text}");
    assert!(offset_text.contains("this problem's scene is offset (x_off 3.000 mm), which the table does NOT simulate"));
    assert!(offset_text.contains("rtol 1e-6) in the problem's scene offset (x_off 3.000 mm): min "), "{offset_text}");
}

/// (3) A bench whose JSON cannot be written to standard output says so, as the text mode
/// and `evaluate --json` do (docs/cli.md): exit 1 and `error: cannot write to standard
/// output: …`. Standard output is a file under `ulimit -f 0` (SIGXFSZ ignored), so every
/// write to it fails (EFBIG), as on a full disk; stderr is a pipe, which the limit spares.
/// Origin: hostile pass of session 37.
#[test]
fn a_bench_json_that_cannot_be_written_names_standard_output() {
    let dir = scratch("bench_json_stdout");
    let sink = dir.join("stdout.json");
    for args in ["bench static '{BOTTLE}' --n 20 --json", "bench nsga --reps 1 --json"] {
        let script = format!(
            "trap '' XFSZ; ulimit -f 0; exec '{}' {} > '{}'",
            crate::common::GRIPOPT_BIN,
            args.replace("{BOTTLE}", BOTTLE_FILE),
            sink.display()
        );
        let o = std::process::Command::new("sh").args(["-c", &script]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args}: {err}");
        assert!(err.lines().last().unwrap().starts_with("error: cannot write to standard output: "), "{args}: {err}");
    }
}

/// (4a) `--reps N` is a maximum that is honoured: `time_it` runs `f` exactly N times for
/// N = 1 and 2 (it used to run 3), and at least three times otherwise.
/// Origin: hostile pass of session 37.
#[test]
fn reps_is_honoured_as_a_maximum() {
    for (max_reps, expected) in [(1usize, 1usize), (2, 2), (3, 3), (50, 3)] {
        let mut calls = 0;
        // a zero time budget: only the minimum number of runs
        let (last, min, med) = gripopt::bench::time_it(
            || {
                calls += 1;
                calls
            },
            0.0,
            max_reps,
        );
        assert_eq!((calls, last), (expected, expected), "max_reps {max_reps}");
        assert!(min <= med, "max_reps {max_reps}");
    }
}

/// (4b) The median of an even count is the mean of the two middle values (the conventional
/// one), not the upper one; NaNs are left out.
/// Origin: hostile pass of session 37.
#[test]
fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
    use gripopt::bench::median;
    assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), 2.5);
    assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
    assert_eq!(median(vec![5.0, f64::NAN, 1.0]), 3.0);
    assert!(median(vec![]).is_nan());
}

/// (4b) With two designs the ensemble's median error is their mean and its p90 the larger
/// (nearest rank): so median ≤ p90 ≤ 2·median in every row, and below p90 wherever the two
/// errors differ (before, the "median" was the upper value and equalled p90 in every row).
/// Origin: hostile pass of session 37.
#[test]
fn an_ensemble_of_two_has_a_median_below_its_p90() {
    let dir = scratch("ensemble_two");
    let args = ["bench", "work-precision", BOTTLE_FILE, "--sample", "2", "--json", "--out", dir.to_str().unwrap()];
    let o = run_gripopt(&args);
    assert!(o.status.success(), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut strictly_below = 0;
    for r in v["rows"].as_array().unwrap() {
        for (med, p90) in [("err_t_stab_median", "err_t_stab_p90"), ("err_e_cyl_median", "err_e_cyl_p90")] {
            let (m, p) = (r[med].as_f64().unwrap(), r[p90].as_f64().unwrap());
            assert!(m <= p && p <= 2.0 * m * (1.0 + 1e-12), "{r}");
            strictly_below += usize::from(m < p);
        }
    }
    assert!(strictly_below > 0, "{v}");
}

/// (4d) A bench that writes over its earlier files says so (bench outputs are regenerated
/// figures and need no `--force`, docs/benchmarks.md), never silently.
/// Origin: hostile pass of session 37.
#[test]
fn a_bench_rewriting_its_files_says_so() {
    let dir = scratch("bench_rewrite");
    let (_, first) = work_precision_json(std::path::Path::new(BOTTLE_FILE), &dir);
    assert!(first.contains("work_precision.svg\n") && !first.contains("replacing"), "{first}");
    let (_, second) = work_precision_json(std::path::Path::new(BOTTLE_FILE), &dir);
    assert!(second.contains("work_precision.svg (replacing the earlier files of that name)"), "{second}");
}

/// `bench work-precision`'s whole staged evaluation times the problem's own method (auto for
/// a `method = "auto"` file) but said only "rtol 1e-6": now the method in the text and in
/// `--json`'s `whole_evaluation_ms`.
/// Origin: hostile pass of session 33.
#[test]
fn bench_work_precision_names_the_method_of_its_whole_evaluation() {
    let d = scratch("bench");
    let path = with_solver_method(BOTTLE_FILE, &d, "auto.toml", "auto");
    let out = d.join("out").display().to_string();
    let args = ["bench", "work-precision", &path, "--rtols", "1e-3", "--reps", "1", "--out", &out, "--json"];
    let o = run_gripopt(&args);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["whole_evaluation_ms"]["method"], "auto", "{v}");
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(text.contains("whole staged evaluation (stages 0-3, pipeline mode, method auto, rtol 1e-6)"), "{text}");
}

/// `bench`'s count flags refuse 0 naming the flag (exit 2; `bench nsga --reps 0` ran 3,
/// `bench static --n 0` printed "NaN %"), and on a robust problem the one-design benchmarks
/// say they run the reference object only (here before a bad `--design` stops them).
/// Origin: the third hostile pass over the CLI.
#[test]
fn bench_refuses_zero_counts_and_notes_a_robust_problem() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    let out = scratch("bench-zero");
    let o = out.to_str().unwrap();
    for (args, flag) in [
        (&["bench", "nsga", "--reps", "0"][..], "--reps 0:"),
        (&["bench", "static", BOTTLE_FILE, "--n", "0"], "--n 0:"),
        (&["bench", "work-precision", BOTTLE_FILE, "--reps", "0", "--out", o], "--reps 0:"),
        (&["bench", "free", BOTTLE_FILE, "--reps", "0", "--out", o], "--reps 0:"),
    ] {
        let r = run_gripopt(args);
        let t = output_text(&r);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains(flag) && t.contains("at least 1") && !t.contains("NaN"), "{args:?}: {t}");
    }
    for bench in ["work-precision", "free"] {
        let r = run_gripopt(&["bench", bench, kitchen, "--design", "l21=nonsense", "--out", o]);
        let t = output_text(&r);
        assert_eq!(r.status.code(), Some(2), "{bench}: {t}");
        assert!(t.contains("[robust]") && t.contains("reference [object]"), "{bench}: {t}");
    }
    assert!(!out.join("work_precision.csv").exists() && !out.join("free_work_precision.csv").exists());
}

/// Issue 44 class 2: `bench replay --out DIR` removed the whole folder once its run.json
/// said "synthetic" (a user's files and whole run folders inside it were lost). Now it
/// removes only files whose content proves the benchmark wrote them; anything else refuses
/// it (exit 2, naming the file) and stays. A folder of its own is written, replayed and
/// cleared as before.
#[test]
fn bench_replay_removes_only_its_own_files() {
    let dir = tmp("i44-bench-replay");
    std::fs::create_dir_all(dir.join("a-run/recording")).unwrap();
    std::fs::write(dir.join("run.json"), r#"{"synthetic": true, "recording": {}, "problem_sha256": "x"}"#).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    std::fs::write(dir.join("a-run/run.json"), "{}").unwrap();
    let d = dir.display().to_string();
    let o = cli(&["bench", "replay", PROBLEM, "--designs", "2", "--per-shard", "1", "--out", &d]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("not written by `gripopt bench replay`"), "{}", stderr(&o));
    assert_eq!(read(&dir.join("notes.txt")), "mine");
    assert!(dir.join("a-run/run.json").is_file());
    // a folder of its own: written, replayed and removed; kept with --keep, then replaced
    let own = tmp("i44-bench-replay-own");
    let o = own.display().to_string();
    for keep in [true, true, false] {
        let mut args = vec!["bench", "replay", PROBLEM, "--designs", "2", "--per-shard", "1", "--out", &o];
        if keep {
            args.push("--keep");
        }
        let r = cli(&args);
        assert_eq!(code(&r), 0, "{}", stderr(&r));
        assert_eq!(own.exists(), keep, "keep {keep}");
    }
}

/// Issue 44 class 2: `bench scaling --out DIR` removed any folder named like `t1` in DIR.
/// Now DIR must be new or empty: what it removes afterwards is only what it made.
#[test]
fn bench_scaling_never_removes_a_folder_it_did_not_make() {
    let dir = tmp("i44-bench-scaling");
    std::fs::create_dir_all(dir.join("t1")).unwrap();
    std::fs::write(dir.join("t1/mine.txt"), "mine").unwrap();
    let d = dir.display().to_string();
    let o = cli(&[
        "bench",
        "scaling",
        PROBLEM,
        "--pop",
        "4",
        "--generations",
        "1",
        "--reps",
        "1",
        "--threads",
        "1",
        "--no-record",
        "--no-ceiling",
        "--out",
        &d,
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("holds `t1`"), "{}", stderr(&o));
    assert_eq!(read(&dir.join("t1/mine.txt")), "mine");
}
