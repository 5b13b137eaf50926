//! Hostile pass 33 (docs/cli.md "Hostile pass 33"): what a new user of session 33's
//! additions (`solver.method`, `export --object`, `--json` failures) ran into. Each test
//! fails without its fix.

use crate::common::{output_text, run_gripopt, untimed, BOTTLE_FILE};
use gripopt::params::Problem;
use gripopt::Stages;
use std::path::{Path, PathBuf};

const KITCHEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/hostile33")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `file` with `method = METHOD` added to its `[solver]`, written to `dir/name`.
fn with_method(file: &str, dir: &Path, name: &str, method: &str) -> String {
    let text = std::fs::read_to_string(file).unwrap();
    assert!(text.contains("\n[solver]\n"), "{file} has a [solver] section");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen("\n[solver]\n", &format!("\n[solver]\nmethod = \"{method}\"\n"), 1)).unwrap();
    path.display().to_string()
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
#[test]
fn evaluate_names_a_method_other_than_radau5() {
    let d = scratch("evaluate");
    for (file, method) in [(BOTTLE_FILE, "auto"), (BOTTLE_FILE, "trbdf2"), (KITCHEN, "auto")] {
        let path = with_method(file, &d, &format!("{method}.toml"), method);
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
    let radau = with_method(BOTTLE_FILE, &d, "radau5.toml", "radau5");
    assert!(evaluate_json(&[&radau]).get("method").is_none(), "{radau}");
    let o = run_gripopt(&["evaluate", &radau]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("method"), "{}", output_text(&o));
    for path in [BOTTLE_FILE, KITCHEN] {
        assert_eq!(evaluate_json(&[path])["method"], "auto", "{path}");
        let o = run_gripopt(&["evaluate", path]);
        let first = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
        assert!(first.ends_with("  method auto"), "{first}");
    }
}

/// `bench work-precision`'s whole staged evaluation times the problem's own method (auto for
/// a `method = "auto"` file) but said only "rtol 1e-6": now the method in the text and in
/// `--json`'s `whole_evaluation_ms`.
#[test]
fn bench_work_precision_names_the_method_of_its_whole_evaluation() {
    let d = scratch("bench");
    let path = with_method(BOTTLE_FILE, &d, "auto.toml", "auto");
    let out = d.join("out").display().to_string();
    let args = ["bench", "work-precision", &path, "--rtols", "1e-3", "--reps", "1", "--out", &out, "--json"];
    let o = run_gripopt(&args);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["whole_evaluation_ms"]["method"], "auto", "{v}");
    let text = String::from_utf8_lossy(&o.stderr);
    assert!(text.contains("whole staged evaluation (stages 0-3, pipeline mode, method auto, rtol 1e-6)"), "{text}");
}
