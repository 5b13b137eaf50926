//! A problem file's `[solver] method`: the integration method of every grasp simulation of
//! the problem (evaluate, optimise, simulate's default); absent, the default (the switching
//! method with the default's tolerance scaling, session 38, within the accuracy rule of
//! docs/benchmarks.md against a tight reference); an unknown value refused naming the file
//! and the field; a run whose problem file's method was edited refused on resume, and a run
//! of before the default (RADAU5) resuming and replaying with RADAU5. The method as the
//! outputs name it (`evaluate --json`, the switching method's counts), the command line's
//! spellings, and TR-BDF2's atol floor.

use crate::common::{
    copy_dir, nominal, output_text, run_gripopt, scratch, untimed, with_solver_method, BOTTLE_FILE, KITCHEN_FILE,
};
use gripopt::eval::{evaluate, EvalOptions, Record};
use gripopt::params::Problem;
use gripopt::sim::{Controls, Integration, Method, Scaling};
use gripopt::Stages;
use std::path::{Path, PathBuf};

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
    let d = scratch("old-run");
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

/// `simulate --json` of the nominal design with `extra` flags, as JSON.
fn simulate_json(extra: &[&str]) -> serde_json::Value {
    let o = run_gripopt(&[&["simulate", BOTTLE_FILE, "--json"], extra].concat());
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// An auto run of the nominal problem switches (its settling tail is stiff for
/// Dormand–Prince: docs/benchmarks.md) and says how many of its accepted steps were
/// explicit; a RADAU5 run's record has neither key, as before the keys existed.
/// Origin: session 34, small user-facing gaps.
#[test]
fn the_switching_method_reports_its_switches_and_explicit_steps() {
    let auto = simulate_json(&["--method", "auto"]);
    assert_eq!(auto["method"], "auto");
    let steps = auto["steps"].as_u64().unwrap();
    let switches = auto["switches"].as_u64().unwrap_or_else(|| panic!("no switches in {auto}"));
    let explicit = auto["explicit_steps"].as_u64().unwrap_or_else(|| panic!("no explicit_steps in {auto}"));
    assert!(switches >= 1, "the nominal's settling tail switches to RADAU5: {auto}");
    assert!(explicit > 0 && explicit <= steps, "explicit {explicit} of {steps} steps");
    // the implicit part did the rest: it computed Jacobians, which Dormand–Prince never does
    assert!(explicit < steps && auto["jac_evals"].as_u64().unwrap() > 0, "{auto}");

    // the library's pipeline record counts them too (evaluate with an explicit Method::Auto;
    // the nominal is discarded at its first impact, before the stiff tail: no switch, so
    // every step was Dormand–Prince's)
    let p = Problem::load(BOTTLE_FILE).unwrap();
    let s = &p.solver;
    let opts = EvalOptions::pipeline(Integration::new(s.rtol, s.atol, s.max_steps).with_method(Method::Auto));
    let r = Record::from_eval(&evaluate(&crate::common::nominal(), &p.scene, &opts));
    let w = &r.grasp.work;
    assert_eq!((w.switches, w.explicit_steps), (Some(0), w.steps), "{w:?}");
    assert_eq!((w.jac_evals, r.verdict.failed_stage), (Some(0), Some(3)), "{w:?}");

    for method in ["radau5", "trbdf2", "dopri5"] {
        let v = simulate_json(&["--method", method]);
        assert_eq!(v["method"], method);
        for key in ["switches", "explicit_steps"] {
            assert!(v.get(key).is_none(), "{method}: `{key}` in {v}");
        }
    }
    // the text report says them on its work line, for auto only
    let text = |m: &str| output_text(&run_gripopt(&["simulate", BOTTLE_FILE, "--method", m]));
    let plural = if switches == 1 { "" } else { "es" };
    let want = format!("steps {steps} (Dormand-Prince {explicit}, RADAU5 the rest; {switches} switch{plural})");
    assert!(text("auto").contains(&want), "{want} not in {}", text("auto"));
    assert!(!text("radau5").contains("the rest"), "{}", text("radau5"));
    let radau_opts = EvalOptions { integration: Integration::new(s.rtol, s.atol, s.max_steps), ..opts };
    let radau = Record::from_eval(&evaluate(&crate::common::nominal(), &p.scene, &radau_opts));
    let v = serde_json::to_value(&radau).unwrap();
    assert!(v.get("switches").is_none() && v.get("explicit_steps").is_none(), "{v}");
    // bottle-1l.toml names no method: the default, the switching method, counts them too
    let default = Record::from_eval(&evaluate(&crate::common::nominal(), &p.scene, &EvalOptions::full(&p)));
    assert!(default.grasp.work.switches.is_some(), "{:?}", default.grasp.work);
}

/// Every method name the command line takes (`--method`, clap's values and its alias
/// `tr-bdf2`) is one that the library's parser takes too (problem files' `solver.method`,
/// Python's `method=`), meaning the same method; the accepted list names the alias.
/// Origin: session 34, small user-facing gaps.
#[test]
fn the_command_lines_method_spellings_are_the_librarys() {
    let v = simulate_json(&["--method", "tr-bdf2"]);
    assert_eq!(v["method"], "trbdf2");
    for m in Method::ALL {
        assert_eq!(Method::parse(m.as_str()), Some(m));
    }
    assert_eq!(Method::parse("tr-bdf2"), Some(Method::TrBdf2));
    assert!(Method::accepted().contains("\"tr-bdf2\""), "{}", Method::accepted());
}

fn evaluate_json(args: &[&str]) -> serde_json::Value {
    let o = run_gripopt(&[&["evaluate", "--json"], args].concat());
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `evaluate --json` of a problem with `method = "auto"` printed the work counters (steps,
/// jac_evals, …) of a simulation whose method it named nowhere (simulate --json says it):
/// now a `method` key where the method is not RADAU5, the rest the library's record; the
/// text says it on its first line. `method = "radau5"` and --static-only are unchanged; a
/// file without the key runs the default, auto, and says so.
/// Origin: hostile pass of session 33.
#[test]
fn evaluate_names_a_method_other_than_radau5() {
    let d = scratch("evaluate");
    for (file, method) in [(BOTTLE_FILE, "auto"), (BOTTLE_FILE, "trbdf2"), (KITCHEN_FILE, "auto")] {
        let path = with_solver_method(file, &d, &format!("{method}.toml"), method);
        let p = Problem::load(&path).unwrap();
        let mut cli = evaluate_json(&[&path]);
        assert_eq!(cli["method"], method, "{path}");
        cli.as_object_mut().unwrap().remove("method");
        let lib = serde_json::to_value(gripopt::evaluate(&p, &p.nominal, Stages::All)).unwrap();
        assert_eq!(untimed(cli), untimed(lib), "{path}: the rest is the library's record");
        // stages 0-2 simulate nothing: no method
        assert!(evaluate_json(&[&path, "--static-only"]).get("method").is_none(), "{path}");
        let o = run_gripopt(&["evaluate", &path]);
        let first = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
        assert!(first.ends_with(&format!("  method {method}")), "{first}");
    }
    // radau5: the record as before the key existed; no method key: the default, auto (session 38)
    let radau = with_solver_method(BOTTLE_FILE, &d, "radau5.toml", "radau5");
    assert!(evaluate_json(&[&radau]).get("method").is_none(), "{radau}");
    let o = run_gripopt(&["evaluate", &radau]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("method"), "{}", output_text(&o));
    for path in [BOTTLE_FILE, KITCHEN_FILE] {
        assert_eq!(evaluate_json(&[path])["method"], "auto", "{path}");
        let o = run_gripopt(&["evaluate", path]);
        let first = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
        assert!(first.ends_with("  method auto"), "{first}");
    }
}

/// TR-BDF2 below atol 1e-11 collapsed its steps (1e-15: "step size underflow" at t = 0) or ran
/// for millions of steps (1e-13, the offset scene): the problem file refuses it, naming
/// `solver.atol` and the method; 1e-11 is taken.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn tr_bdf2_needs_an_atol_its_error_estimate_can_meet() {
    let dir = scratch("trbdf2-atol");
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
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn simulate_method_tr_bdf2_checks_the_files_atol() {
    let dir = scratch("radau5-atol");
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("atol = 1e-9", "atol = 1e-13", 1);
    let file = dir.join("radau5-1e-13.toml");
    std::fs::write(&file, text).unwrap();
    let o = run_gripopt(&["simulate", file.to_str().unwrap(), "--method", "trbdf2"]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--method trbdf2") && e.contains("solver.atol 1e-13") && e.contains(">= 1e-11"), "{e}");
}
