//! `gripopt bench …`: the arguments of the speed figures (not tests); the benchmarks
//! themselves are the library's `gripopt::app::bench`.

use anyhow::{Context as _, Result};
use clap::Subcommand;
use gripopt::app::bench::{AccuracyBench, EnsembleBench, FreeBench, ReplayBench, ScalingBench, WorkPrecision};
use gripopt::app::RecordOptions;
use std::path::PathBuf;

/// The design a table is about, and where it is written (`bench work-precision`, `bench free`).
#[derive(clap::Args)]
pub struct DesignTable {
    /// Problem file.
    #[arg(default_value = "problems/bottle-1l.toml")]
    problem: PathBuf,
    /// Design (default: the problem's nominal).
    #[arg(long)]
    design: Option<String>,
    /// Output folder.
    #[arg(long, default_value = "results/bench")]
    out: PathBuf,
}

impl DesignTable {
    /// The problem and the design; for a robust problem a note that `bench` (its name)
    /// evaluates the reference object only.
    fn load(&self, bench: &str) -> Result<(gripopt::app::Problem, gripopt::app::Design)> {
        let p = super::load_problem(&self.problem)?;
        robust_note(&p, &self.problem, bench);
        let x = super::design_of(&p, &self.design)?;
        Ok((p, x))
    }
}

/// As sweep and export say it: on a problem with [robust], a benchmark of one design's
/// grasp runs the reference [object] and [scene] only (its verdict is not the robust one).
fn robust_note(p: &gripopt::app::Problem, path: &std::path::Path, bench: &str) {
    if p.robust.is_some() {
        eprintln!(
            "note: {} has [robust]: bench {bench} evaluates the reference [object] and [scene] only; the robust objects and scenarios are not evaluated, and its verdict is not the robust one (`gripopt evaluate`, docs/robust.md)",
            super::out::path(path)
        );
    }
}

/// A benchmark's progress as the CLI shows it (the library reports it,
/// [`gripopt::app::bench::BenchProgress`]): an indicatif bar on stderr per phase, cleared when the
/// phase ends (drawn only on a terminal).
#[derive(Default)]
struct Bars(std::sync::Mutex<Option<indicatif::ProgressBar>>);

impl Bars {
    fn with(&self, f: impl FnOnce(&indicatif::ProgressBar)) {
        if let Some(pb) = self.0.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            f(pb);
        }
    }
}

impl gripopt::app::bench::BenchProgress for Bars {
    fn begin(&self, label: &str, len: u64, unit: &str) {
        let pb = indicatif::ProgressBar::new(len);
        pb.set_style(
            indicatif::ProgressStyle::with_template("{prefix} [{bar:30}] {pos}/{len} {msg}").expect("template"),
        );
        pb.set_prefix(label.to_string());
        pb.set_message(unit.to_string());
        if let Some(old) = self.0.lock().unwrap_or_else(|e| e.into_inner()).replace(pb) {
            old.finish_and_clear();
        }
    }
    fn message(&self, m: &str) {
        self.with(|pb| pb.set_message(m.to_string()));
    }
    fn step(&self) {
        self.with(|pb| pb.inc(1));
    }
    fn end(&self) {
        if let Some(pb) = self.0.lock().unwrap_or_else(|e| e.into_inner()).take() {
            pb.finish_and_clear();
        }
    }
}

/// A count flag that must be at least 1: refused with its name and value (exit 2).
fn at_least_one(flag: &str, v: usize) -> Result<()> {
    if v < 1 {
        anyhow::bail!("{flag} {v}: must be at least 1");
    }
    Ok(())
}

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
        /// Repetitions per size (at least 3 are run).
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
    /// Parallel efficiency of a fixed optimisation at 1, 2, … threads, where the time goes,
    /// and a list-scheduling prediction for 16 and 64 threads.
    Scaling {
        /// Problem file.
        #[arg(default_value = "problems/bottle-1l.toml")]
        problem: PathBuf,
        /// Population size.
        #[arg(long, default_value_t = 128)]
        pop: usize,
        /// Generations.
        #[arg(long, default_value_t = 10)]
        generations: u64,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Largest thread count (default: all cores).
        #[arg(long)]
        max_threads: Option<usize>,
        /// Thread counts to measure instead of 1, 2, … --max-threads (comma separated; 1 is always measured).
        #[arg(long, value_delimiter = ',')]
        threads: Vec<usize>,
        /// Repetitions per thread count.
        #[arg(long, default_value_t = 3)]
        reps: usize,
        /// Without recording.
        #[arg(long)]
        no_record: bool,
        /// Skip the hardware ceiling (n independent 1-thread runs at once, per thread count).
        #[arg(long)]
        no_ceiling: bool,
        /// Folder of the benchmark runs (deleted afterwards).
        #[arg(long, default_value = "results/bench/scaling-run")]
        out: PathBuf,
    },
    /// CPU time against error (t of first contact, impact energy, t_stab, final forces) for
    /// rtol 1e-3 … 1e-10 and each integrator; writes work_precision.csv and .svg.
    WorkPrecision {
        #[command(flatten)]
        target: DesignTable,
        /// Maximum repetitions per point: each point runs this many times, or stops after
        /// ~1 s once 3 ran (so 1 or 2 run exactly that often); the whole staged evaluation
        /// line runs max(this, 20) times.
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
        /// Relative tolerances of the table, comma-separated (not for --sample).
        #[arg(long, value_delimiter = ',', default_values_t = gripopt::app::bench::RTOLS, conflicts_with = "sample")]
        rtols: Vec<f64>,
    },
    /// The free scene (MODEL.md §14) of one design: CPU time, steps and evaluations against
    /// the error of its outputs, per rtol: RADAU5 with the block and the dense Jacobian, and
    /// the stiffness-switching method (auto); writes free_work_precision.csv and .svg.
    Free {
        #[command(flatten)]
        target: DesignTable,
        /// Maximum repetitions per point: each point runs this many times, or stops after
        /// ~1 s once 3 ran (so 1 or 2 run exactly that often; the CSV's `reps` says how many).
        #[arg(long, default_value_t = 100)]
        reps: usize,
        /// Absolute tolerance at every rtol (default: 1e-3·rtol).
        #[arg(long)]
        atol: Option<f64>,
        /// Relative tolerances, comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = gripopt::app::bench::FREE_RTOLS)]
        rtols: Vec<f64>,
        /// Leave out the dense-Jacobian rows (RADAU5 and auto with the block Jacobian only).
        #[arg(long)]
        no_dense: bool,
    },
    /// The accuracy rule (docs/benchmarks.md): solver settings against RADAU5 at rtol 1e-10,
    /// atol 1e-13 — verdicts over the grasp ensemble, its free scenes and a robust problem's
    /// scenarios, and the objectives' relative errors (p90 <= 5e-5, max <= 2e-3); writes
    /// accuracy.csv and accuracy_cases.csv (the reference is cached beside them).
    Accuracy {
        /// The grasp ensemble's problem.
        #[arg(long, default_value = "problems/bottle-1l.toml")]
        grasp_problem: PathBuf,
        /// The robust problem.
        #[arg(long, default_value = "problems/kitchen.toml")]
        robust_problem: PathBuf,
        /// Designs of the grasp ensemble (those of `bench work-precision --sample N`).
        #[arg(long, default_value_t = 40)]
        sample: usize,
        /// Designs of the robust ensemble (the kitchen front design of issue 40 first).
        #[arg(long, default_value_t = 30)]
        designs: usize,
        /// Seed of both ensembles.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Settings to check, comma-separated: `default` (each problem's own [solver]) or
        /// METHOD:RTOL[:ATOL] (the problem's atol where left out).
        #[arg(long, value_delimiter = ',', default_value = "default")]
        candidates: Vec<String>,
        /// Output folder.
        #[arg(long, default_value = "results/bench")]
        out: PathBuf,
    },
}

/// The flags of `bench scaling`, each on its own: the first one out of range is named with
/// its value and range (exit 2). Thread counts have the limit of `optimise --threads`.
fn check_scaling_flags(
    pop: usize,
    generations: u64,
    max_threads: Option<usize>,
    threads: &[usize],
    reps: usize,
) -> Result<()> {
    let max = gripopt::app::MAX_THREADS;
    if pop < 4 {
        anyhow::bail!("--pop {pop}: must be at least 4");
    }
    if generations < 1 {
        anyhow::bail!("--generations {generations}: must be at least 1");
    }
    if reps < 1 {
        anyhow::bail!("--reps {reps}: must be at least 1");
    }
    match max_threads {
        Some(m) if !(1..=max).contains(&m) => anyhow::bail!("--max-threads {m}: must be 1 to {max}"),
        _ => {}
    }
    if let Some(&t) = threads.iter().find(|&&t| !(1..=max).contains(&t)) {
        anyhow::bail!("--threads {t}: each thread count must be 1 to {max}");
    }
    Ok(())
}

/// The lock of a benchmark's output folder `dir` (created), held while the benchmark writes
/// its tables there: a held one is refused, naming the holder.
fn lock_out(dir: &std::path::Path) -> Result<gripopt::app::RunLock> {
    std::fs::create_dir_all(dir).map_err(|e| gripopt::Error::io(dir, "cannot create the output folder", e))?;
    Ok(gripopt::app::RunLock::acquire(dir)?)
}

/// The thread counts `bench scaling` times: those given (default: 1 to `max_threads`, else
/// the cores), always with 1, sorted, once each.
fn thread_counts(mut threads: Vec<usize>, max_threads: Option<usize>) -> Vec<usize> {
    if threads.is_empty() {
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        threads = (1..=max_threads.unwrap_or(cores)).collect();
    }
    threads.push(1);
    threads.sort_unstable();
    threads.dedup();
    threads
}

/// Run a benchmark: its text report on stdout, or with `json` the report on stderr and
/// the figures as one JSON object on stdout.
pub fn run(b: BenchCmd, json: bool) -> Result<()> {
    let (mut stdout, mut stderr) = (std::io::stdout().lock(), std::io::stderr().lock());
    let out: gripopt::app::bench::Out = if json { &mut stderr } else { &mut stdout };
    let bars = Bars::default();
    let summary = match b {
        BenchCmd::Static { problem, n, seed } => {
            at_least_one("--n", n)?;
            let p = super::load_problem(&problem)?;
            robust_note(&p, &problem, "static");
            gripopt::app::bench::static_pipeline(&p, &problem, n, seed, out, &bars)?
        }
        BenchCmd::Nsga { reps } => {
            at_least_one("--reps", reps)?;
            gripopt::app::bench::nsga(reps, out)?
        }
        BenchCmd::Replay { problem, designs, per_shard, out: dir, keep } => {
            let p = super::load_problem(&problem)?;
            gripopt::app::bench::replay(&p, &ReplayBench { designs, per_shard, out: dir, keep }, out, &bars)?
        }
        BenchCmd::Scaling {
            problem,
            pop,
            generations,
            seed,
            max_threads,
            threads,
            reps,
            no_record,
            no_ceiling,
            out: dir,
        } => {
            check_scaling_flags(pop, generations, max_threads, &threads, reps)?;
            let p = super::load_problem(&problem)?;
            let b = ScalingBench {
                pop,
                generations,
                seed,
                threads: thread_counts(threads, max_threads),
                reps,
                record: if no_record { RecordOptions::none() } else { RecordOptions::default() },
                predict: vec![2, 16, 64],
                ceiling: !no_ceiling,
            };
            gripopt::app::bench::scaling(&p, &b, &dir, out)?
        }
        BenchCmd::WorkPrecision { sample: Some(0), .. } => anyhow::bail!("--sample 0: must be at least 1"),
        BenchCmd::WorkPrecision { target, sample: Some(n), seed, atol, .. } => {
            gripopt::app::bench::check_atol(atol)?;
            let p = super::load_problem(&target.problem)?;
            robust_note(&p, &target.problem, "work-precision");
            let _lock = lock_out(&target.out)?;
            let b = EnsembleBench { sample: n, seed, out_dir: target.out, atol };
            gripopt::app::bench::work_precision_ensemble(&p, &target.problem, &b, out, &bars)?
        }
        BenchCmd::WorkPrecision { target, reps, atol, rtols, .. } => {
            at_least_one("--reps", reps)?;
            gripopt::app::bench::check_atol(atol)?;
            let (p, x) = target.load("work-precision")?;
            let _lock = lock_out(&target.out)?;
            gripopt::app::bench::work_precision(
                &p,
                &x,
                &WorkPrecision { out_dir: target.out, reps, atol, rtols },
                out,
                &bars,
            )?
        }
        BenchCmd::Free { target, reps, atol, rtols, no_dense } => {
            at_least_one("--reps", reps)?;
            let (p, x) = target.load("free")?;
            let _lock = lock_out(&target.out)?;
            let table = WorkPrecision { out_dir: target.out, reps, atol, rtols };
            gripopt::app::bench::free_scene(&p, &x, &FreeBench { table, dense: !no_dense }, out, &bars)?
        }
        BenchCmd::Accuracy { grasp_problem, robust_problem, sample, designs, seed, candidates, out: dir } => {
            at_least_one("--sample", sample)?;
            at_least_one("--designs", designs)?;
            let candidates = candidates
                .iter()
                .map(|c| gripopt::app::bench::Candidate::parse(c))
                .collect::<gripopt::Result<Vec<_>>>()?;
            let gp = super::load_problem(&grasp_problem)?;
            let rp = super::load_problem(&robust_problem)?;
            let b = AccuracyBench { sample, robust_designs: designs, seed, candidates, out_dir: dir };
            gripopt::app::bench::accuracy(&gp, &grasp_problem, &rp, &robust_problem, &b, out, &bars)?
        }
    };
    if json {
        // as every other stdout write of the CLI: a failure names standard output (a full
        // disk would otherwise read like a failed CSV or SVG write of the bench)
        use std::io::Write as _;
        let text = serde_json::to_string_pretty(&summary)?;
        writeln!(stdout, "{text}").and_then(|_| stdout.flush()).context("cannot write to standard output")?;
    }
    Ok(())
}
