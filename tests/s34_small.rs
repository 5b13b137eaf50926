//! Small user-facing gaps of session 34: the switching method's counts in the record
//! (`switches`, `explicit_steps`, absent for every other method) and the command line's
//! method spellings accepted by the library's parser (problem files, Python).

use crate::common::{output_text, run_gripopt, BOTTLE_FILE};
use gripopt::eval::{evaluate, EvalOptions, Record};
use gripopt::params::Problem;
use gripopt::sim::{Integration, Method};

/// `simulate --json` of the nominal design with `extra` flags, as JSON.
fn simulate_json(extra: &[&str]) -> serde_json::Value {
    let o = run_gripopt(&[&["simulate", BOTTLE_FILE, "--json"], extra].concat());
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// An auto run of the nominal problem switches (its settling tail is stiff for
/// Dormand–Prince: docs/benchmarks.md) and says how many of its accepted steps were
/// explicit; a RADAU5 run's record has neither key, as before the keys existed.
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
