//! A problem file's `[solver] method`: the integration method of every grasp simulation of
//! the problem (evaluate, optimise, simulate's default); absent, the default (the switching
//! method with the default's tolerance scaling, session 38, within the accuracy rule of
//! docs/benchmarks.md against a tight reference); an unknown value refused naming the file
//! and the field; a run whose problem file's method was edited refused on resume, and a run
//! of before the default (RADAU5) resuming and replaying with RADAU5.

use crate::common::{copy_dir, nominal, output_text, run_gripopt, scratch_dir, untimed, BOTTLE_FILE};
use gripopt::eval::{evaluate, EvalOptions, Record};
use gripopt::params::Problem;
use gripopt::sim::{Controls, Integration, Method, Scaling};
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
    let radau = Problem::load(bottle_with(&d, "radau.toml", "1e-7", Some("radau5"))).unwrap();
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

/// A problem without `solver.method` runs the default: the switching method with the
/// default's scaling of its tolerances (`Scaling::DEFAULT`), not `method = "auto"` at the
/// file's tolerances (a named method keeps them as given); its serialised settings name the
/// method. With the method its checkpoint records, `Problem::with_run_method(None)` (a run of
/// before session 38), it is bit for bit a problem with `method = "radau5"`.
#[test]
fn an_absent_method_is_the_default() {
    let d = scratch("absent");
    let absent = Problem::load(BOTTLE_FILE).unwrap();
    assert_eq!((absent.solver.method, absent.solver.method_named), (Method::Auto, false));
    assert_eq!(Method::PROBLEM_DEFAULT, Method::Auto);
    let s = &absent.solver;
    let integ = Integration::from_solver(s);
    assert_eq!(integ.scaling, Scaling::DEFAULT);
    assert_eq!((integ.method, integ.rtol, integ.atol), (Method::Auto, s.rtol, s.atol));
    let own = Record::from_eval(&evaluate(&nominal(), &absent.scene, &EvalOptions::full(&absent)));
    let scaled = EvalOptions {
        dynamics: true,
        integration: Integration::new(s.rtol, s.atol, s.max_steps)
            .with_method(Method::Auto)
            .with_scaling(Scaling::DEFAULT),
        controls: Controls::PIPELINE,
        measure_always: false,
    };
    let by_hand = Record::from_eval(&evaluate(&nominal(), &absent.scene, &scaled));
    assert_eq!(untimed_record(&own), untimed_record(&by_hand), "the default is auto with Scaling::DEFAULT");
    // a named auto at the same tolerances integrates them as given: another record
    let named = Problem::load(bottle_with(&d, "auto.toml", "1e-6", Some("auto"))).unwrap();
    assert_eq!(Integration::from_solver(&named.solver).scaling, Scaling::AS_GIVEN);
    let (n, _) = records(&named, Method::Auto);
    assert_ne!(own.grasp.work.steps, n.grasp.work.steps, "the default's grasp runs at a tenth of the tolerances");
    let v = serde_json::to_value(absent.solver).unwrap();
    assert_eq!(v, serde_json::json!({ "rtol": 1e-6, "atol": 1e-9, "max_steps": 200000, "method": "auto" }));
    // a run that started before the default keeps RADAU5: the named radau5's record, bit for bit
    let old = absent.clone().with_run_method(None);
    let radau = Problem::load(bottle_with(&d, "radau5.toml", "1e-6", Some("radau5"))).unwrap();
    assert_eq!(
        (old.solver.method, Integration::from_solver(&old.solver)),
        (Method::Radau5, Integration::from_solver(&radau.solver))
    );
    let (a, _) = records(&old, Method::Radau5);
    let (r, _) = records(&radau, Method::Radau5);
    assert_eq!(untimed_record(&a), untimed_record(&r));
    assert_ne!(a.grasp.work.steps, own.grasp.work.steps);
    let v = serde_json::to_value(radau.solver).unwrap();
    assert_eq!(v, serde_json::json!({ "rtol": 1e-6, "atol": 1e-9, "max_steps": 200000 }), "RADAU5 is not written");
    // a file that names its method keeps it, whatever the checkpoint says
    assert_eq!(named.clone().with_run_method(None).solver.method, Method::Auto);
}

/// The default against the accuracy rule's reference (RADAU5 at rtol 1e-10, atol 1e-13), on
/// the kitchen scenario where the switching method at the file's tolerances misses t_stab
/// most (`bench accuracy`'s ensemble: design below, bottle-full, scenario 6; auto at rtol
/// 1e-6 is 3.4e-2 off, a threshold crossing moved by one oscillation): the default's verdict
/// is the reference's and its t_stab within the rule's largest error, 2e-3; and on the first
/// designs of the grasp ensemble, t_stab within the rule's p90, 5e-5.
#[test]
fn the_default_meets_the_tight_reference() {
    use gripopt::eval::Study;
    let p = Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml")).unwrap();
    let study = Study::of(&p, &EvalOptions::full(&p));
    let x = gripopt::params::Design::parse_assignments("l21=0.040293890699921606,b=0.06007415374949163,t22=0.03390882134602177,r=0.3173298185809163,p=0.5999131719097579,psi_deg=110.32810485295943").unwrap();
    let start = study.start(&x);
    let scenario = |integ: Integration| {
        let opts = EvalOptions { integration: integ, ..EvalOptions::full(&p) };
        study.run_scenario(&start, 0, 6, &opts, &mut ()).0
    };
    let reference = scenario(Integration::new(1e-10, 1e-13, 20_000_000));
    let default = scenario(Integration::from_solver(&p.solver));
    let as_given = scenario(Integration::from_solver(&p.solver).with_scaling(Scaling::AS_GIVEN));
    let t_ref = reference.t_stab.unwrap();
    let err = |t: Option<f64>| (t.unwrap() / t_ref - 1.0).abs();
    assert_eq!(default.stays, reference.stays);
    assert!(
        err(default.t_stab) <= 2e-3,
        "default t_stab {:?} against {t_ref}: {:e}",
        default.t_stab,
        err(default.t_stab)
    );
    assert!(
        err(as_given.t_stab) > 2e-3,
        "the case the scaling is for: auto at the file's tolerances {:e}",
        err(as_given.t_stab)
    );

    let g = Problem::load(BOTTLE_FILE).unwrap();
    let integ = Integration::from_solver(&g.solver);
    let tight = Integration::new(1e-10, 1e-13, 20_000_000);
    for c in gripopt::bench::ensemble_cases(&g, 3, 1).unwrap() {
        let r = gripopt::sim::diagnostic_grasp(&c.finger, &g.scene, &c.statics, &tight);
        let o = gripopt::sim::diagnostic_grasp(&c.finger, &g.scene, &c.statics, &integ);
        assert_eq!(o.outcome, r.outcome);
        let e = (o.t_stab.unwrap() / r.t_stab.unwrap() - 1.0).abs();
        assert!(e <= 5e-5, "{:?}: t_stab error {e:e}", c.design);
    }
}

/// A run folder of the gripopt before the default (tests/fixtures/run-64f5714: bottle-1l.toml,
/// no `solver.method`, so RADAU5; population 16, seed 4, 2 generations, recorded; its problem
/// file's original path gone) resumes with RADAU5, its checkpoint naming no method: the run
/// equals, bit for bit, a run of the problem with `method = "radau5"` (with NSGA-II, the
/// algorithm the old run resumes with since issue 42; history.csv's `pareto_hypervolume`
/// from the resume on), and not one with the default; every design, recorded by revision 4
/// or by the resume, replays verified.
#[test]
fn a_run_of_before_the_default_resumes_and_replays_with_radau5() {
    use gripopt::optim::{Survival, Variation};
    use gripopt::run::{optimise_with, resume, RunFolder, RunHooks, RunSpec};
    let d = scratch_dir("solver-method", "old-run");
    let old = d.join("old");
    copy_dir(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/run-64f5714")), &old);
    resume(&old, Some(3), false, Some(1)).unwrap();
    let text = std::fs::read_to_string(old.join("problem.toml")).unwrap();
    let run = |name: &str, text: String| {
        let problem = d.join(format!("{name}.toml"));
        std::fs::write(&problem, text).unwrap();
        let out = d.join(name);
        let spec = RunSpec {
            problem_path: problem,
            out: out.clone(),
            pop: 16,
            generations: 3,
            seed: 4,
            threads: Some(1),
            record: gripopt::record::RecordOptions::default(),
        };
        let nsga2 = RunHooks { algorithm: Some((Survival::Crowding, Variation::Sbx)), ..Default::default() };
        optimise_with(&spec, nsga2).unwrap();
        out
    };
    let named = run("radau5", text.replace("max_steps = 200000\n", "max_steps = 200000\nmethod = \"radau5\"\n"));
    let default = run("default", text);
    let csv = |dir: &std::path::Path, f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    for f in ["population.csv", "archive.csv", "pareto.csv"] {
        assert_eq!(csv(&old, f), csv(&named, f), "{f}: the resumed run is RADAU5's");
    }
    // history.csv: the same but for the old run's generations, which reported no
    // pareto_hypervolume (their pareto.csv was the population's front)
    let history = |dir: &std::path::Path| -> Vec<Vec<String>> {
        let text = csv(dir, "history.csv");
        text.lines().filter(|l| !l.starts_with('#')).map(|l| l.split(',').map(String::from).collect()).collect()
    };
    let (h_old, h_named) = (history(&old), history(&named));
    assert_eq!(h_old.len(), h_named.len());
    for (k, (a, b)) in h_old.iter().zip(&h_named).enumerate() {
        let all = k == 0 || k == h_old.len() - 1;
        let n = if all { a.len() } else { a.len() - 1 };
        assert_eq!(a[..n], b[..n], "history.csv line {k}: the resumed run is RADAU5's");
    }
    assert_ne!(csv(&old, "archive.csv"), csv(&default, "archive.csv"), "the default integrates otherwise");
    let cp: serde_json::Value = serde_json::from_slice(&std::fs::read(old.join("checkpoint.json")).unwrap()).unwrap();
    assert!(cp["options"].get("method").is_none(), "{}", cp["options"]);
    let folder = RunFolder::open(&old).unwrap();
    let mut simulated = [0; 3];
    for id in 0..48 {
        let r = folder.replay(id).unwrap();
        assert!(r.verified, "design {id}: {:?}", r.across_revisions);
        assert_eq!(r.recorded.simulator_revision, 4, "design {id}: RADAU5 as before the default");
        if r.fresh.grasp.work.steps.is_some() {
            simulated[(r.recorded.record.generation - 1) as usize] += 1;
        }
    }
    assert!(simulated[0] > 0 && simulated[2] > 0, "designs simulated per generation: {simulated:?}");
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
