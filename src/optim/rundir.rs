//! Optimisation runs in a run folder: start, checkpoint every generation, resume exactly,
//! write the final front and plots.
//!
//! Files in RUN_DIR: `problem.toml` (copy of the problem file), `run.json` (settings, seed,
//! versions, wall time, evaluations, resumes), `checkpoint.json`, `history.csv`,
//! `pareto.csv` (the final feasible non-dominated designs; deterministic, so a resumed run
//! writes the same bytes as an uninterrupted one), `pareto_timings.csv` (their wall-clock
//! stage timings, which are not deterministic), `population.csv` (the whole final
//! population with discard stages and reasons), `pareto_matrix.svg`, `hypervolume.svg`.

use super::checkpoint::{sha256_hex, settings_hash, Checkpoint};
use super::gripper::{GripperInfo, GripperProblem};
use super::nsga2::{Nsga2Settings, Nsga2State};
use super::operators::Operators;
use super::run::{execute, observe, CheckpointObserver, ProgressObserver, SharedProgress};
use super::Individual;
use crate::params::Problem;
use argmin::core::observers::Observe;
use argmin::core::{Error as ArgminError, State, KV};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// What to run.
#[derive(Debug, Clone)]
pub struct RunSpec {
    /// Problem file.
    pub problem_path: PathBuf,
    /// Run folder.
    pub out: PathBuf,
    /// Population size.
    pub pop: usize,
    /// Total generations (1 = initial population only).
    pub generations: u64,
    /// Seed.
    pub seed: u64,
    /// Worker threads (None = all cores). Results do not depend on it.
    pub threads: Option<usize>,
    /// Show a progress bar.
    pub progress: bool,
    /// Test hook: fail after this generation's checkpoint, as a crash would.
    pub crash_after: Option<u64>,
    /// What to record to MCAP.
    pub record: crate::record::RecordOptions,
}

/// `run.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunInfo {
    /// gripopt version.
    pub gripopt_version: String,
    /// Problem name.
    pub problem_name: String,
    /// Path of the problem file given at the start.
    pub problem_path: PathBuf,
    /// SHA-256 of the problem file at the start.
    pub problem_sha256: String,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// Total generations requested.
    pub generations: u64,
    /// Completed generations.
    pub completed_generations: u64,
    /// Evaluations.
    pub evaluations: u64,
    /// Threads of the last process.
    pub threads: usize,
    /// Wall time over all processes (s).
    pub wall_s: f64,
    /// running | finished | interrupted
    pub status: String,
    /// Resumes: generation at which each happened, new total, and whether forced.
    pub resumes: Vec<Resume>,
    /// Recording options.
    pub recording: crate::record::RecordOptions,
    /// Bytes recorded by the last process.
    pub recording_bytes: u64,
    /// Seconds spent recording by the last process.
    pub recording_s: f64,
}

/// One resume.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Resume {
    /// Completed generations when resumed.
    pub at_generation: u64,
    /// New total.
    pub generations: u64,
    /// Forced despite a changed problem file.
    pub forced: bool,
    /// Note (e.g. what changed).
    pub note: String,
}

/// Summary returned to the CLI.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Run folder.
    pub out: PathBuf,
    /// Completed generations.
    pub generations: u64,
    /// Evaluations.
    pub evaluations: u64,
    /// Size of the final feasible front.
    pub front_size: usize,
    /// Feasible members of the final population.
    pub feasible: usize,
    /// Final normalised hypervolume.
    pub hv: f64,
    /// Stopped by ctrl-c.
    pub interrupted: bool,
    /// Wall time of this process (s).
    pub wall_s: f64,
}

fn err(path: &Path, what: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("{}: {what}", path.display())
}

fn settings_for(p: &GripperProblem, pop: usize, seed: u64) -> Nsga2Settings {
    let (ideal, r) = p.hv_points();
    Nsga2Settings { pop_size: pop, seed, operators: Operators::default(), eliminate_duplicates: true, hv_ideal: ideal, hv_ref: r }
}

fn pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        b = b.num_threads(t);
    }
    Ok(b.build()?)
}

struct CrashAfter(u64);
impl<I> Observe<Nsga2State<I>> for CrashAfter {
    fn observe_iter(&mut self, s: &Nsga2State<I>, _kv: &KV) -> Result<(), ArgminError> {
        if s.generation >= self.0 {
            return Err(ArgminError::msg(format!("simulated crash after generation {}", s.generation)));
        }
        Ok(())
    }
    fn observe_init(&mut self, _n: &str, s: &Nsga2State<I>, kv: &KV) -> Result<(), ArgminError> {
        self.observe_iter(s, kv)
    }
}

/// Start a new run in `spec.out` (which must not hold a checkpoint already).
pub fn optimise(spec: &RunSpec) -> anyhow::Result<RunSummary> {
    if spec.pop < 4 {
        anyhow::bail!("--pop {}: must be at least 4", spec.pop);
    }
    if spec.generations < 1 {
        anyhow::bail!("--generations {}: must be at least 1", spec.generations);
    }
    let problem = Problem::load(&spec.problem_path)?;
    std::fs::create_dir_all(&spec.out).map_err(|e| err(&spec.out, format!("cannot create the run folder: {e}")))?;
    let cp_path = spec.out.join("checkpoint.json");
    if cp_path.exists() {
        anyhow::bail!("{} already holds a run (checkpoint.json); use `gripopt resume {}` or another --out", spec.out.display(), spec.out.display());
    }
    super::checkpoint::write_atomic(&spec.out.join("problem.toml"), problem.source_text.as_bytes())?;
    let gp = GripperProblem::new(problem);
    let settings = settings_for(&gp, spec.pop, spec.seed);
    let info = RunInfo {
        gripopt_version: env!("CARGO_PKG_VERSION").into(),
        problem_name: gp.problem.name.clone(),
        problem_path: spec.problem_path.clone(),
        problem_sha256: sha256_hex(gp.problem.source_text.as_bytes()),
        settings: settings.clone(),
        generations: spec.generations,
        completed_generations: 0,
        evaluations: 0,
        threads: 0,
        wall_s: 0.0,
        status: "running".into(),
        resumes: vec![],
        recording: spec.record,
        recording_bytes: 0,
        recording_s: 0.0,
    };
    let state = Nsga2State::new().with_max_generations(spec.generations);
    drive(gp, settings, state, info, &spec.out, spec.threads, spec.progress, spec.crash_after, 0.0)
}

/// Continue a stopped, killed or finished run; `generations` is the new total.
pub fn resume(dir: &Path, generations: Option<u64>, force: bool, threads: Option<usize>, progress: bool) -> anyhow::Result<RunSummary> {
    let run_json = dir.join("run.json");
    let text = std::fs::read_to_string(&run_json).map_err(|e| err(&run_json, format!("cannot read: {e} (is {} a run folder?)", dir.display())))?;
    let mut info: RunInfo = serde_json::from_str(&text).map_err(|e| err(&run_json, format!("invalid run.json: {e}")))?;
    let cp_path = dir.join("checkpoint.json");
    let cp: Checkpoint<GripperInfo> = Checkpoint::load(&cp_path)?;
    if cp.settings != info.settings || cp.settings_hash != settings_hash(&cp.settings, &cp.options) {
        anyhow::bail!("{}: settings differ from {} (the run folder was modified); refusing to resume", cp_path.display(), run_json.display());
    }
    // problem file: the original path, or the copy in the run folder if it is gone
    let (problem_path, note) = if info.problem_path.exists() { (info.problem_path.clone(), String::new()) } else { (dir.join("problem.toml"), format!("{} not found; used the run's copy", info.problem_path.display())) };
    let problem = Problem::load(&problem_path)?;
    let now = sha256_hex(problem.source_text.as_bytes());
    let mut note = note;
    if now != cp.problem_hash {
        if !force {
            anyhow::bail!(
                "{}: the problem file changed since the run started (sha256 {} → {}); resuming would mix two problems. Use --force to resume with the new file (recorded in run.json)",
                problem_path.display(), &cp.problem_hash[..12], &now[..12]
            );
        }
        note = format!("forced: problem file changed (sha256 {} → {})", &cp.problem_hash[..12], &now[..12]);
    }
    if cp.options.get("recording") != Some(&serde_json::to_value(info.recording)?) {
        anyhow::bail!("{}: recording options differ from {} (the run folder was modified); refusing to resume", cp_path.display(), run_json.display());
    }
    let total = generations.unwrap_or(info.generations);
    if total < cp.state.generation {
        anyhow::bail!("--generations {total}: the run already has {} generations", cp.state.generation);
    }
    info.resumes.push(Resume { at_generation: cp.state.generation, generations: total, forced: force && now != cp.problem_hash, note });
    info.generations = total;
    info.status = "running".into();
    let gp = GripperProblem::new(problem);
    let state = cp.state.with_max_generations(total);
    drive(gp, cp.settings, state, info, dir, threads, progress, None, cp.wall_s)
}

#[allow(clippy::too_many_arguments)]
fn drive(
    gp: GripperProblem,
    settings: Nsga2Settings,
    state: Nsga2State<GripperInfo>,
    mut info: RunInfo,
    out: &Path,
    threads: Option<usize>,
    progress: bool,
    crash_after: Option<u64>,
    wall_before: f64,
) -> anyhow::Result<RunSummary> {
    let start = Instant::now();
    let pool = pool(threads)?;
    info.threads = pool.current_num_threads();
    write_json(&out.join("run.json"), &info)?;
    let problem_hash = sha256_hex(gp.problem.source_text.as_bytes());
    let options = run_options(&gp, &info.recording);
    let mut gp = gp;
    if info.recording.enabled {
        gp.keep_trajectories = info.recording.trajectories;
    }
    let recorder = if info.recording.enabled {
        let mut meta = std::collections::BTreeMap::new();
        meta.insert("gripopt_version".to_string(), env!("CARGO_PKG_VERSION").to_string());
        meta.insert("problem".to_string(), gp.problem.name.clone());
        meta.insert("problem_sha256".to_string(), info.problem_sha256.clone());
        meta.insert("settings".to_string(), serde_json::to_string(&settings)?);
        meta.insert("recording".to_string(), serde_json::to_string(&info.recording)?);
        meta.insert("time_convention".to_string(), "design k: log_time in [k s, k s + 1 s); field t = simulated time".to_string());
        let r = crate::record::Recorder::open(out, gp.problem.clone(), meta, info.recording, state.generation)?;
        Some(crate::record::writer::SharedRecorder(Arc::new(Mutex::new(r))))
    } else {
        None
    };
    let first = state.generation.max(1);
    let prog = SharedProgress(Arc::new(Mutex::new(ProgressObserver::new(state.max_generations, first, progress))));
    let ckpt = CheckpointObserver { path: out.join("checkpoint.json"), problem_hash, settings: settings.clone(), options, wall_before, start };
    let prog2 = prog.clone();
    let rec2 = recorder.clone();
    let result = pool.install(|| {
        execute(gp, settings, state, move |e| {
            // recorder first: a generation is checkpointed only after its shard is complete
            let e = match rec2 {
                Some(r) => observe(e, r),
                None => e,
            };
            let e = observe(observe(e, ckpt), prog2);
            match crash_after {
                Some(k) => observe(e, CrashAfter(k)),
                None => e,
            }
        }, crash_after.is_none())
    });
    prog.0.lock().expect("progress").finish();
    if let Some(r) = &recorder {
        let r = r.0.lock().expect("recorder");
        info.recording_bytes = r.bytes;
        info.recording_s = r.seconds;
    }
    let (gp, st) = match result {
        Ok(r) => r,
        Err(e) => {
            info.status = "interrupted".into();
            info.wall_s = wall_before + start.elapsed().as_secs_f64();
            let _ = write_json(&out.join("run.json"), &info);
            return Err(anyhow::anyhow!("run in {} stopped: {e}; resume with `gripopt resume {}`", out.display(), out.display()));
        }
    };
    let interrupted = matches!(st.get_termination_reason(), Some(argmin::core::TerminationReason::Interrupt));
    info.completed_generations = st.generation;
    info.evaluations = st.evaluations;
    info.wall_s = wall_before + start.elapsed().as_secs_f64();
    info.status = if interrupted { "interrupted".into() } else { "finished".into() };
    write_outputs(out, &gp, &st)?;
    write_json(&out.join("run.json"), &info)?;
    Ok(RunSummary {
        out: out.to_path_buf(),
        generations: st.generation,
        evaluations: st.evaluations,
        front_size: st.feasible_front().len(),
        feasible: st.population.iter().filter(|p| p.eval.cv.is_feasible()).count(),
        hv: st.hv_history.last().copied().unwrap_or(f64::NAN),
        interrupted,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Run options hashed into checkpoints: pipeline settings and recording.
fn run_options(gp: &GripperProblem, rec: &crate::record::RecordOptions) -> serde_json::Value {
    serde_json::json!({ "pipeline": "stages 0-3, stage 3 in pipeline mode", "rtol": gp.problem.solver.rtol, "atol": gp.problem.solver.atol, "max_steps": gp.problem.solver.max_steps, "recording": rec })
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> anyhow::Result<()> {
    let mut s = serde_json::to_string_pretty(v)?;
    s.push('\n');
    super::checkpoint::write_atomic(path, s.as_bytes())?;
    Ok(())
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// The final feasible non-dominated designs, sorted by id.
pub fn final_front(st: &Nsga2State<GripperInfo>) -> Vec<&Individual<GripperInfo>> {
    let mut f = st.feasible_front();
    f.sort_by_key(|p| p.id);
    f
}

fn write_outputs(out: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>) -> anyhow::Result<()> {
    let front = final_front(st);
    let mut csv = String::from("id,generation,l21,b,t22,r,p,psi_deg,l11,l12,l22,l_hand,max_offset,alpha,mean_force,t_stab,sim_steps,sim_rhs_evals,force_model\n");
    let force_model = gp.problem.scene.criteria.force_model.as_str(); // D22: which forces define alpha, mean_force
    let mut tim = String::from("id,stage01_s,stage2_s,stage3_s\n");
    for ind in &front {
        let i = &ind.eval.info;
        let x = &ind.x;
        let l = i.lengths.unwrap_or([f64::NAN; 3]);
        let w = i.sim_work.map(|w| (w[0].to_string(), w[1].to_string())).unwrap_or_default();
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            ind.id, ind.generation, x[0], x[1], x[2], x[3], x[4], x[5], l[0], l[1], l[2], i.l_hand,
            opt(i.objectives[0]), opt(i.objectives[1]), opt(i.objectives[2]), opt(i.objectives[3]), w.0, w.1, force_model
        );
        let _ = writeln!(tim, "{},{},{},{}", ind.id, i.stage_seconds[1], i.stage_seconds[2], i.stage_seconds[3]);
    }
    super::checkpoint::write_atomic(&out.join("pareto.csv"), csv.as_bytes())?;
    super::checkpoint::write_atomic(&out.join("pareto_timings.csv"), tim.as_bytes())?;
    let mut pop = String::from("id,generation,rank,feasible,failed_stage,violation,reason,l21,b,t22,r,p,psi_deg,max_offset,alpha,mean_force,t_stab\n");
    let mut order: Vec<usize> = (0..st.population.len()).collect();
    order.sort_by_key(|&k| (st.rank[k], st.population[k].id));
    for k in order {
        let ind = &st.population[k];
        let i = &ind.eval.info;
        let x = &ind.x;
        let _ = writeln!(
            pop,
            "{},{},{},{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{}",
            ind.id, ind.generation, st.rank[k], ind.eval.cv.is_feasible(), i.failed_stage.map(|s| s.to_string()).unwrap_or_default(),
            opt(i.violation), i.reason.clone().unwrap_or_default().replace('"', "'"), x[0], x[1], x[2], x[3], x[4], x[5],
            opt(i.objectives[0]), opt(i.objectives[1]), opt(i.objectives[2]), opt(i.objectives[3])
        );
    }
    super::checkpoint::write_atomic(&out.join("population.csv"), pop.as_bytes())?;
    let mut hist = String::from("generation,evaluations,feasible,hypervolume\n");
    for (g, (hv, fe)) in st.hv_history.iter().zip(&st.feasible_history).enumerate() {
        let _ = writeln!(hist, "{},{},{},{}", g + 1, (g as u64 + 1) * st.population.len() as u64, fe, hv);
    }
    super::checkpoint::write_atomic(&out.join("history.csv"), hist.as_bytes())?;
    super::plots::pareto_matrix(&out.join("pareto_matrix.svg"), gp, st)?;
    super::plots::hypervolume(&out.join("hypervolume.svg"), &st.hv_history)?;
    Ok(())
}
