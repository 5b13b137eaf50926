//! `gripopt bench …`: speed figures (not tests).

use anyhow::{Context, Result};
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
    /// Replay speed in a synthetic run of many recorded designs.
    Replay {
        /// Problem file.
        #[arg(default_value = "problems/bottle-1l.toml")]
        problem: PathBuf,
        /// Recorded designs.
        #[arg(long, default_value_t = 100_000)]
        designs: u64,
        /// Designs per shard.
        #[arg(long, default_value_t = 1000)]
        per_shard: u64,
        /// Folder of the synthetic run (deleted afterwards unless --keep).
        #[arg(long, default_value = "results/bench/replay-run")]
        out: PathBuf,
        /// Keep the synthetic run.
        #[arg(long)]
        keep: bool,
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
        /// Instead of one design: an ensemble of this many random designs of the box that
        /// pass stage 2 (seeded), reporting median and 90th-percentile errors per rtol.
        #[arg(long, conflicts_with = "design")]
        sample: Option<usize>,
        /// Seed of the ensemble.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Absolute tolerance on angles and rates, fixed for every rtol (default: 1e-3·rtol).
        #[arg(long)]
        atol: Option<f64>,
    },
}

/// Run a benchmark.
pub fn run(b: BenchCmd) -> Result<()> {
    match b {
        BenchCmd::Static { problem, n, seed } => bench_static(&problem, n, seed),
        BenchCmd::Nsga { reps } => bench_nsga(reps.max(3)),
        BenchCmd::Replay { problem, designs, per_shard, out, keep } => bench_replay(&problem, designs, per_shard.max(1), &out, keep),
        BenchCmd::WorkPrecision { sample: Some(0), .. } => anyhow::bail!("--sample 0: must be at least 1"),
        BenchCmd::WorkPrecision { atol: Some(a), .. } if !(a > 0.0 && a.is_finite()) => anyhow::bail!("--atol {a}: must be a positive number"),
        BenchCmd::WorkPrecision { problem, sample: Some(n), seed, out, atol, .. } => super::workprec::run_ensemble(&problem, n, seed, &out, atol),
        BenchCmd::WorkPrecision { problem, design, out, reps, atol, .. } => {
            let p = super::load_problem(&problem)?;
            let x = super::design_of(&p, &design)?;
            super::workprec::run(&problem, x, &out, reps, atol)
        }
    }
}

fn bench_static(problem: &PathBuf, n: usize, seed: u64) -> Result<()> {
    use gripopt::eval::{evaluate, EvalOptions};
    use gripopt::params::Design;
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
            gripopt::optim::nsga2::execute(which.instance(), s, st, |e| e, false)
        })
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        let total = t0.elapsed().as_secs_f64();
        per_gen.push((total - eval_s * 100.0 * gens as f64) / gens as f64);
    }
    let (a, b) = min_med(per_gen);
    println!("NSGA-II overhead per generation on ZDT1 (pop 100, 250 generations, 1 thread, evaluation time {:.2} us/eval subtracted): {:.3} / {:.3} ms", eval_s * 1e6, a * 1e3, b * 1e3);
    Ok(())
}

fn bench_replay(problem: &PathBuf, n: u64, per_shard: u64, out: &std::path::Path, keep: bool) -> Result<()> {
    use gripopt::run::gripper::{GripperProblem, TrajectoryKeep};
    use gripopt::optim::{Individual, MooProblem};
    use gripopt::record::writer::{write_shard, ShardEntry};
    use rand::{Rng, SeedableRng};
    let p = super::load_problem(problem)?;
    if out.exists() {
        std::fs::remove_dir_all(out).with_context(|| format!("cannot clear {}", out.display()))?;
    }
    let rec_dir = out.join("recording");
    std::fs::create_dir_all(&rec_dir).with_context(|| format!("cannot create {}", rec_dir.display()))?;
    std::fs::write(out.join("problem.toml"), &p.source_text)?;
    let opts = gripopt::record::RecordOptions { scene_dt: 0.0, ..Default::default() };
    std::fs::write(out.join("run.json"), serde_json::to_string_pretty(&serde_json::json!({ "synthetic": true, "recording": opts }))?)?;
    // the nominal design's real evaluation and recorded grasp, under every id
    let mut gp = GripperProblem::new(p.clone());
    gp.keep_trajectories = TrajectoryKeep::All;
    let x = p.nominal.to_array().to_vec();
    let eval = gp.evaluate(&x);
    let samples = eval.info.trajectory.as_ref().map_or(0, |t| t.samples.len());
    let meta = std::collections::BTreeMap::from([("synthetic".to_string(), "gripopt bench replay".to_string())]);
    let t0 = std::time::Instant::now();
    let shards = n.div_ceil(per_shard);
    let pb = indicatif::ProgressBar::new(shards);
    pb.set_style(indicatif::ProgressStyle::with_template("writing synthetic run [{bar:30}] {pos}/{len} shards").expect("template"));
    let mut index = String::new();
    let mut bytes = 0u64;
    for k in 0..shards {
        let ids = (k * per_shard)..((k + 1) * per_shard).min(n);
        let inds: Vec<Individual<_>> = ids.clone().map(|id| Individual { id, generation: k + 1, x: x.clone(), eval: eval.clone() }).collect();
        let refs: Vec<&Individual<_>> = inds.iter().collect();
        let file = format!("gen-{:05}.mcap", k + 1);
        let b = write_shard(&rec_dir.join(&file), &p, &meta, &refs, &opts)?;
        bytes += b;
        index.push_str(&serde_json::to_string(&ShardEntry { generation: k + 1, file, first_id: ids.start, last_id: ids.end - 1, designs: ids.end - ids.start, bytes: b })?);
        index.push('\n');
        pb.inc(1);
    }
    pb.finish_and_clear();
    std::fs::write(rec_dir.join("index.jsonl"), index)?;
    let write_s = t0.elapsed().as_secs_f64();
    println!("synthetic run: {n} designs ({samples} trajectory samples each) in {shards} shards, {:.1} MB, written in {:.1} s", bytes as f64 / 1e6, write_s);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut t_read, mut t_full) = (vec![], vec![]);
    for _ in 0..50 {
        let id = rng.random_range(0..n);
        let a = std::time::Instant::now();
        let r = gripopt::record::replay::read_design(out, id)?;
        t_read.push(a.elapsed().as_secs_f64());
        anyhow::ensure!(r.record["id"].as_u64() == Some(id), "wrong design returned");
        let a = std::time::Instant::now();
        let rp = gripopt::record::replay::replay(out, id)?;
        t_full.push(a.elapsed().as_secs_f64());
        anyhow::ensure!(rp.verified, "design {id} did not verify");
    }
    let (r0, r1) = min_med(t_read);
    let (f0, f1) = min_med(t_full);
    println!("find + read one design (index, MCAP summary, one chunk): {:.2} / {:.2} ms (min / median of 50 random ids)", r0 * 1e3, r1 * 1e3);
    println!("replay (find, read, re-simulate, verify):               {:.2} / {:.2} ms", f0 * 1e3, f1 * 1e3);
    if !keep {
        std::fs::remove_dir_all(out).with_context(|| format!("cannot remove {}", out.display()))?;
    }
    Ok(())
}
