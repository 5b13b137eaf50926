//! `gripopt bench scaling`: parallel efficiency of a fixed optimisation on this machine, where
//! its time goes, and a list-scheduling prediction for many cores.
//!
//! Each run is the pipeline of `gripopt optimise` (recorder, background persister writing
//! shard k then checkpoint k, NSGA-II in a pool of n threads) with a timing observer. From
//! the measured per-design costs, the solver's serial time and the persister's time per
//! generation, each generation is replayed on P simulated threads: every design's cheap
//! start (stages 0–2), then the rest list scheduled in the order the solver used (its cost
//! model's: predicted longest first, the same at any thread count), the serial step
//! follows, and the persister works through the shards as a pipeline beside it (one
//! generation queued). The predicted time is the larger of that schedule and the total work
//! divided by P, so the prediction is an upper bound on efficiency.

use super::say;
use crate::optim::{execute, observe, Nsga2, Nsga2Settings, Nsga2State, Operators};
use crate::params::Problem;
use crate::record::{RecordOptions, Recorder};
use crate::run::{
    Archive, CheckpointSpec, GripperInfo, GripperProblem, OutputsObserver, PersistStats, Persister, VIEWS_MIN_INTERVAL,
};
use crate::{Error, Result};
use argmin::core::observers::Observe;
use argmin::core::{State, KV};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// What to run.
#[derive(Debug, Clone)]
pub struct ScalingBench {
    /// Population size.
    pub pop: usize,
    /// Generations.
    pub generations: u64,
    /// Seed.
    pub seed: u64,
    /// Thread counts measured (ascending, starting with 1).
    pub threads: Vec<usize>,
    /// Repetitions per thread count (min and median reported).
    pub reps: usize,
    /// Recording options (default: the defaults of `gripopt optimise`).
    pub record: RecordOptions,
    /// Thread counts to predict.
    pub predict: Vec<usize>,
    /// Also measure the hardware's ceiling: n independent 1-thread runs at once (at n ≥ 2;
    /// at 1 thread it is 100 % by definition and not measured).
    pub ceiling: bool,
}

/// One generation as measured.
#[derive(Debug, Clone, Default)]
struct Gen {
    costs: Vec<f64>,
    start_costs: Vec<f64>,
    order: Vec<usize>,
    costly: usize,
    eval_s: f64,
    serial_s: f64,
    hv_s: f64,
    order_s: f64,
}

/// One measured run.
#[derive(Debug, Clone, Default)]
struct Measured {
    wall_s: f64,
    gens: Vec<Gen>,
    persist: PersistStats,
}

#[derive(Clone)]
struct Timer(Arc<Mutex<Vec<Gen>>>);

impl Observe<Nsga2State<GripperInfo>> for Timer {
    fn observe_init(
        &mut self,
        _n: &str,
        st: &Nsga2State<GripperInfo>,
        kv: &KV,
    ) -> std::result::Result<(), argmin::core::Error> {
        self.observe_iter(st, kv)
    }
    fn observe_iter(&mut self, st: &Nsga2State<GripperInfo>, _kv: &KV) -> std::result::Result<(), argmin::core::Error> {
        let mut g = self.0.lock().expect("timer");
        let t = &st.timing;
        g.push(Gen {
            costs: t.costs.clone(),
            start_costs: t.start_costs.clone(),
            order: t.order.clone(),
            costly: t.costly,
            eval_s: t.eval_s,
            serial_s: t.serial_s,
            hv_s: t.hv_s,
            order_s: t.order_s,
        });
        Ok(())
    }
}

fn run_once(problem: &Problem, b: &ScalingBench, threads: usize, dir: &Path) -> Result<Measured> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "cannot create the benchmark run folder", e))?;
    let start = Instant::now();
    let mut gp = GripperProblem::new(problem.clone());
    if b.record.enabled {
        gp.recording = b.record;
    }
    let (ideal, r) = gp.hv_points();
    let settings = Nsga2Settings {
        pop_size: b.pop,
        seed: b.seed,
        operators: Operators::default(),
        eliminate_duplicates: true,
        hv_ideal: ideal,
        hv_ref: r,
    };
    let recorder = if b.record.enabled {
        Some(Arc::new(Mutex::new(Recorder::open(dir, problem.clone(), Default::default(), b.record, 0)?)))
    } else {
        None
    };
    let spec = CheckpointSpec {
        path: dir.join("checkpoint.json"),
        problem_hash: String::new(),
        settings: settings.clone(),
        options: crate::run::RunOptions::of(&problem.solver, &b.record),
        wall_before: 0.0,
        start,
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let outputs = OutputsObserver {
        out: dir.to_path_buf(),
        settings: settings.clone(),
        archive: Arc::new(Mutex::new(Archive::default())),
    };
    let persister = Persister::start(Some(outputs), recorder, spec, threads)?;
    let timer = Arc::new(Mutex::new(Vec::new()));
    let (p2, t1) = (persister.clone(), Timer(timer.clone()));
    let state = Nsga2State::new().with_max_generations(b.generations);
    let res = pool.install(|| execute(gp, Nsga2::new(settings), state, move |e| observe(observe(e, t1), p2)));
    let persist = persister.finish()?;
    res?;
    let wall_s = start.elapsed().as_secs_f64();
    let gens = std::mem::take(&mut *timer.lock().expect("timer"));
    Ok(Measured { wall_s, gens, persist })
}

/// Greedy list schedule of `costs` (in the given order) on `p` threads: the makespan.
fn makespan(costs: &[f64], p: usize) -> f64 {
    let mut free = vec![0.0f64; p.max(1)];
    for &c in costs {
        let (k, _) = free.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).expect("p ≥ 1");
        free[k] += c;
    }
    free.into_iter().fold(0.0, f64::max)
}

/// A prediction at some thread count.
struct Prediction {
    /// Predicted wall time (s).
    t: f64,
    /// All the work on one core (s).
    work: f64,
    /// The largest loss.
    what: &'static str,
    /// Efficiency of the evaluation alone, longest first.
    lpt: f64,
    /// Finish passes summed over the generations (s): the solver's order, classes only, longest first.
    ordering: [f64; 3],
}

/// Prediction at `p` threads. The per-design costs and the serial steps are as measured.
/// The persister's thread updates the archive and commits (its time per generation is
/// serial); the shards and the checkpoints' serialisation go to its pool of p/4 threads,
/// several at once (each shard's time taken as serial within it, which is conservative);
/// the CSV views follow their time rule, their files in parallel in the pool.
fn predict(m: &Measured, p: usize, recording: bool) -> Prediction {
    let n = m.gens.len().max(1) as f64;
    let pool = (p / 4).max(1) as f64;
    // the archive's update runs in the pool (its hypervolume in parallel): taken as spread
    // over the pool's threads; the commit is serial on the persister thread; shards and
    // checkpoints are serialised in the pool; the CSV views follow their time rule (below)
    let ps = &m.persist;
    let archive = ps.archive_s;
    let pool_g = if recording { ps.record_s } else { 0.0 } + ps.checkpoint_pool_s;
    let persist_g =
        ((ps.outputs_s - ps.views_s - archive + archive / pool + ps.checkpoint_s) / n).max(pool_g / n / pool);
    let handover_g = ps.handover_s / n;
    let persist_work_g =
        (if recording { ps.record_s } else { 0.0 } + ps.outputs_s + ps.checkpoint_s + ps.checkpoint_pool_s) / n;
    let (mut main_t, mut prev_start, mut prev_finish) = (0.0f64, 0.0f64, 0.0f64);
    let (mut strag, mut serial, mut work, mut waited) = (0.0, 0.0, 0.0, 0.0);
    // the same generations with every design's cost known in advance (longest first): the
    // best any order could do, so what is left is the designs' own costs
    let (mut lpt_t, mut eval_sum) = (0.0, 0.0);
    let mut ordering = [0.0; 3];
    for g in &m.gens {
        // the solver's two passes: every design's start (fine-grained, index order), then
        // the rest in the solver's order (its cost model's, the same at any thread count)
        let finish: Vec<f64> =
            g.order.iter().map(|&i| g.costs[i] - g.start_costs.get(i).copied().unwrap_or(0.0)).collect();
        let sum: f64 = g.costs.iter().sum();
        let ms = makespan(&g.start_costs, p) + makespan(&finish, p);
        // the finish pass in the solver's order, in its classes only (costly then cheap,
        // each by index: no cost model) and longest first
        let mut classes: Vec<usize> = g.order[..g.costly.min(g.order.len())].to_vec();
        classes.sort_unstable();
        let mut rest: Vec<usize> = g.order[classes.len()..].to_vec();
        rest.sort_unstable();
        classes.extend(rest);
        let fin = |i: usize| g.costs[i] - g.start_costs.get(i).copied().unwrap_or(0.0);
        let mut longest: Vec<f64> = (0..g.costs.len()).map(fin).collect();
        longest.sort_by(|a, b| b.total_cmp(a));
        let classes: Vec<f64> = classes.into_iter().map(fin).collect();
        ordering[0] += makespan(&finish, p);
        ordering[1] += makespan(&classes, p);
        ordering[2] += makespan(&longest, p);
        let mut lpt = g.costs.clone();
        lpt.sort_by(|a, b| b.total_cmp(a));
        lpt_t += makespan(&lpt, p);
        eval_sum += sum;
        strag += ms - sum / p as f64;
        let ser = g.serial_s + handover_g;
        serial += ser;
        work += sum + ser + persist_work_g;
        main_t += ms + ser;
        // hand-over: waits while the previous generation is still queued (capacity 1)
        waited += (prev_start - main_t).max(0.0);
        main_t = main_t.max(prev_start);
        prev_start = main_t.max(prev_finish);
        prev_finish = prev_start + persist_g;
    }
    // the views: written at most every VIEWS_MIN_INTERVAL and after the last generation,
    // their five files in parallel in the pool (never faster than the longest file), all
    // taken as on the critical path
    let written = ps.views_written.max(1) as f64;
    let per_view = (ps.views_longest_s / written).max(ps.views_files_s / written / pool);
    let writes = (1.0 + (prev_finish / VIEWS_MIN_INTERVAL.as_secs_f64()).floor()).min(n);
    prev_finish += writes * per_view;
    let t = prev_finish.max(work / p as f64);
    let persister = waited + (prev_finish - main_t).max(0.0);
    let losses = [(strag, "waiting for the slowest design of each generation"), (serial, "the serial step between generations (solver + hand-over)"), (persister, "the persister (per generation: archive and commit on its thread; shards and checkpoints serialised in its pool; the CSV views)")];
    let what = losses.iter().copied().fold((f64::MIN, ""), |a, b| if b.0 > a.0 { b } else { a }).1;
    Prediction { t, work, what, lpt: eval_sum / (p as f64 * lpt_t.max(1e-300)), ordering }
}

/// `best` with each design's cost (and each generation's serial time) replaced by its
/// minimum over the repetitions `runs`: the same seed evaluates the same designs in the
/// same order, so the minimum removes the machine's noise (a design interrupted by another
/// process) from the costs the prediction schedules.
fn per_design_min(mut best: Measured, runs: &[Measured]) -> Measured {
    for (gi, g) in best.gens.iter_mut().enumerate() {
        let same: Vec<&Gen> =
            runs.iter().filter_map(|r| r.gens.get(gi)).filter(|o| o.costs.len() == g.costs.len()).collect();
        for (k, c) in g.costs.iter_mut().enumerate() {
            *c = same.iter().map(|o| o.costs[k]).fold(*c, f64::min);
        }
        for (k, c) in g.start_costs.iter_mut().enumerate() {
            *c = same.iter().filter_map(|o| o.start_costs.get(k)).fold(*c, |a, &b| a.min(b));
        }
        g.serial_s = same.iter().map(|o| o.serial_s).fold(g.serial_s, f64::min);
    }
    best
}

fn min_med(v: &[f64]) -> (f64, f64) {
    super::min_med(v.to_vec())
}

/// Run the benchmark: prints the table and the prediction; `dir` holds the run folders
/// (deleted afterwards).
pub fn scaling(problem: &Problem, b: &ScalingBench, dir: &Path, out: super::Out) -> Result<serde_json::Value> {
    // each setting on its own, named with its value and range
    let bad = |m: String| Err(Error::Input(format!("bench scaling: {m}")));
    if b.pop < 4 {
        return bad(format!("--pop {}: must be at least 4", b.pop));
    }
    if b.generations < 1 {
        return bad(format!("--generations {}: must be at least 1", b.generations));
    }
    if b.reps < 1 {
        return bad(format!("--reps {}: must be at least 1", b.reps));
    }
    if let Some(t) = b.threads.iter().find(|&&t| t == 0) {
        return bad(format!("--threads {t}: each thread count must be at least 1"));
    }
    if b.threads.first() != Some(&1) || !b.threads.windows(2).all(|w| w[0] < w[1]) {
        return bad(format!("thread counts {:?}: must be ascending and start with 1 (the reference)", b.threads));
    }
    // the benchmark's own run folders go below `dir`, new or empty and locked while it runs:
    // what it removes afterwards is only what this process made there (a name such as `t1`
    // proves nothing: an earlier benchmark's leftovers are refused, never deleted)
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "cannot create the benchmark folder", e))?;
    let lock = crate::fsutil::lock::RunLock::acquire(dir)?;
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list", e))?;
    if let Some(other) =
        rd.flatten().map(|e| e.file_name().to_string_lossy().to_string()).find(|n| n != crate::fsutil::lock::LOCK_FILE)
    {
        return Err(Error::RunDir { path: dir.to_path_buf(), message: format!("holds `{other}`: `gripopt bench scaling` writes into a new or empty folder and removes only what it made (an earlier benchmark that did not finish left it? remove it yourself): choose another --out (nothing was deleted)") });
    }
    let mut rows = vec![];
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    say!(out,
        "bench scaling: pop {} × {} generations, seed {}, recording {}, {} repetitions (min / median wall s); load average {}",
        b.pop,
        b.generations,
        b.seed,
        if b.record.enabled { "on (defaults)" } else { "off" },
        b.reps,
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    say!(out, "threads  wall min / med   eff(min)  ceiling  of ceil.  work    eval    strag.  serial  hand-over  out.(bg)  rec.(bg)  ckpt(bg)  waited");
    let mut t1 = None;
    let mut best: Option<Measured> = None;
    for &n in &b.threads {
        let mut runs = vec![];
        for _ in 0..b.reps {
            runs.push(run_once(problem, b, n, &dir.join(format!("t{n}")))?);
        }
        // the hardware's ceiling: n independent 1-thread runs at once (nothing shared but the
        // machine: clock, caches, memory); their wall time over one run's
        // at 1 thread the ceiling is 100 % by definition (T1 over one independent 1-thread
        // run is the same measurement twice): not measured, shown as "-" (null in JSON)
        let mut indep = vec![];
        for _ in 0..if b.ceiling && n > 1 { b.reps } else { 0 } {
            let t = Instant::now();
            std::thread::scope(|sc| {
                let hs: Vec<_> = (0..n)
                    .map(|k| {
                        sc.spawn(move || run_once(problem, b, 1, &dir.join(format!("t{n}")).join(format!("c{k}"))))
                    })
                    .collect();
                hs.into_iter()
                    .map(|h| h.join().map_err(|_| Error::Optimiser("a ceiling run panicked".into()))?.map(|_| ()))
                    .collect::<Result<Vec<()>>>()
            })?;
            indep.push(t.elapsed().as_secs_f64());
        }
        let walls: Vec<f64> = runs.iter().map(|r| r.wall_s).collect();
        let (mn, md) = min_med(&walls);
        let r = runs.iter().min_by(|a, b| a.wall_s.total_cmp(&b.wall_s)).expect("reps ≥ 1").clone();
        let t1v = *t1.get_or_insert(mn);
        // efficiency the hardware allows (T1 / wall of n independent runs), and how much of it is reached
        let ceil = (!indep.is_empty()).then(|| t1v / min_med(&indep).0);
        let of_ceil = ceil.map(|c| t1v / (n as f64 * mn) / c);
        let pct = |v: Option<f64>| v.map_or(format!("{:>8}", "-"), |v| format!("{:>6.1} %", 100.0 * v));
        let eval: f64 = r.gens.iter().map(|g| g.eval_s).sum();
        let work: f64 = r.gens.iter().flat_map(|g| g.costs.iter()).sum();
        let strag: f64 = r.gens.iter().map(|g| g.eval_s - g.costs.iter().sum::<f64>() / n as f64).sum();
        let serial: f64 = r.gens.iter().map(|g| g.serial_s).sum();
        let p = r.persist;
        say!(out,
            "{n:>7}  {mn:>6.3} / {md:>6.3}   {:>6.1} %  {} {}  {work:>6.3}  {eval:>6.3}  {strag:>6.3}  {serial:>6.3}  {:>9.3}  {:>8.3}  {:>8.3}  {:>8.3}  {:>6.3}",
            100.0 * t1v / (n as f64 * mn),
            pct(ceil),
            pct(of_ceil),
            p.handover_s,
            p.outputs_s,
            p.record_s,
            p.checkpoint_s,
            p.wait_s
        );
        rows.push(serde_json::json!({
            "threads": n, "wall_min_s": mn, "wall_median_s": md, "efficiency_min": t1v / (n as f64 * mn), "ceiling_efficiency": ceil, "of_ceiling": of_ceil,
            "independent_wall_s": indep, "work_s": work, "eval_s": eval,
            "straggler_s": strag, "serial_s": serial, "handover_s": p.handover_s, "outputs_bg_s": p.outputs_s, "record_bg_s": p.record_s,
            "checkpoint_bg_s": p.checkpoint_s, "archive_bg_s": p.archive_s, "waited_s": p.wait_s, "views_skipped": p.views_skipped, "views_written": p.views_written, "views_s": p.views_s, "views_files_s": p.views_files_s, "views_longest_s": p.views_longest_s, "checkpoint_pool_s": p.checkpoint_pool_s, "persist_pool_threads": p.pool_threads,
        }));
        if n == 1 {
            best = Some(per_design_min(r, &runs));
        }
    }
    for n in &b.threads {
        let _ = std::fs::remove_dir_all(dir.join(format!("t{n}")));
    }
    drop(lock);
    let _ = std::fs::remove_dir(dir); // only if now empty
    say!(out, "(ceiling: T1 over the wall time of n independent 1-thread runs at once, the efficiency the machine itself allows, - at 1 thread where it is 100 % by definition; of ceil.: eff(min) / ceiling;");
    say!(out, " work: sum of the designs' evaluation times; eval: wall of the parallel evaluation; strag.: of it, waiting beyond the mean work per thread; serial: the solver's own step;");
    say!(out, " hand-over: cloning each generation for the persister; out./rec./ckpt: the persister's background wall time (outputs, shards, checkpoints); waited: backpressure + final flush)");
    let m = best.expect("one thread measured");
    let (hv, order): (f64, f64) = (m.gens.iter().map(|g| g.hv_s).sum(), m.gens.iter().map(|g| g.order_s).sum());
    say!(out, "1 thread: of the serial step, the exact hypervolume took {hv:.3} s; the first pass (stages 0–2 of every design, and ordering) {order:.3} s of the evaluation");
    let on = b.record.enabled;
    say!(out, "prediction from the 1-thread runs' per-design costs (each design's minimum over the repetitions; list scheduling of each generation, persister pipelined beside it; efficiency against all the work on one core):");
    let mut predictions = vec![];
    for &p in &b.predict {
        let Prediction { t, work, what, lpt, ordering: o } = predict(&m, p, on);
        // how much of the gap between no cost model and every cost known the model closes
        let closed = if o[1] > o[2] {
            format!("{:.0} % of that gap closed", 100.0 * (o[1] - o[0]) / (o[1] - o[2]))
        } else {
            "no gap to close".to_string()
        };
        predictions.push(serde_json::json!({ "threads": p, "wall_s": t, "efficiency": work / (p as f64 * t), "limited_by": what, "evaluation_efficiency_longest_first": lpt,
            "finish_pass_s": { "cost_model_order": o[0], "classes_only": o[1], "longest_first": o[2] } }));
        let w = |e: std::io::Error| Error::io("<benchmark report>", "cannot write the report", e);
        write!(out, "  {p:>3} threads: {t:.3} s, efficiency {:.1} %, limited by {what}", 100.0 * work / (p as f64 * t))
            .map_err(w)?;
        write!(out, "; the evaluation alone with every cost known in advance (longest first): {:.1} %", 100.0 * lpt)
            .map_err(w)?;
        if on {
            let q = predict(&m, p, false);
            write!(
                out,
                "; if recording took no time: {:.1} %, limited by {}",
                100.0 * q.work / (p as f64 * q.t),
                q.what
            )
            .map_err(w)?;
        }
        write!(out, "; simulation pass {:.1} ms in the cost model's order, {:.1} ms without it (costly first), {:.1} ms longest first ({closed})", 1e3 * o[0], 1e3 * o[1], 1e3 * o[2]).map_err(w)?;
        say!(out,);
    }
    Ok(serde_json::json!({
        "bench": "scaling", "pop": b.pop, "generations": b.generations, "seed": b.seed, "recording": b.record.enabled, "repetitions": b.reps,
        "load_average": load.split_whitespace().take(3).collect::<Vec<_>>().join(" "), "rows": rows,
        "hypervolume_s_1_thread": hv, "ordering_s_1_thread": order, "predictions": predictions,
    }))
}
