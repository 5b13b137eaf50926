//! Session 37 hostile pass fixes: the offset scene says why it could not start, the bench
//! names the scene it times and the stream it failed to write, `--reps`, the median and
//! `--scene`'s parsing say what they do, and `bench free --out` keeps earlier files.

use crate::common::{bottle, output_text, run_gripopt, scratch_dir, BOTTLE_FILE};
use gripopt::eval::{stage_kinematics, stage_statics, Cause};
use gripopt::model::{grasp_at, OffsetFailure};
use gripopt::params::SceneKind;
use gripopt::sim::{Controls, Integration};

/// The nominal design's verdict in the offset scene at `x_off`.
fn offset_verdict(x_off: f64) -> gripopt::eval::Verdict {
    let p = bottle();
    let integ = Integration::from_solver(&p.solver);
    let scene = gripopt::SceneChoice { kind: SceneKind::Offset, x_off: Some(x_off) };
    let p = p.in_scene(scene, std::path::Path::new("offset")).unwrap();
    let spec = gripopt::sim::SceneSpec::of(&p.scene.setup);
    let ev = gripopt::eval::simulate(&p.nominal, &p.scene, &spec, &integ, &Controls::PIPELINE, &mut ());
    assert!(ev.scene.is_some(), "stages 0–2 pass");
    gripopt::Record::from_eval(&ev).verdict
}

/// (1) Past the nominal's largest offset the static grasp at the offset does not exist (the
/// model's own `grasp_at` says which finger and why): the verdict names that failure with
/// its own cause, not "compliant static equilibrium not found". Where the grasp exists the
/// verdict is not this cause.
#[test]
fn an_offset_past_the_grasp_says_which_finger_has_no_closed_pose() {
    let p = bottle();
    let kin = stage_kinematics(&p.nominal, &p.scene).unwrap();
    let st = stage_statics(&kin.finger, &p.scene).unwrap();
    for x_off in [0.005, -0.006, 0.01] {
        let why = grasp_at(&kin.finger, &p.scene, st.tau_s0, x_off).expect_err("no grasp this far off");
        let OffsetFailure::NoClosedPose(j, e) = why else { panic!("{why:?}") };
        let v = offset_verdict(x_off);
        assert_eq!(v.failed_stage, Some(3));
        assert_eq!(v.cause, Some(Cause::NoOffsetGrasp), "{v:?}");
        assert_eq!(Cause::NoOffsetGrasp.as_str(), "no_offset_grasp");
        let reason = v.reason.unwrap();
        assert!(!reason.contains("equilibrium"), "{reason}");
        assert!(reason.contains(&format!("finger {}: {}", j + 1, e.reason())), "{reason}");
        assert!(reason.contains(&format!("x_off = {:.3} mm", x_off * 1e3)), "{reason}");
    }
    for x_off in [0.0, 0.002, 0.004] {
        assert!(grasp_at(&kin.finger, &p.scene, st.tau_s0, x_off).is_ok());
        assert_ne!(offset_verdict(x_off).cause, Some(Cause::NoOffsetGrasp));
    }
}

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
#[test]
fn work_precision_names_the_scene_it_simulates() {
    let dir = scratch_dir("s37_fixes", "work_precision_scene");
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
#[test]
fn a_bench_json_that_cannot_be_written_names_standard_output() {
    let dir = scratch_dir("s37_fixes", "bench_json_stdout");
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
#[test]
fn an_ensemble_of_two_has_a_median_below_its_p90() {
    let dir = scratch_dir("s37_fixes", "ensemble_two");
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

/// (4c) `--scene` names what is wrong with a missing or blank-padded offset instead of
/// showing an empty pair of backticks or accepting it silently.
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

/// (4d) A bench that writes over its earlier files says so (bench outputs are regenerated
/// figures and need no `--force`, docs/benchmarks.md), never silently.
#[test]
fn a_bench_rewriting_its_files_says_so() {
    let dir = scratch_dir("s37_fixes", "bench_rewrite");
    let (_, first) = work_precision_json(std::path::Path::new(BOTTLE_FILE), &dir);
    assert!(first.contains("work_precision.svg\n") && !first.contains("replacing"), "{first}");
    let (_, second) = work_precision_json(std::path::Path::new(BOTTLE_FILE), &dir);
    assert!(second.contains("work_precision.svg (replacing the earlier files of that name)"), "{second}");
}
