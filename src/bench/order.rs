//! The step-count experiment of issue 23 (item 2): the centred grasp over the work-precision
//! ensemble with Radau IIA of order 9 (5 stages, [`RadauIIA`]) against the default order 5
//! (RADAU5), at the same tolerances, through the same scene and driver: steps, evaluations,
//! Newton iterations, LU factorisations, CPU time and the errors of t_stab and E_cyl against
//! the ensemble's reference. Run by `cargo bench -p gripopt-diffsol-bench --bench radau_order`
//! (docs/benchmarks.md has the figures).

use super::ensemble::ensemble_cases;
use super::work_precision::rel;
use super::{say, time_it, Out};
use crate::params::{Problem, SceneParams};
use crate::sim::{drive, CentredScene, DynamicsResult, Radau5, RadauIIA, Scene, SimOptions, Stepper, Tol, NS};
use crate::Result;
use crate::{eval::StaticsResult, model::Finger};

/// The orders compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// RADAU5 (3 stages), the default.
    Five,
    /// Radau IIA with 5 stages.
    Nine,
}

/// The centred scene's tolerances (as `sim::scene::centred`): atol on angles and rates, 1e4·atol
/// on the filtered force.
fn tolerances(opts: &SimOptions) -> Tol<NS> {
    let a = opts.atol;
    Tol { rtol: opts.rtol, atol: nalgebra::SVector::<f64, NS>::from([a, a, a, a, a * 1e4]) }
}

/// The centred grasp of `f` with the stepper of `order` (as `simulate_grasp`, no recording).
pub fn simulate_order(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    opts: &SimOptions,
    order: Order,
) -> DynamicsResult {
    fn with<St: Stepper<NS>>(
        f: &Finger,
        s: &SceneParams,
        st: &StaticsResult,
        opts: &SimOptions,
        stepper: &mut St,
    ) -> DynamicsResult {
        let mut scene = CentredScene::new(f, s, st, opts, None);
        if !scene.prepare(st.f0, opts) {
            return scene.result();
        }
        let run = drive(&mut scene, stepper, opts, s.criteria.t_max);
        scene.finish(&run)
    }
    let tol = tolerances(opts);
    match order {
        Order::Five => with(f, s, st, opts, &mut Radau5::new(tol, 1e-5)),
        Order::Nine => with(f, s, st, opts, &mut RadauIIA::<NS, 5>::new(tol, 1e-5)),
    }
}

/// The q-quantile (nearest rank) of the non-NaN values of `v`.
fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.retain(|x| !x.is_nan());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The experiment over `n` ensemble designs (seed `seed`) at each of `rtols` (atol
/// 1e-3·rtol) for each of `orders`: one line per (order, rtol) to `out`, and the figures as
/// JSON.
pub fn radau_order(
    problem: &Problem,
    n: usize,
    seed: u64,
    rtols: &[f64],
    orders: &[Order],
    out: Out,
) -> Result<serde_json::Value> {
    let s = &problem.scene;
    let cases = ensemble_cases(problem, n, seed)?;
    say!(out, "{} ensemble designs (seed {seed}); reference Radau IIA order 5 at rtol 1e-11", cases.len());
    say!(
        out,
        "{:<8} {:>7} {:>8} {:>8} {:>8} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "order",
        "rtol",
        "steps",
        "rhs",
        "newton",
        "lu",
        "cpu med",
        "t_stab med",
        "t_stab p90",
        "E_cyl med",
        "E_cyl p90"
    );
    let mut rows = vec![];
    for &rtol in rtols {
        for &order in orders {
            let o = SimOptions::diagnostic(rtol, rtol * 1e-3, 5_000_000);
            let (mut steps, mut rhs, mut newton, mut lu) = (0u64, 0u64, 0u64, 0u64);
            let (mut cpu, mut ets, mut ees) = (vec![], vec![], vec![]);
            let mut differ = 0;
            for c in &cases {
                let (r, _, tmed) = time_it(|| simulate_order(&c.finger, s, &c.statics, &o, order), 0.05, 5);
                steps += r.stats.steps;
                rhs += r.rhs_evals;
                newton += r.stats.newton;
                lu += r.stats.lu;
                cpu.push(tmed);
                ets.push(rel(r.t_stab, c.reference.t_stab));
                ees.push(rel(r.first.map(|x| x.impact.e_cyl), c.reference.first.map(|x| x.impact.e_cyl)));
                differ += usize::from(r.outcome != c.reference.outcome);
            }
            let name = if order == Order::Five { "5 (RADAU5)" } else { "9" };
            let row = (quantile(cpu, 0.5), quantile(ets.clone(), 0.5), quantile(ets, 0.9), quantile(ees.clone(), 0.5));
            let ee90 = quantile(ees, 0.9);
            say!(
                out,
                "{name:<8} {rtol:>7.0e} {steps:>8} {rhs:>8} {newton:>8} {lu:>7} {:>8.3}ms {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e}{}",
                row.0 * 1e3,
                row.1,
                row.2,
                row.3,
                ee90,
                if differ > 0 { format!("  {differ} verdicts differ") } else { String::new() }
            );
            rows.push(serde_json::json!({
                "order": name, "rtol": rtol, "steps": steps, "rhs": rhs, "newton": newton, "lu": lu,
                "cpu_median_s": row.0, "err_t_stab_median": row.1, "err_t_stab_p90": row.2,
                "err_e_cyl_median": row.3, "err_e_cyl_p90": ee90, "verdicts_differing": differ,
            }));
        }
    }
    Ok(serde_json::json!({ "bench": "radau-order", "designs": cases.len(), "seed": seed, "rows": rows }))
}
