//! Robust runs across a forced resume, what a robust record reports for a design that is not
//! form closed (hostile pass 32b), and the size checks of a robust run's records.

use crate::robust::{robust_problem, robust_text, spec, tmp, BOTTLE};
use gripopt::eval::{evaluate_record, EvalOptions, Study};
use gripopt::optim::MooProblem;
use gripopt::run::{GripperProblem, RunSpec};
use rand::SeedableRng;
use std::path::{Path, PathBuf};

/// Every file under `dir` (recursively) with its content, sorted by path.
fn folder_bytes(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = vec![];
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(folder_bytes(&p));
        } else {
            out.push((p.clone(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

/// `resume --force` may change the problem but not its robust objects (names, order, count)
/// nor whether it is robust: every table has one fixed set of `NAME.*` columns, so such a
/// resume is refused (exit 2, naming the file and `robust.objects`), the folder unchanged.
#[test]
fn a_forced_resume_refuses_another_robust_object_list() {
    let dir = tmp("forced-objects");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("robust.toml");
    let text = robust_text("");
    std::fs::write(&file, &text).unwrap();
    let run = dir.join("run");
    gripopt::run::optimise(&RunSpec { generations: 1, ..spec(&file, &run, 1) }).unwrap();
    let before = folder_bytes(&run);
    let can = "[[robust.objects]]\nname = \"can\"\nradius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\ntau = 0.5\n";
    assert!(text.contains(can));
    let bottle = "[[robust.objects]]\nname = \"bottle\"\nradius = 0.040\nlength = 0.200\ndensity = 1000.0\ngrasp_height = 0.050\ntau = 0.5\n";
    let swapped = text.replacen(bottle, "", 1).replacen(can, &format!("{can}{bottle}"), 1);
    let renamed = text.replacen("name = \"can\"", "name = \"tin\"", 1);
    let plain = std::fs::read_to_string(BOTTLE).unwrap();
    let (r, f) = (run.display().to_string(), file.display().to_string());
    for (case, changed) in
        [("removed", text.replacen(can, "", 1)), ("swapped", swapped), ("renamed", renamed), ("not robust", plain)]
    {
        std::fs::write(&file, &changed).unwrap();
        let o = crate::robustness::cli(&["resume", &r, "--generations", "2", "--force", "--threads", "1"]);
        let e = crate::robustness::stderr(&o);
        assert_eq!(crate::robustness::code(&o), 2, "{case}: {e}");
        assert!(e.contains(&f) && e.contains("robust.objects") && e.contains("new run"), "{case}: {e}");
        assert!(folder_bytes(&run) == before, "{case}: the refused resume changed the run folder");
        let e = gripopt::run::resume(&run, Some(2), true, Some(1)).unwrap_err().to_string();
        assert!(e.contains("robust.objects"), "{case}: the library refuses alike: {e}");
        assert!(folder_bytes(&run) == before, "{case}: the library's refusal changed the run folder");
    }
    // the same objects with another p_min: a forced resume takes it
    std::fs::write(&file, text.replacen("p_min = 0.5", "p_min = 0.4", 1)).unwrap();
    gripopt::run::resume(&run, Some(2), true, Some(1)).unwrap();
    assert!(run.join("problem-1.toml").is_file(), "the earlier problem kept");
}

/// A design that passes stage 2 on every object but is not form closed at the centred
/// reference object (MODEL.md §6.7): its record's max_offset is null everywhere, the robust
/// aggregate and the object's own value too (hostile pass 32b: the −Δ_off placeholder leaked
/// there), while the optimiser still ranks it at −Δ_off (f = +Δ_off in minimisation form).
#[test]
fn a_design_not_form_closed_has_no_robust_max_offset() {
    let p = robust_problem();
    let setup = Study::of(&p, &EvalOptions::full(&p));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let x = (0..20_000)
        .map(|_| p.bounds.sample(&mut rng))
        .find(|x| {
            let flat = evaluate_record(&p, x, &EvalOptions::statics_only());
            flat.statics.form_closed == Some(false) && setup.start(x).passed()
        })
        .expect("a design passing stage 2 that is not form closed");
    let e = GripperProblem::new(p.clone()).evaluate(&x.to_array());
    let r = &e.info.record;
    assert_eq!((r.statics.form_closed, r.statics.max_offset), (Some(false), None));
    let rb = r.robust.as_ref().unwrap();
    assert!(rb.objects.iter().all(|o| o.objectives.mean_force.is_some()), "stage 2 passed on every object");
    assert_eq!(rb.objects[0].objectives.max_offset, None, "the reference object is not form closed");
    assert!(rb.objects.iter().all(|o| o.objectives.max_offset.is_none_or(|m| m >= 0.0)), "{:?}", rb.objects);
    // "worst" of the objects: one without a max_offset has none aggregated
    assert_eq!(rb.objectives.max_offset, None);
    assert_eq!(r.objectives()[0], None);
    let json = serde_json::to_value(&**r).unwrap();
    assert!(json["robust"]["objectives"]["max_offset"].is_null(), "{}", json["robust"]["objectives"]);
    assert!(json["robust"]["objects"][0]["max_offset"].is_null());
    // what NSGA-II ranks is unchanged: −Δ_off, negated
    assert_eq!(e.f[0], p.scene.criteria.offset_step);
}

/// Issue 44 class 6: the size a run's checks count for a robust design's scenario record
/// (`BYTES_PER_SCENARIO_JSON`) is at least what one takes as JSON, measured here on the
/// longest record there can be: 17-digit negative numbers with a three-digit exponent in
/// every field, the longest cause word, the largest counts.
#[test]
fn a_scenario_record_takes_no_more_json_than_the_size_checks_count() {
    let long = -1.2345678901234567e-105;
    let rec = gripopt::eval::ScenarioRecord {
        object: 99_999,
        k: 999_999,
        inputs: gripopt::eval::ScenarioInputs([long; gripopt::params::N_INPUTS]),
        stays: false,
        cause: Some(gripopt::Cause::InitialPenetration),
        t_stab: Some(long),
        max_displacement: Some(long),
        max_tilt_deg: Some(long),
        rhs_evals: [u64::MAX; 2],
        steps: [u64::MAX; 2],
        abort: None,
    };
    let json = serde_json::to_string(&rec).unwrap();
    assert!(json.len() as u64 <= gripopt::run::BYTES_PER_SCENARIO_JSON, "{} bytes: {json}", json.len());
}

/// Issue 44 class 6: the `--pop` check assumed ~1 MiB per design, but a robust record
/// grows with objects × scenarios: kitchen.toml with K = 4096 (4 objects: 16384 scenario
/// records, ~6.6 MB a design in the checkpoint) at `--pop 400` started a run whose
/// checkpoint would pass the 4 GiB it is read back at, unresumable after hours. Now it is
/// refused before anything is written (exit 2, naming `--pop`, with the estimate).
#[test]
fn a_robust_run_whose_records_would_not_fit_is_refused_before_it_starts() {
    let d = crate::common::scratch("i44-size");
    let kitchen = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml")).unwrap();
    let p = d.join("k4096.toml");
    std::fs::write(&p, kitchen.replace("scenarios = 8 ", "scenarios = 4096 ")).unwrap();
    let out = d.join("run");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_gripopt"))
        .args(["optimise", p.to_str().unwrap(), "--out", out.to_str().unwrap(), "--pop", "400", "--generations", "2"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed().as_secs() > 60 {
            let _ = child.kill();
            panic!("the run started");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let o = child.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--pop") && e.contains("16384 scenario records (4 objects × 4096 scenarios)"), "{e}");
    assert!(!out.exists(), "the run folder was created");
}
