//! `gripopt bench …`: speed figures (not tests).

use anyhow::Result;
use clap::Subcommand;
use std::path::PathBuf;

/// Benchmarks.
#[derive(Subcommand)]
pub enum BenchCmd {
    /// Static pipeline (stages 0–2) throughput on one core over random designs in the bounds.
    Static {
        /// Problem file.
        #[arg(default_value = "problems/bottle-1l.toml")]
        problem: PathBuf,
        /// Number of random designs.
        #[arg(long, default_value_t = 100_000)]
        n: usize,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Non-dominated sort + crowding on random sets, and the optimiser's own overhead per
    /// generation on ZDT1 (everything but evaluation).
    Nsga {
        /// Repetitions per size.
        #[arg(long, default_value_t = 30)]
        reps: usize,
    },
    /// CPU time against error (t of first contact, impact energy, t_stab, final forces) for
    /// rtol 1e-3 … 1e-10 and each integrator; writes work_precision.csv and .svg.
    WorkPrecision {
        /// Problem file.
        #[arg(default_value = "problems/bottle-1l.toml")]
        problem: PathBuf,
        /// Design (default: the problem's nominal).
        #[arg(long)]
        design: Option<String>,
        /// Output folder.
        #[arg(long, default_value = "results/bench")]
        out: PathBuf,
        /// Maximum repetitions per point (each point also stops after ~1 s).
        #[arg(long, default_value_t = 200)]
        reps: usize,
    },
}

/// Run a benchmark.
pub fn run(b: BenchCmd) -> Result<()> {
    match b {
        BenchCmd::Static { problem, n, seed } => bench_static(&problem, n, seed),
        BenchCmd::Nsga { reps } => bench_nsga(reps.max(3)),
        BenchCmd::WorkPrecision { problem, design, out, reps } => {
            let p = super::load_problem(&problem)?;
            let x = super::design_of(&p, &design)?;
            super::workprec::run(&problem, x, &out, reps)
        }
    }
}

fn bench_static(problem: &PathBuf, n: usize, seed: u64) -> Result<()> {
    use gripopt::pipeline::{evaluate, EvalOptions};
    use gripopt::problem::Design;
    use rand::{Rng, SeedableRng};
    let p = super::load_problem(problem)?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let designs: Vec<Design> = (0..n)
        .map(|_| {
            let mut x = [0.0; 6];
            for i in 0..6 {
                x[i] = rng.random_range(p.bounds.lo[i]..=p.bounds.hi[i]);
            }
            Design::from_array(&x)
        })
        .collect();
    let opts = EvalOptions::statics_only();
    let mut counts = [0usize; 4];
    let mut feasible = 0usize;
    let mut times = Vec::new();
    let pb = indicatif::ProgressBar::new(5);
    pb.set_style(indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} repetitions").unwrap());
    pb.set_message("bench static");
    for rep in 0..5 {
        let t0 = std::time::Instant::now();
        for x in &designs {
            let ev = evaluate(x, &p.scene, &opts);
            if rep == 0 {
                match ev.discard {
                    Some(d) => counts[d.stage as usize] += 1,
                    None => feasible += 1,
                }
            }
            std::hint::black_box(&ev);
        }
        times.push(t0.elapsed().as_secs_f64());
        pb.inc(1);
    }
    pb.finish_and_clear();
    times.sort_by(f64::total_cmp);
    let (tmin, tmed) = (times[0], times[times.len() / 2]);
    println!("static pipeline (stages 0-2), {} random designs in the bounds of {}, seed {seed}, 1 thread, 5 repetitions", n, problem.display());
    println!("  designs/s: min-time {:.0}  median-time {:.0}   ({:.2} us/design at min)", n as f64 / tmin, n as f64 / tmed, tmin / n as f64 * 1e6);
    for (s, c) in counts.iter().enumerate() {
        println!("  discarded at stage {s}: {c} ({:.1} %)", 100.0 * *c as f64 / n as f64);
    }
    println!("  passed stage 2: {feasible} ({:.1} %)", 100.0 * feasible as f64 / n as f64);
    Ok(())
}

fn min_med(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

fn bench_nsga(reps: usize) -> Result<()> {
    use gripopt::optim::sort::rank_and_crowding;
    use gripopt::optim::Infeasibility;
    use rand::{Rng, SeedableRng};
    println!("non-dominated sort + crowding distance, uniform random points, 1 thread, {reps} repetitions (min / median)");
    for m in [2usize, 4] {
        for n in [200usize, 1000, 10000] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64 + m as u64);
            let pts: Vec<Vec<f64>> = (0..n).map(|_| (0..m).map(|_| rng.random::<f64>()).collect()).collect();
            let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
            let cv = vec![Infeasibility::FEASIBLE; n];
            let mut ts = vec![];
            for _ in 0..reps {
                let t0 = std::time::Instant::now();
                std::hint::black_box(rank_and_crowding(&f, &cv));
                ts.push(t0.elapsed().as_secs_f64());
            }
            let (a, b) = min_med(ts);
            println!("  {m} objectives, {n:>5} points: {:.3} / {:.3} ms", a * 1e3, b * 1e3);
        }
    }
    // optimiser overhead on ZDT1: whole run minus evaluation time, per generation
    use gripopt::optim::testproblems::{reference_settings, TestProblem};
    use gripopt::optim::MooProblem;
    let which = TestProblem::Zdt1;
    let gens = 250u64;
    let mut per_gen = vec![];
    let inst = which.instance();
    let x: Vec<f64> = vec![0.5; 30];
    let t0 = std::time::Instant::now();
    let k = 100_000;
    for _ in 0..k {
        std::hint::black_box(inst.evaluate(std::hint::black_box(&x)));
    }
    let eval_s = t0.elapsed().as_secs_f64() / k as f64;
    for rep in 0..reps.min(10) {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
        let t0 = std::time::Instant::now();
        pool.install(|| {
            use argmin::core::State;
            let st = gripopt::optim::nsga2::Nsga2State::new().with_max_generations(gens);
            let mut s = reference_settings(which, rep as u64 + 1, 100);
            s.hv_ref.clear();
            gripopt::optim::run::execute(which.instance(), s, st, |e| e, false)
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let total = t0.elapsed().as_secs_f64();
        per_gen.push((total - eval_s * 100.0 * gens as f64) / gens as f64);
    }
    let (a, b) = min_med(per_gen);
    println!("NSGA-II overhead per generation on ZDT1 (pop 100, 250 generations, 1 thread, evaluation time {:.2} us/eval subtracted): {:.3} / {:.3} ms", eval_s * 1e6, a * 1e3, b * 1e3);
    Ok(())
}
