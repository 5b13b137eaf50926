//! `gripopt moo-test`, `optimise`, `resume`.

use anyhow::{bail, Context, Result};
use gripopt::optim::testproblems::{run_test, TestProblem};

/// `gripopt moo-test NAME --seed S | --seeds A-B [--json]`.
pub fn moo_test(name: &str, seed: Option<u64>, seeds: Option<String>, json: bool, pop: usize, generations: Option<u64>) -> Result<()> {
    let probs: Vec<TestProblem> = if name.eq_ignore_ascii_case("all") {
        TestProblem::ALL.to_vec()
    } else {
        vec![TestProblem::parse(name).with_context(|| format!("unknown test problem `{name}` (expected one of {} or all)", TestProblem::ALL.map(|p| p.name()).join(", ")))?]
    };
    let seed_list: Vec<u64> = match (seed, seeds) {
        (Some(s), None) => vec![s],
        (None, Some(r)) => {
            let (a, b) = r.split_once('-').with_context(|| format!("--seeds `{r}`: expected a range A-B"))?;
            let a: u64 = a.trim().parse().with_context(|| format!("--seeds `{r}`: `{a}` is not a whole number"))?;
            let b: u64 = b.trim().parse().with_context(|| format!("--seeds `{r}`: `{b}` is not a whole number"))?;
            if a > b {
                bail!("--seeds `{r}`: empty range");
            }
            (a..=b).collect()
        }
        (None, None) => vec![1],
        (Some(_), Some(_)) => bail!("give --seed or --seeds, not both"),
    };
    for p in probs {
        let pb = indicatif::ProgressBar::new(seed_list.len() as u64);
        pb.set_style(indicatif::ProgressStyle::with_template("{msg} [{bar:25}] {pos}/{len} seeds").expect("template"));
        pb.set_message(p.name().to_string());
        if json {
            pb.set_draw_target(indicatif::ProgressDrawTarget::hidden());
        }
        let mut runs = vec![];
        for &s in &seed_list {
            let r = run_test(p, s, pop, generations);
            if json {
                println!("{}", serde_json::to_string(&r)?);
            }
            runs.push(r);
            pb.inc(1);
        }
        pb.finish_and_clear();
        if !json {
            let mut hv: Vec<f64> = runs.iter().map(|r| r.hv).collect();
            hv.sort_by(f64::total_cmp);
            let med = hv[hv.len() / 2];
            let (rm, lo, hi) = p.hv_band();
            let igd_med = {
                let mut v: Vec<f64> = runs.iter().map(|r| r.igd).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let wall: f64 = runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64;
            let verdict = if med >= lo && med <= hi { "inside" } else { "OUTSIDE" };
            println!(
                "{:<8} seeds {:>2}: HV median {:.5} [min {:.5}, max {:.5}]  reference median {} [{}, {}]: {verdict}; IGD median {:.3e}; {} evals, {:.3} s/run",
                p.name(), runs.len(), med, hv[0], hv[hv.len() - 1], rm, lo, hi, igd_med, runs[0].evaluations, wall
            );
        }
    }
    Ok(())
}

/// Print where the results are.
pub fn summary(s: &gripopt::optim::rundir::RunSummary) {
    let d = s.out.display();
    if s.interrupted {
        println!("interrupted after generation {} ({} evaluations); resume with `gripopt resume {d}`", s.generations, s.evaluations);
    } else {
        println!("finished: {} generations, {} evaluations in {:.1} s; {} feasible designs in the final population, {} on the Pareto front (hypervolume {:.4})", s.generations, s.evaluations, s.wall_s, s.feasible, s.front_size, s.hv);
    }
    println!("results in {d}/: pareto.csv (front), population.csv, history.csv, pareto_matrix.svg, hypervolume.svg, run.json, checkpoint.json");
}
