//! Hostile pass 35 on the CLI: `sweep --vary` of a `[scene]` field the problem's scene kind
//! does not simulate, `show --design` of an id the run never had, `optimise --out` inside
//! another run's folder.

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch_dir("s35-cli-runs", name)
}

/// bottle-1l with `[scene] kind` replaced, written into `dir`.
fn bottle_of_kind(dir: &Path, kind: &str) -> PathBuf {
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let text = text.replacen("kind = \"centred\"", &format!("kind = \"{kind}\""), 1);
    assert!(text.contains(&format!("kind = \"{kind}\"")));
    let p = dir.join(format!("bottle-{kind}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// A tiny run (population 4, one generation: ids 0 to 3) in `dir`.
fn tiny_run(dir: &Path) -> PathBuf {
    let run = dir.join("run");
    let o = run_gripopt(&["optimise", BOTTLE_FILE, "--out", run.to_str().unwrap(), "--pop", "4", "--generations", "1"]);
    assert!(o.status.success(), "{}", output_text(&o));
    run
}

/// `sweep --vary scene.x_off` on a centred problem varied nothing (every row the same, the
/// record's x_off 0 beside a varied column of ±2 mm); so did the ground's fields and t_obs
/// outside the free scene. Refused (exit 2, nothing written) naming the field and the kind.
#[test]
fn sweep_refuses_a_scene_field_the_scene_kind_does_not_simulate() {
    let d = scratch("sweep");
    let offset = bottle_of_kind(&d, "offset");
    let cases = [
        (BOTTLE_FILE.to_string(), "scene.x_off=-0.002:0.002:3", "scene.x_off", "centred"),
        (BOTTLE_FILE.to_string(), "x_off=0:0.002:2", "scene.x_off", "centred"),
        (BOTTLE_FILE.to_string(), "scene.ground_points=3:5:3", "scene.ground_points", "centred"),
        (BOTTLE_FILE.to_string(), "ground_k=1e8:2e8:2", "scene.ground_k", "centred"),
        (offset.display().to_string(), "scene.t_obs=0.05:0.1:2", "scene.t_obs", "offset"),
        (offset.display().to_string(), "scene.ground_v_d=3e-4:4e-4:2", "scene.ground_v_d", "offset"),
    ];
    for (problem, vary, field, kind) in cases {
        let out = d.join("out");
        let o =
            run_gripopt(&["sweep", &problem, "--vary", vary, "--stage", "kinematics", "--out", out.to_str().unwrap()]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{vary}: {text}");
        assert!(text.contains(field) && text.contains(&format!("scene kind \"{kind}\"")), "{vary}: {text}");
        assert!(!out.exists(), "{vary}: nothing written");
    }
    // the offset scene uses x_off: swept (a warning says a static sweep stops before it)
    let out = d.join("ok");
    let o = run_gripopt(&[
        "sweep",
        offset.to_str().unwrap(),
        "--vary",
        "scene.x_off=0:0.002:2",
        "--stage",
        "static",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = output_text(&o);
    assert!(o.status.success() && out.join("sweep.csv").exists(), "{text}");
    assert!(text.contains("warning: --vary scene.x_off: only stage 3"), "{text}");
}

/// `show RUN --design 999` (the run's ids are 0 to 3) suggested `gripopt replay RUN --design
/// 999`, which fails: it now says the id range, and suggests replay only for an id the run has.
#[test]
fn show_names_the_id_range_for_an_id_the_run_never_had() {
    let d = scratch("show");
    let run = tiny_run(&d);
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

/// `optimise --out RUN/recording/sub` (or `RUN/sub`) created a run inside another run's
/// folder; refused (exit 2) like export and sweep refuse to write into a run folder, with
/// nothing created.
#[test]
fn optimise_refuses_a_run_inside_another_runs_folder() {
    let d = scratch("nested");
    let run = tiny_run(&d);
    for sub in ["recording/sub", "sub", "sub/deeper"] {
        let out = run.join(sub);
        let o =
            run_gripopt(&["optimise", BOTTLE_FILE, "--out", out.to_str().unwrap(), "--pop", "4", "--generations", "1"]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{sub}: {text}");
        assert!(text.contains("inside the run folder") && text.contains("holds run.json"), "{sub}: {text}");
        assert!(!out.exists() && !run.join("sub").exists(), "{sub}: nothing created");
    }
    // beside the run: a new run as before
    let o = run_gripopt(&[
        "optimise",
        BOTTLE_FILE,
        "--out",
        d.join("other").to_str().unwrap(),
        "--pop",
        "4",
        "--generations",
        "1",
    ]);
    assert!(o.status.success(), "{}", output_text(&o));
}

/// The library refuses it too (Python's `optimise` and any Rust caller go through
/// `run::optimise`, not the CLI's check): nothing is created inside the run.
#[test]
fn the_library_refuses_a_run_inside_another_runs_folder() {
    let d = scratch("nested-lib");
    let run = tiny_run(&d);
    let out = run.join("recording").join("sub");
    let spec = gripopt::run::RunSpec {
        problem_path: PathBuf::from(BOTTLE_FILE),
        out: out.clone(),
        pop: 4,
        generations: 1,
        seed: 1,
        threads: Some(1),
        record: gripopt::record::RecordOptions::default(),
    };
    let e = gripopt::run::optimise(&spec).unwrap_err().to_string();
    assert!(e.contains("inside the run folder") && e.contains("holds run.json"), "{e}");
    assert!(!out.exists());
}

/// `verify` of a run whose problem.toml was deleted says that file is missing (run.json is
/// there), not "not a run folder".
#[test]
fn verify_names_a_missing_problem_toml() {
    let d = scratch("verify-no-problem");
    let run = tiny_run(&d);
    std::fs::remove_file(run.join("problem.toml")).unwrap();
    let o = run_gripopt(&["verify", run.to_str().unwrap(), "--record", "none"]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("problem.toml is missing from the run folder (run.json is there)"), "{text}");
}
