//! `gripopt bench work-precision --sample N`: work against precision over random designs.

use super::say;
use super::work_precision::{check_atol, rel};
use super::{median, time_it, BenchProgress};
use crate::eval::{stage_kinematics, stage_statics};
use crate::model::{Finger, StaticsResult};
use crate::params::{Design, Problem, DESIGN_NAMES};
use crate::sim::{diagnostic_grasp, DynamicsResult, Integration, Method};
use crate::{Error, Result};
use rand::SeedableRng;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The `f`-quantile (nearest rank) of the non-NaN values of `v`; NaN if none.
pub(super) fn quantile(mut v: Vec<f64>, f: f64) -> f64 {
    v.retain(|x| !x.is_nan());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * f).round() as usize]
}

/// What `bench work-precision --sample N` is asked for.
#[derive(Debug, Clone)]
pub struct EnsembleBench {
    /// Random designs in the ensemble (at least 1).
    pub sample: usize,
    /// The seed of their draw.
    pub seed: u64,
    /// The folder of work_precision_ensemble.csv and its designs' CSV.
    pub out_dir: PathBuf,
    /// Absolute tolerance (None: rtol × 1e-3), as in [`super::WorkPrecision`].
    pub atol: Option<f64>,
}

/// Work-precision over an ensemble of `b.sample` random designs of the box that pass stage
/// 2 (seed `b.seed`): for each method and rtol, the median CPU time per simulation and the
/// median / 90th-percentile relative errors in t_stab and E_cyl against Radau IIA at rtol
/// 1e-11, and how many verdicts differ. `path` is the problem file, for messages. Writes
/// work_precision_ensemble.csv into `b.out_dir`; the text goes to `out`, the drawing of the
/// designs and their references to `progress`.
pub fn work_precision_ensemble(
    problem: &Problem,
    path: &Path,
    b: &EnsembleBench,
    out: super::Out,
    progress: &dyn BenchProgress,
) -> Result<serde_json::Value> {
    let (n, seed, out_dir, atol) = (b.sample, b.seed, b.out_dir.as_path(), b.atol);
    if n == 0 {
        return Err(Error::Input("--sample 0: must be at least 1".into()));
    }
    check_atol(atol)?;
    let p = problem;
    let s = &p.scene;
    let diag = |m: Method, rtol: f64| Integration::new(rtol, atol.unwrap_or(rtol * 1e-3), 5_000_000).with_method(m);
    let (cases, drawn) = draw_cases(p, n, seed, progress)?;
    if cases.is_empty() {
        return Err(Error::bench(format!(
            "{}: no random design of the box passed stage 2 and reached stability in {drawn} draws",
            path.display()
        )));
    }
    super::work_precision::say_scene(p, out)?;
    say!(out, "ensemble: {} designs passing stage 2 and reaching stability (drawn {drawn}, seed {seed}); reference Radau IIA rtol 1e-11", cases.len());
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, "cannot create", e))?;
    let csv = out_dir.join("work_precision_ensemble.csv");
    let existed = csv.exists();
    write_designs(&out_dir.join("work_precision_ensemble_designs.csv"), cases.iter().map(|c| &c.design), out)?;
    let io = |e| Error::io(&csv, "cannot write", e);
    let mut w = crate::fsutil::AtomicFile::create(&csv)?;
    writeln!(w, "method,rtol,designs,cpu_median_s,steps_median,rhs_median,err_t_stab_median,err_t_stab_p90,err_e_cyl_median,err_e_cyl_p90,verdicts_differing").map_err(io)?;
    say!(
        out,
        "{:<8} {:>7} {:>10} {:>7} {:>7} {:>11} {:>11} {:>11} {:>11} verdicts differ",
        "method",
        "rtol",
        "cpu med",
        "steps",
        "rhs",
        "t_stab med",
        "t_stab p90",
        "E_cyl med",
        "E_cyl p90"
    );
    let mut summary = vec![];
    for m in [Method::Radau5, Method::Auto, Method::Dopri5, Method::TrBdf2] {
        for rtol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
            if m == Method::TrBdf2 && rtol < 1e-7 {
                continue;
            }
            let o = diag(m, rtol);
            let (mut cpu, mut steps, mut rhs, mut ets, mut ee) = (vec![], vec![], vec![], vec![], vec![]);
            let mut differ = 0;
            for c in &cases {
                let (f, st, reference) = (&c.finger, &c.statics, &c.reference);
                let (r, _, tmed) = time_it(|| diagnostic_grasp(f, s, st, &o), 0.05, 7);
                cpu.push(tmed);
                steps.push(r.stats.steps as f64);
                rhs.push(r.rhs_evals as f64);
                ets.push(rel(r.t_stab, reference.t_stab));
                ee.push(rel(r.first.map(|x| x.impact.e_cyl), reference.first.map(|x| x.impact.e_cyl)));
                differ += usize::from(r.outcome != reference.outcome);
            }
            let q = quantile;
            let (cpu, steps, rhs) = (median(cpu), median(steps), median(rhs));
            let (ets_med, ets_p90, ee_med, ee_p90) = (median(ets.clone()), q(ets, 0.9), median(ee.clone()), q(ee, 0.9));
            summary.push(serde_json::json!({
                "method": format!("{m:?}"), "rtol": rtol, "cpu_median_s": cpu, "steps_median": steps, "rhs_median": rhs,
                "err_t_stab_median": ets_med, "err_t_stab_p90": ets_p90, "err_e_cyl_median": ee_med, "err_e_cyl_p90": ee_p90, "verdicts_differing": differ,
            }));
            let n = cases.len();
            writeln!(
                w,
                "{m:?},{rtol:e},{n},{cpu:e},{steps},{rhs},{ets_med:e},{ets_p90:e},{ee_med:e},{ee_p90:e},{differ}"
            )
            .map_err(io)?;
            let (method, cpu_ms) = (format!("{m:?}"), cpu * 1e3);
            say!(
                out,
                "{method:<8} {rtol:>7.0e} {cpu_ms:>8.3}ms {steps:>7} {rhs:>7} {ets_med:>11.2e} {ets_p90:>11.2e} {ee_med:>11.2e} {ee_p90:>11.2e} {differ}"
            );
        }
    }
    w.commit()?;
    say!(out, "wrote {}{}", csv.display(), super::replaced_note(existed));
    Ok(
        serde_json::json!({ "bench": "work-precision-ensemble", "scene": "centred", "problem_scene": p.scene.setup.kind, "designs": cases.len(), "drawn": drawn, "seed": seed, "rows": summary, "csv": csv.display().to_string() }),
    )
}

/// One design of the ensemble: its finger and statics, and the reference simulation (Radau
/// IIA at rtol 1e-11) that reached stability.
#[derive(Debug, Clone)]
pub struct Case {
    /// The design.
    pub design: Design,
    /// Its finger.
    pub finger: Finger,
    /// Its statics (stage 2).
    pub statics: StaticsResult,
    /// The reference simulation.
    pub reference: DynamicsResult,
}

/// `n` random designs of the box (seed `seed`) that pass stage 2 and whose reference reaches
/// stability, and how many were drawn (at most 1000·n).
fn draw_cases(p: &Problem, n: usize, seed: u64, progress: &dyn BenchProgress) -> Result<(Vec<Case>, usize)> {
    let s = &p.scene;
    let tight = Integration::new(1e-11, 1e-14, 5_000_000);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut cases = vec![];
    let mut drawn = 0usize;
    progress.begin("designs + references", n as u64, "");
    while cases.len() < n && drawn < 1000 * n {
        drawn += 1;
        let d = p.bounds.sample(&mut rng);
        let Ok(k) = stage_kinematics(&d, s) else { continue };
        let Ok(st) = stage_statics(&k.finger, s) else { continue };
        let reference = diagnostic_grasp(&k.finger, s, &st, &tight);
        if reference.t_stab.is_none() {
            continue;
        }
        cases.push(Case { design: d, finger: k.finger, statics: st, reference });
        progress.step();
    }
    progress.end();
    Ok((cases, drawn))
}

/// The ensemble of `gripopt bench work-precision --sample n --seed seed`: the same designs,
/// with their references.
pub fn ensemble_cases(p: &Problem, n: usize, seed: u64) -> Result<Vec<Case>> {
    if n == 0 {
        return Err(Error::Input("--sample 0: must be at least 1".into()));
    }
    let (cases, drawn) = draw_cases(p, n, seed, &())?;
    if cases.is_empty() {
        return Err(Error::bench(format!(
            "no random design of the box passed stage 2 and reached stability in {drawn} draws"
        )));
    }
    Ok(cases)
}

/// The ensemble's designs, one `--design` argument per line (for `tools/compare_baseline.py`,
/// which runs two binaries on them).
fn write_designs<'a>(csv: &Path, designs: impl Iterator<Item = &'a Design>, out: super::Out) -> Result<()> {
    let io = |e| Error::io(csv, "cannot write", e);
    let mut w = crate::fsutil::AtomicFile::create(csv)?;
    writeln!(w, "design").map_err(io)?;
    for d in designs {
        let x = d.to_array();
        let arg: Vec<String> = DESIGN_NAMES.iter().zip(x).map(|(n, v)| format!("{n}={v}")).collect();
        writeln!(w, "\"{}\"", arg.join(",")).map_err(io)?;
    }
    w.commit()?;
    say!(out, "wrote {}", csv.display());
    Ok(())
}
