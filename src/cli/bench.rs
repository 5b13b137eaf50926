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
