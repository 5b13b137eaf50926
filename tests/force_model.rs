//! D22 (MODEL.md v2 §6.5): α and F̃ follow `[criteria] force_model`; both pairs always reported.

use crate::common::{bottle, close_rel};
use gripopt::eval::{evaluate, EvalOptions, Record};
use gripopt::params::{Design, ForceModel, Problem};
use std::path::Path;

const ALPHA_MU: f64 = 0.630876786547;
const FMEAN_MU: f64 = 11.0872485551;
const ALPHA_0: f64 = 0.134162947086;
const FMEAN_0: f64 = 8.29512361390;

fn bottle_text() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
}

fn with_model(model: &str) -> Problem {
    let t = bottle_text().replace("force_model = \"mobilised\"", &format!("force_model = \"{model}\""));
    Problem::from_toml_str(&t, Path::new("test.toml")).unwrap()
}

fn record(p: &Problem) -> Record {
    Record::from_eval(&evaluate(&Design::nominal(), &p.scene, &EvalOptions::statics_only()))
}

/// The record's objective pair (α, F̃) is `objective` under `model`, and both the mobilised
/// and the frictionless pairs are reported with MODEL.md's nominal values whatever the model.
#[track_caller]
fn assert_reports_both_pairs(r: &Record, model: ForceModel, objective: (f64, f64)) {
    assert_eq!(r.statics.force_model, Some(model));
    close_rel(r.statics.alpha.unwrap(), objective.0, 1e-9, &format!("alpha under {model:?}"));
    close_rel(r.statics.mean_force.unwrap(), objective.1, 1e-9, &format!("mean_force under {model:?}"));
    close_rel(r.statics.alpha_mu.unwrap(), ALPHA_MU, 1e-9, "alpha_mu");
    close_rel(r.statics.mean_force_mu.unwrap(), FMEAN_MU, 1e-9, "mean_force_mu");
    close_rel(r.statics.alpha_0.unwrap(), ALPHA_0, 1e-9, "alpha_0");
    close_rel(r.statics.mean_force_0.unwrap(), FMEAN_0, 1e-9, "mean_force_0");
}

#[test]
fn default_problem_is_mobilised_and_reports_both_pairs() {
    let p = bottle();
    assert_eq!(p.scene.criteria.force_model, ForceModel::Mobilised);
    let r = record(&p);
    assert_reports_both_pairs(&r, ForceModel::Mobilised, (ALPHA_MU, FMEAN_MU));
    // eq. 3.12 by hand from the reported f^μ (an independent path to the same number)
    let (f1, f2) = (r.statics.fmu_1.unwrap(), r.statics.fmu_2.unwrap());
    let m = 0.5 * (f1 + f2);
    close_rel(((m - f1).powi(2) + (m - f2).powi(2)) / (f1 * f2), ALPHA_MU, 1e-9, "alpha_mu from fmu");
    let ev = evaluate(&Design::nominal(), &p.scene, &EvalOptions::statics_only());
    let o = ev.objectives();
    close_rel(o[1], ALPHA_MU, 1e-9, "objective alpha");
    close_rel(-o[2], FMEAN_MU, 1e-9, "objective mean force");
}

#[test]
fn frictionless_model_switches_the_objectives_only() {
    let p = with_model("frictionless");
    assert_eq!(p.scene.criteria.force_model, ForceModel::Frictionless);
    let r = record(&p);
    assert_reports_both_pairs(&r, ForceModel::Frictionless, (ALPHA_0, FMEAN_0));
    // the constraints do not depend on the model (D7): same max_offset, same forces
    let m = record(&bottle());
    assert_eq!(r.statics.max_offset, m.statics.max_offset);
    assert_eq!(r.statics.f0_1, m.statics.f0_1);
}

#[test]
fn force_model_key_is_required_and_checked() {
    let bad = bottle_text().replace("force_model = \"mobilised\"", "force_model = \"coulomb\"");
    let e = Problem::from_toml_str(&bad, Path::new("x.toml")).unwrap_err().to_string();
    assert!(e.contains("criteria.force_model") && e.contains("mobilised"), "{e}");
    let missing: String =
        bottle_text().lines().filter(|l| !l.starts_with("force_model")).map(|l| format!("{l}\n")).collect();
    let e = Problem::from_toml_str(&missing, Path::new("x.toml")).unwrap_err().to_string();
    assert!(e.contains("force_model"), "{e}");
}

#[test]
fn every_shipped_problem_names_its_force_model() {
    for f in ["bottle-1l", "can", "light-bottle"] {
        let t = std::fs::read_to_string(format!("{}/problems/{f}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap();
        assert!(t.contains("force_model = "), "{f}.toml");
    }
}
