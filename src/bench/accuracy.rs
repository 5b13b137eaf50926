//! `gripopt bench accuracy`: the accuracy rule of docs/benchmarks.md ("The accuracy rule")
//! checked for solver settings against a tight reference (RADAU5, rtol 1e-10, atol 1e-13):
//! every verdict the same over the grasp ensemble (the designs of `bench work-precision
//! --sample N`), their free scenes and a robust problem's scenarios (30 kitchen designs × 32
//! scenarios = 960 by default), and each objective's relative error (p90 and max) against
//! the rule's bounds, the aggregated robust objectives included. Diagnostic quantities (the
//! impact energy, the object's displacement and tilt) are reported, not held.

use super::accuracy_table::{
    summarise, write_cases, CandidateSummary, GraspOutcome, Outcomes, RobustOutcome, ScenarioOutcome, RULE_MAX,
    RULE_P90,
};
use super::say;
use super::BenchProgress;
use crate::eval::{evaluate, simulate, EvalOptions, Study};
use crate::params::{Design, Method, Problem, DESIGN_NAMES};
use crate::sim::{diagnostic_grasp, Controls, Integration, SceneSpec, SIMULATOR_REVISION};
use crate::{Error, Result};
use rand::SeedableRng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The reference's relative tolerance (the rule's).
pub const REFERENCE_RTOL: f64 = 1e-10;
/// The reference's absolute tolerance (the rule's).
pub const REFERENCE_ATOL: f64 = 1e-13;
/// The reference's step budget.
const REFERENCE_MAX_STEPS: u64 = 20_000_000;
/// The kitchen front design of issue 40 (`make bench-instructions` counts its evaluation):
/// the first design of the robust ensemble.
pub const KITCHEN_FRONT_DESIGN: &str = "l21=0.04304807948252374,b=0.06871978187729287,t22=0.03375918412304188,r=0.2601664030440584,p=0.25261005423197275,psi_deg=135.766034896994";

/// Solver settings the bench measures: `default` (each problem file's own `[solver]`, as
/// loaded) or `METHOD:RTOL[:ATOL]` (the file's atol where left out).
#[derive(Debug, Clone, PartialEq)]
pub enum Candidate {
    /// Each problem's own settings.
    Default,
    /// A method at a relative and (optionally) absolute tolerance.
    Fixed {
        /// The method.
        method: Method,
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance (None: the problem's).
        atol: Option<f64>,
    },
}

impl Candidate {
    /// Parse `default` or `METHOD:RTOL[:ATOL]`.
    pub fn parse(s: &str) -> Result<Self> {
        let bad = |why: &str| {
            Error::Input(format!("--candidates: `{s}` {why} (`default` or METHOD:RTOL[:ATOL], e.g. auto:1e-6)"))
        };
        if s == "default" {
            return Ok(Candidate::Default);
        }
        let parts: Vec<&str> = s.split(':').collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(bad("is not of that form"));
        }
        let method =
            Method::parse(parts[0]).ok_or_else(|| bad(&format!("names no method ({})", Method::accepted())))?;
        let num = |t: &str| t.parse::<f64>().ok().filter(|v| *v > 0.0 && *v < 1.0);
        let rtol = num(parts[1]).ok_or_else(|| bad("has no rtol in (0, 1)"))?;
        let atol = match parts.get(2) {
            Some(t) => Some(num(t).ok_or_else(|| bad("has no atol in (0, 1)"))?),
            None => None,
        };
        if let Some(a) = atol {
            method.check_atol(a).map_err(|rule| bad(&format!("atol {rule}")))?;
        }
        Ok(Candidate::Fixed { method, rtol, atol })
    }

    /// The integration of problem `p` under this candidate.
    pub fn integration(&self, p: &Problem) -> Integration {
        match *self {
            Candidate::Default => Integration::from_solver(&p.solver),
            Candidate::Fixed { method, rtol, atol } => {
                Integration::new(rtol, atol.unwrap_or(p.solver.atol), p.solver.max_steps).with_method(method)
            }
        }
    }

    /// As written on the command line.
    pub fn label(&self) -> String {
        match self {
            Candidate::Default => "default".into(),
            Candidate::Fixed { method, rtol, atol: None } => format!("{method}:{rtol:e}"),
            Candidate::Fixed { method, rtol, atol: Some(a) } => format!("{method}:{rtol:e}:{a:e}"),
        }
    }
}

/// What `bench accuracy` is asked for.
#[derive(Debug, Clone)]
pub struct AccuracyBench {
    /// Designs of the grasp ensemble (those of `bench work-precision --sample N`).
    pub sample: usize,
    /// Designs of the robust ensemble (the kitchen front design first, then random designs
    /// of the box that pass stages 0–2 on every object).
    pub robust_designs: usize,
    /// Seed of both draws.
    pub seed: u64,
    /// The settings measured.
    pub candidates: Vec<Candidate>,
    /// Folder of accuracy.csv, accuracy_cases.csv and the reference's cache.
    pub out_dir: PathBuf,
}

/// The reference's outcomes with what they were computed for (the cache's key).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CachedReference {
    key: serde_json::Value,
    outcomes: Outcomes,
}

/// The grasp design `x` of `p` under `integ`.
fn grasp_outcome(p: &Problem, x: &Design, integ: &Integration) -> GraspOutcome {
    let t = Instant::now();
    let s = &p.scene;
    let opts = EvalOptions { integration: *integ, ..EvalOptions::full(p) };
    let ev = evaluate(x, s, &opts);
    let verdict_of = |e: &crate::eval::Evaluation| {
        let d = e.discard.as_ref();
        (e.feasible(), d.map(|d| d.stage), d.map(|d| d.reason.to_string()))
    };
    let sim_work = |e: &crate::eval::Evaluation| {
        let g = e.dynamics.map_or([0, 0], |d| [d.stats.steps, d.rhs_evals]);
        let f = e.free.map_or([0, 0], |f| [f.stats.steps, f.rhs_evals]);
        [g[0] + f[0], g[1] + f[1]]
    };
    let mut work = sim_work(&ev);
    let (mut t_stab, mut e_cyl) = (None, None);
    if let (Some(k), Some(st)) = (ev.kin, ev.statics) {
        let d = diagnostic_grasp(&k.finger, s, &st, integ);
        (t_stab, e_cyl) = (d.t_stab, d.first.map(|f| f.impact.e_cyl));
        work = [work[0] + d.stats.steps, work[1] + d.rhs_evals];
    }
    let fr = simulate(x, s, &SceneSpec::free(0.0), integ, &Controls::DIAGNOSTIC, &mut ());
    let fw = sim_work(&fr);
    let free_motion = fr.free.map_or((None, None), |f| (Some(f.object_max_displacement), Some(f.object_max_tilt_deg)));
    GraspOutcome {
        verdict: verdict_of(&ev),
        objectives: ev.objectives().map(|v| (!v.is_nan()).then_some(v)),
        t_stab,
        e_cyl,
        free_verdict: verdict_of(&fr),
        free_motion,
        work: [work[0] + fw[0], work[1] + fw[1]],
        seconds: t.elapsed().as_secs_f64(),
    }
}

/// The robust design `x` of `p` (its study `study`, every scenario run) under `integ`.
fn robust_outcome(p: &Problem, study: &Study, x: &Design, integ: &Integration) -> RobustOutcome {
    let t = Instant::now();
    let opts = EvalOptions { integration: *integ, ..EvalOptions::full(p) };
    let rec = study.evaluate(x, &opts).record;
    let r = rec.robust.as_ref();
    let mut scenarios: Vec<(usize, usize, ScenarioOutcome)> = r
        .map(|r| {
            r.scenarios
                .iter()
                .map(|s| {
                    let o = ScenarioOutcome {
                        stays: s.stays,
                        t_stab: s.t_stab,
                        motion: (s.max_displacement, s.max_tilt_deg),
                    };
                    (s.object, s.k, o)
                })
                .collect()
        })
        .unwrap_or_default();
    scenarios.sort_by_key(|s| (s.0, s.1));
    RobustOutcome {
        verdict: (rec.verdict.feasible, rec.verdict.failed_stage),
        objectives: r.map_or([None; 4], |r| r.objectives.reported().to_array()),
        objects: r
            .map(|r| r.objects.iter().map(|o| (o.objectives.reported().to_array(), o.meets_p_min)).collect())
            .unwrap_or_default(),
        scenarios: scenarios.into_iter().map(|s| s.2).collect(),
        work: r.map_or([0, 0], |r| [r.steps[0] + r.steps[1], r.rhs_evals[0] + r.rhs_evals[1]]),
        seconds: t.elapsed().as_secs_f64(),
    }
}

/// `n` robust designs: the kitchen front design, then random designs of the box (seed
/// `seed`) that pass stages 0–2 on every object.
fn robust_designs(p: &Problem, study: &Study, n: usize, seed: u64) -> Result<Vec<Design>> {
    let mut designs = vec![Design::parse_assignments(KITCHEN_FRONT_DESIGN)?];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut drawn = 0;
    while designs.len() < n && drawn < 10_000 * n {
        drawn += 1;
        let d = p.bounds.sample(&mut rng);
        if study.start(&d).passed() {
            designs.push(d);
        }
    }
    designs.truncate(n);
    Ok(designs)
}

/// Every outcome under `integ_of` (per problem), in parallel, in the designs' order.
fn outcomes(
    grasp: (&Problem, &[Design]),
    robust: (&Problem, &Study, &[Design]),
    integ_of: &(dyn Fn(&Problem) -> Integration + Sync),
    progress: &dyn BenchProgress,
) -> Outcomes {
    let (gp, gd) = grasp;
    let (rp, setup, rd) = robust;
    let gi = integ_of(gp);
    let ri = integ_of(rp);
    let grasp = gd
        .par_iter()
        .map(|x| {
            let o = grasp_outcome(gp, x, &gi);
            progress.step();
            o
        })
        .collect();
    let robust = rd
        .par_iter()
        .map(|x| {
            let o = robust_outcome(rp, setup, x, &ri);
            progress.step();
            o
        })
        .collect();
    Outcomes { grasp, robust }
}

/// Check `b` and run it: the grasp problem `gp` (its file `gpath`) and the robust problem
/// `rp` (`rpath`). Writes accuracy.csv (one row per candidate and quantity) and
/// accuracy_cases.csv (every case's values) into `b.out_dir`, and caches the reference's
/// outcomes there (accuracy_reference.json, reused while its key matches).
pub fn accuracy(
    gp: &Problem,
    gpath: &Path,
    rp: &Problem,
    rpath: &Path,
    b: &AccuracyBench,
    out: super::Out,
    progress: &dyn BenchProgress,
) -> Result<serde_json::Value> {
    if b.sample == 0 || b.robust_designs == 0 || b.candidates.is_empty() {
        return Err(Error::Input("bench accuracy: --sample, --designs and --candidates need at least one each".into()));
    }
    if rp.robust.is_none() {
        return Err(Error::Input(format!(
            "{}: has no [robust] section (bench accuracy's robust problem)",
            rpath.display()
        )));
    }
    // the optimisation's scenarios, every one run
    let mut setup = Study::of(rp, &EvalOptions::full(rp));
    setup.early_stop = false;
    progress.begin("grasp designs", b.sample as u64, "");
    let gcases = super::ensemble_cases(gp, b.sample, b.seed)?;
    progress.end();
    let gd: Vec<Design> = gcases.iter().map(|c| c.design).collect();
    let rd = robust_designs(rp, &setup, b.robust_designs, b.seed)?;
    std::fs::create_dir_all(&b.out_dir).map_err(|e| Error::io(&b.out_dir, "cannot create", e))?;
    say!(
        out,
        "accuracy rule: against RADAU5 rtol {REFERENCE_RTOL:e} atol {REFERENCE_ATOL:e}: every verdict the same; objectives' relative error p90 <= {RULE_P90:e}, max <= {RULE_MAX:e}"
    );
    say!(
        out,
        "grasp ensemble: {} designs of {} (seed {}), each in its scene and in the free scene; robust ensemble: {} designs of {} x {} scenarios (every scenario run)",
        gd.len(),
        gpath.display(),
        b.seed,
        rd.len(),
        rpath.display(),
        setup.planned()
    );
    let key = serde_json::json!({
        "revision": SIMULATOR_REVISION,
        "grasp": crate::fsutil::sha256_hex(gp.source_text.as_bytes()),
        "robust": crate::fsutil::sha256_hex(rp.source_text.as_bytes()),
        "designs": [gd.iter().map(|d| d.to_array()).collect::<Vec<_>>(), rd.iter().map(|d| d.to_array()).collect::<Vec<_>>()],
        "reference": [REFERENCE_RTOL, REFERENCE_ATOL],
    });
    let cache = b.out_dir.join("accuracy_reference.json");
    let reference = match read_cache(&cache, &key) {
        Some(o) => {
            say!(out, "reference: reused {}", cache.display());
            o
        }
        None => {
            let len = (gd.len() + rd.len()) as u64;
            progress.begin("reference", len, "RADAU5 1e-10");
            let tight = |_: &Problem| Integration::new(REFERENCE_RTOL, REFERENCE_ATOL, REFERENCE_MAX_STEPS);
            let o = outcomes((gp, &gd), (rp, &setup, &rd), &tight, progress);
            progress.end();
            // numbers, strings and plain structs: serialising cannot fail
            let text = serde_json::to_string(&CachedReference { key: key.clone(), outcomes: o.clone() })
                .expect("outcomes serialise");
            std::fs::write(&cache, text).map_err(|e| Error::io(&cache, "cannot write", e))?;
            say!(out, "reference: computed, cached in {}", cache.display());
            o
        }
    };
    let mut summaries: Vec<CandidateSummary> = vec![];
    let mut all = vec![];
    for c in &b.candidates {
        let label = c.label();
        progress.begin("candidate", (gd.len() + rd.len()) as u64, &label);
        let t = Instant::now();
        let o = outcomes((gp, &gd), (rp, &setup, &rd), &|p| c.integration(p), progress);
        let wall = t.elapsed().as_secs_f64();
        progress.end();
        let s = summarise(&label, &reference, &o, wall);
        s.say(out)?;
        summaries.push(s);
        all.push((label, o));
    }
    let csv = b.out_dir.join("accuracy.csv");
    super::accuracy_table::write_summaries(&csv, &summaries)?;
    let cases = b.out_dir.join("accuracy_cases.csv");
    write_cases(&cases, &gd, &rd, &reference, &all)?;
    say!(out, "wrote {} and {}", csv.display(), cases.display());
    let names = DESIGN_NAMES;
    Ok(serde_json::json!({
        "bench": "accuracy",
        "reference": {"method": "radau5", "rtol": REFERENCE_RTOL, "atol": REFERENCE_ATOL},
        "rule": {"p90": RULE_P90, "max": RULE_MAX},
        "design_names": names,
        "grasp_designs": gd.len(),
        "robust_designs": rd.len(),
        "scenarios": rd.len() * setup.planned(),
        "candidates": summaries.iter().map(|s| s.to_json()).collect::<Vec<_>>(),
        "csv": csv.display().to_string(),
    }))
}

/// The cached reference at `path`, if its key is `key`.
fn read_cache(path: &Path, key: &serde_json::Value) -> Option<Outcomes> {
    let text = std::fs::read_to_string(path).ok()?;
    let c: CachedReference = serde_json::from_str(&text).ok()?;
    (c.key == *key).then_some(c.outcomes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::accuracy_table::{Kind, Quantity, RULE_MAX, RULE_P90};

    #[test]
    fn candidates_parse_as_written_and_refuse_what_is_not() {
        assert_eq!(Candidate::parse("default").unwrap(), Candidate::Default);
        let c = Candidate::parse("auto:1e-7").unwrap();
        assert_eq!(c, Candidate::Fixed { method: Method::Auto, rtol: 1e-7, atol: None });
        assert_eq!(c.label(), "auto:1e-7");
        let c = Candidate::parse("tr-bdf2:1e-6:1e-9").unwrap();
        assert_eq!(c, Candidate::Fixed { method: Method::TrBdf2, rtol: 1e-6, atol: Some(1e-9) });
        for bad in ["auto", "euler:1e-6", "auto:2", "auto:1e-6:0", "trbdf2:1e-6:1e-13", "auto:1e-6:1e-9:1"] {
            let e = Candidate::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--candidates") && e.contains(bad), "{bad}: {e}");
        }
    }

    #[test]
    fn a_quantity_holds_within_the_rule_only() {
        let q =
            |kind, differing, p90, max| Quantity { name: "q".into(), kind, n: 10, differing, errors: [0.0, p90, max] };
        assert!(q(Kind::Objective, 0, RULE_P90, RULE_MAX).holds());
        assert!(!q(Kind::Objective, 0, RULE_P90 * 1.01, 0.0).holds());
        assert!(!q(Kind::Objective, 0, 0.0, RULE_MAX * 1.01).holds());
        assert!(!q(Kind::Objective, 1, 0.0, 0.0).holds(), "a value on one side only");
        assert!(!q(Kind::Verdict, 1, f64::NAN, f64::NAN).holds());
        assert!(q(Kind::Verdict, 0, f64::NAN, f64::NAN).holds());
        assert!(q(Kind::Diagnostic, 3, 1.0, 1.0).holds(), "reported, not held");
    }
}
