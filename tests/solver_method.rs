//! A problem file's `[solver] method`: the integration method of every grasp simulation of
//! the problem (evaluate, optimise, simulate's default), RADAU5 when the key is absent (the
//! same records as before the key existed), an unknown value refused naming the file and the
//! field, and a run whose problem file's method was edited refused on resume.

use crate::common::{nominal, output_text, run_gripopt, untimed, BOTTLE_FILE};
use gripopt::eval::{evaluate, EvalOptions, Record};
use gripopt::params::Problem;
use gripopt::sim::{Integration, Method};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/solver-method")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// bottle-1l.toml with `rtol = RTOL` and, when given, `method = METHOD` in `[solver]`,
/// written to `dir/name`.
fn bottle_with(dir: &Path, name: &str, rtol: &str, method: Option<&str>) -> PathBuf {
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    assert!(text.contains("\n[solver]\nrtol = 1e-6\n"), "bottle-1l.toml's [solver] starts with rtol = 1e-6");
    let mut solver = format!("\n[solver]\nrtol = {rtol}\n");
    if let Some(m) = method {
        solver.push_str(&format!("method = \"{m}\"\n"));
    }
    let path = dir.join(name);
    std::fs::write(&path, text.replace("\n[solver]\nrtol = 1e-6\n", &solver)).unwrap();
    path
}

/// The record as JSON without its CPU times (the only values that differ between two runs).
fn untimed_record(r: &Record) -> serde_json::Value {
    untimed(serde_json::to_value(r).unwrap())
}

/// The nominal design's pipeline record under `p`'s own settings, and under them with the
/// method `m` set explicitly (not through the problem file).
fn records(p: &Problem, m: Method) -> (Record, Record) {
    let own = Record::from_eval(&evaluate(&nominal(), &p.scene, &EvalOptions::full(p)));
    let s = &p.solver;
    let explicit = EvalOptions::pipeline(Integration::new(s.rtol, s.atol, s.max_steps).with_method(m));
    (own, Record::from_eval(&evaluate(&nominal(), &p.scene, &explicit)))
}

/// `method = "auto"` simulates the problem's grasps with the switching method: the record
/// is the one of an explicit `Method::Auto` integration, its work differs from RADAU5's
/// (explicit steps, fewer Jacobians), and at rtol 1e-7 its verdict is RADAU5's (the violation,
/// the impact energy, within 1e-5; the methods' ensemble error is ~1e-7).
#[test]
fn method_auto_evaluates_with_the_switching_method() {
    let d = scratch("auto");
    let auto = Problem::load(bottle_with(&d, "auto.toml", "1e-7", Some("auto"))).unwrap();
    let radau = Problem::load(bottle_with(&d, "radau.toml", "1e-7", None)).unwrap();
    assert_eq!((auto.solver.method, radau.solver.method), (Method::Auto, Method::Radau5));
    let (a, a_explicit) = records(&auto, Method::Auto);
    let (r, r_explicit) = records(&radau, Method::Radau5);
    assert_eq!(untimed_record(&a), untimed_record(&a_explicit), "the problem's method is the one integrated");
    assert_eq!(untimed_record(&r), untimed_record(&r_explicit));
    let (wa, wr) = (&a.grasp.work, &r.grasp.work);
    assert!(wa.steps != wr.steps && wa.rhs_evals != wr.rhs_evals, "auto {wa:?}\nradau5 {wr:?}");
    assert!(wa.jac_evals < wr.jac_evals, "auto computes fewer Jacobians: {wa:?} vs {wr:?}");
    // the nominal design fails the impact criterion (MODEL.md's nominal numbers): the same
    // stage, cause and violation (E_cyl) with either method
    let (va, vr) = (&a.verdict, &r.verdict);
    assert_eq!((va.feasible, va.failed_stage, va.cause), (vr.feasible, vr.failed_stage, vr.cause));
    assert_eq!(va.failed_stage, Some(3), "{va:?}");
    let (ea, er) = (va.violation.unwrap(), vr.violation.unwrap());
    assert!((ea / er - 1.0).abs() < 1e-5, "violation auto {ea} radau5 {er}");

    // the command line: evaluate --json gives the library's record, simulate reports the
    // problem's method unless --method says another
    let file = d.join("auto.toml").display().to_string();
    let o = run_gripopt(&["evaluate", &file, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let cli: Record = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(untimed_record(&cli), untimed_record(&a));
    let method_of = |extra: &[&str]| {
        let o = run_gripopt(&[&["simulate", file.as_str(), "--json"], extra].concat());
        assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (v["method"].as_str().unwrap().to_string(), v["steps"].as_u64().unwrap())
    };
    let (m_auto, steps_auto) = method_of(&[]);
    let (m_radau, steps_radau) = method_of(&["--method", "radau5"]);
    assert_eq!((m_auto.as_str(), m_radau.as_str()), ("auto", "radau5"));
    assert_ne!(steps_auto, steps_radau, "--method radau5 overrides the problem's auto");
}

/// A problem without `solver.method` is a problem with `method = "radau5"`: the same
/// settings and the same record, bit for bit; its serialised form has no `method` key (as
/// before the key existed).
#[test]
fn an_absent_method_is_radau5() {
    let d = scratch("absent");
    let absent = Problem::load(BOTTLE_FILE).unwrap();
    let named = Problem::load(bottle_with(&d, "radau5.toml", "1e-6", Some("radau5"))).unwrap();
    assert_eq!(absent.solver, named.solver);
    assert_eq!(absent.solver.method, Method::Radau5);
    let (a, _) = records(&absent, Method::Radau5);
    let (n, _) = records(&named, Method::Radau5);
    assert_eq!(untimed_record(&a), untimed_record(&n));
    let v = serde_json::to_value(absent.solver).unwrap();
    assert_eq!(v, serde_json::json!({ "rtol": 1e-6, "atol": 1e-9, "max_steps": 200000 }));
    let v = serde_json::to_value(Problem::load(bottle_with(&d, "auto.toml", "1e-7", Some("auto"))).unwrap().solver);
    assert_eq!(v.unwrap()["method"], "auto");
}

/// An unknown method is an input error (exit 2) naming the file and `solver.method` and
/// listing the accepted values; so is a method that is not a string.
#[test]
fn an_unknown_method_is_refused_naming_the_field() {
    let d = scratch("unknown");
    let file = bottle_with(&d, "euler.toml", "1e-6", Some("euler"));
    let e = Problem::load(&file).unwrap_err().to_string();
    for want in ["euler.toml", "solver.method", "\"euler\"", "\"radau5\"", "\"auto\"", "\"trbdf2\"", "\"dopri5\""] {
        assert!(e.contains(want), "{want} missing in: {e}");
    }
    let o = run_gripopt(&["evaluate", &file.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("solver.method"), "{}", output_text(&o));
    // the spelling is the problem file's, not the Rust name
    let file = bottle_with(&d, "case.toml", "1e-6", Some("Radau5"));
    assert!(Problem::load(&file).unwrap_err().to_string().contains("solver.method"));
    let text = std::fs::read_to_string(BOTTLE_FILE)
        .unwrap()
        .replace("max_steps = 200000\n", "max_steps = 200000\nmethod = 5\n");
    let file = d.join("number.toml");
    std::fs::write(&file, text).unwrap();
    let e = Problem::load(&file).unwrap_err().to_string();
    assert!(e.contains("number.toml") && e.contains("method"), "{e}");
}

/// A run of a problem with `method = "auto"` states the method in its checkpoint's options;
/// editing the method in its problem file is a problem change: resume refuses it (exit 2)
/// and resumes once the file is restored.
#[test]
fn resume_refuses_a_run_whose_method_was_edited() {
    let d = scratch("resume");
    let file = bottle_with(&d, "p.toml", "1e-6", Some("auto"));
    let out = d.join("run").display().to_string();
    let args = ["--pop", "4", "--record", "none", "--threads", "1"];
    let o = run_gripopt(
        &[&["optimise", &file.display().to_string(), "--out", &out, "--generations", "1"], &args[..]].concat(),
    );
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let cp: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("run/checkpoint.json")).unwrap()).unwrap();
    assert_eq!(cp["options"]["method"], "auto", "{}", cp["options"]);
    let original = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, original.replace("method = \"auto\"", "method = \"radau5\"")).unwrap();
    let o = run_gripopt(&["resume", &out, "--generations", "2", "--threads", "1"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("changed since the run started"), "{}", output_text(&o));
    std::fs::write(&file, original).unwrap();
    let o = run_gripopt(&["resume", &out, "--generations", "2", "--threads", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
}
