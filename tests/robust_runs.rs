//! Robust runs across a forced resume, and what a robust record reports for a design that
//! is not form closed (hostile pass 32b).
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

/// `verify` on a robust run without a feasible design says why, as for a single-object run
/// (docs/cli.md: the discard causes), not only that there is nothing to verify.
#[test]
fn verify_of_a_robust_run_without_a_feasible_design_lists_the_discards() {
    let dir = tmp("verify-none-feasible");
    let _ = std::fs::remove_dir_all(&dir);
    let kitchen = Path::new(BOTTLE).with_file_name("kitchen.toml");
    let run = |args: &[&str]| crate::robustness::cli(args);
    let d = dir.display().to_string();
    let k = kitchen.display().to_string();
    let o = run(&["optimise", &k, "--out", &d, "--pop", "8", "--generations", "1", "--seed", "1", "--threads", "1"]);
    assert_eq!(crate::robustness::code(&o), 0, "{}", crate::robustness::stderr(&o));
    let shown: serde_json::Value = serde_json::from_slice(&run(&["show", &d, "--json"]).stdout).unwrap();
    assert!(shown["no_feasible_design"].is_array(), "the run has a feasible design: {shown}");
    let o = run(&["verify", &d]);
    let e = crate::robustness::stderr(&o);
    assert_eq!(crate::robustness::code(&o), 2, "{e}");
    assert!(e.contains("nothing written") && e.contains("were discarded") && e.contains("at stage"), "{e}");
    assert!(!dir.join("verify_robust.csv").exists());
}
