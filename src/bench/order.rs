//! The step-count experiment of issue 23 (item 2): the centred grasp over the work-precision
//! ensemble with Radau IIA of order 9 (5 stages, [`RadauIIA`]) against the default order 5
//! (RADAU5), at the same tolerances, through the same scene and driver: steps, evaluations,
//! Newton iterations, LU factorisations, CPU time and the errors of t_stab and E_cyl against
//! the ensemble's reference. Run by `cargo bench -p gripopt-diffsol-bench --bench radau_order`
//! (docs/benchmarks.md has the figures).

use super::ensemble::{ensemble_cases, quantile};
use super::median;
use super::work_precision::rel;
use super::{say, time_it, Out};
use crate::model::{Finger, StaticsResult};
use crate::params::{Problem, SceneParams};
use crate::sim::{
    centred_tolerances, drive, CentredScene, Controls, DynamicsResult, Integration, Radau5, RadauIIA, Stepper, NS,
};
use crate::Result;

/// The orders compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// RADAU5 (3 stages), the default.
    Five,
    /// Radau IIA with 5 stages.
    Nine,
}

/// The centred grasp of `f` with the stepper of `order` (as `sim::diagnostic_grasp`, nothing
/// sampled).
pub fn simulate_order(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    integ: &Integration,
    order: Order,
) -> DynamicsResult {
    fn with<St: Stepper<NS>>(
        f: &Finger,
        s: &SceneParams,
        st: &StaticsResult,
        integ: &Integration,
        stepper: &mut St,
    ) -> DynamicsResult {
        let ctl = Controls::DIAGNOSTIC;
        let mut scene = CentredScene::new(f, s, st, &ctl);
        if !scene.prepare(st.grasp.f0, &ctl) {
            return scene.result();
        }
        let run = drive(&mut scene, stepper, integ, &ctl, s.criteria.t_max, &mut ());
        scene.finish(&run)
    }
    let tol = centred_tolerances(integ);
    match order {
        Order::Five => with(f, s, st, integ, &mut Radau5::new(tol, 1e-5)),
        Order::Nine => with(f, s, st, integ, &mut RadauIIA::<NS, 5>::new(tol, 1e-5)),
    }
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
            let o = Integration::new(rtol, rtol * 1e-3, 5_000_000);
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
            let row = (median(cpu), median(ets.clone()), quantile(ets, 0.9), median(ees.clone()));
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
