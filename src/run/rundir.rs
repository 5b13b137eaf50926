//! Optimisation runs in a run folder: start, checkpoint every generation, resume exactly,
//! write the final front and plots.
//!
//! Files in RUN_DIR: `problem.toml` (copy of the problem file), `run.json` (settings, seed,
//! versions, wall time, evaluations, resumes), `checkpoint.json`, `history.csv`,
//! `pareto.csv` (the final feasible non-dominated designs; deterministic, so a resumed run
//! writes the same bytes as an uninterrupted one), `pareto_timings.csv` (their wall-clock
//! stage timings, which are not deterministic), `population.csv` (the whole final
//! population with discard stages and reasons), `pareto_matrix.svg`, `hypervolume.svg`.

use super::archive::Archive;
use super::checkpoint::{settings_hash, sha256_hex, Checkpoint};
use super::gripper::{GripperInfo, GripperProblem};
use super::lock::{RunLock, LOCK_FILE};
use super::observers::{OutputsObserver, Progress, ProgressObserver};
use super::outputs::write_outputs;
use super::persist::{CheckpointSpec, Persister};
use crate::fsutil::write_atomic;
use crate::optim::{execute, observe, Evaluator, Nsga2, Nsga2Settings, Nsga2State, Operators};
use crate::params::Problem;
use crate::record::{RecordOptions, Recorder, LAYOUT_FILE};
use crate::{Error, Result};
use argmin::core::State;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
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
    /// What to record to MCAP.
    pub record: RecordOptions,
}

impl RunSpec {
    /// Check the settings before anything is created: the population and run length
    /// (memory, recording ids), the thread count and the recording options.
    pub fn validate(&self) -> Result<()> {
        super::limits::check_population(self.pop, self.generations, self.record.enabled)?;
        super::limits::check_threads(self.threads)?;
        self.record.validate()
    }
}

/// What a caller adds to a run: progress reports, a stop flag, another batch evaluator.
#[derive(Default)]
pub struct RunHooks {
    /// Told of every generation and of notes (warnings); None: nothing reported.
    pub progress: Option<Box<dyn Progress>>,
    /// When set (e.g. by ctrl-c), the run stops after the current generation's
    /// checkpoint: status interrupted, resumable.
    pub stop: Option<Arc<AtomicBool>>,
    /// The batch evaluator (None: the problem's default, `GripperProblem::default_evaluator`).
    pub evaluator: Option<Box<dyn Evaluator<GripperProblem>>>,
}

/// State of a run as written to `run.json` (`"running"`, `"finished"`, `"interrupted"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// A process is running it, or was killed while running it.
    Running,
    /// All requested generations are done.
    Finished,
    /// Stopped by ctrl-c or an error; resumable.
    Interrupted,
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
    /// Whether the run is running, finished or interrupted.
    pub status: RunStatus,
    /// Resumes: generation at which each happened, new total, and whether forced.
    pub resumes: Vec<Resume>,
    /// Recording options.
    pub recording: RecordOptions,
    /// Bytes recorded, over all processes (a process killed with -9 does not add its own).
    pub recording_bytes: u64,
    /// Seconds spent recording, over all processes (as `recording_bytes`).
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
    /// Final normalised hypervolume of the population's feasible front.
    pub hv: f64,
    /// Designs in the archive (every feasible non-dominated design evaluated).
    pub archive_size: usize,
    /// Normalised hypervolume of the archive.
    pub archive_hv: f64,
    /// Stopped by ctrl-c.
    pub interrupted: bool,
    /// Wall time of this process (s).
    pub wall_s: f64,
}

fn settings_for(p: &GripperProblem, pop: usize, seed: u64) -> Nsga2Settings {
    let (ideal, r) = p.hv_points();
    Nsga2Settings {
        pop_size: pop,
        seed,
        operators: Operators::default(),
        eliminate_duplicates: true,
        hv_ideal: ideal,
        hv_ref: r,
    }
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        b = b.num_threads(t);
    }
    Ok(b.build()?)
}

/// Start a new run in `spec.out` (which must not hold a checkpoint already).
pub fn optimise(spec: &RunSpec) -> Result<RunSummary> {
    optimise_with(spec, RunHooks::default())
}

/// [`optimise`] with the caller's progress, stop flag or evaluator.
pub fn optimise_with(spec: &RunSpec, hooks: RunHooks) -> Result<RunSummary> {
    spec.validate()?;
    let problem = Problem::load(&spec.problem_path)?;
    std::fs::create_dir_all(&spec.out).map_err(|e| Error::io(&spec.out, "cannot create the run folder", e))?;
    let cp_path = spec.out.join("checkpoint.json");
    let holds_run = || -> Result<()> {
        if cp_path.exists() {
            let message = format!(
                "already holds a run (checkpoint.json); use `gripopt resume {}` or another --out",
                spec.out.display()
            );
            return Err(Error::RunDir { path: spec.out.clone(), message });
        }
        Ok(())
    };
    holds_run()?;
    check_new_run_folder(&spec.out)?;
    let _lock = RunLock::acquire(&spec.out)?;
    holds_run()?; // again under the lock: another process may have started meanwhile
    write_atomic(&spec.out.join("problem.toml"), problem.source_text.as_bytes())?;
    crate::record::write_layout(&spec.out, &spec.record)?;
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
        status: RunStatus::Running,
        resumes: vec![],
        recording: spec.record.starting_now(),
        recording_bytes: 0,
        recording_s: 0.0,
    };
    let state = Nsga2State::new().with_max_generations(spec.generations);
    drive(gp, settings, state, info, &spec.out, spec.threads, hooks, 0.0)
}

/// Continue a stopped, killed or finished run; `generations` is the new total.
pub fn resume(dir: &Path, generations: Option<u64>, force: bool, threads: Option<usize>) -> Result<RunSummary> {
    resume_with(dir, generations, force, threads, RunHooks::default())
}

/// [`resume`] with the caller's progress, stop flag or evaluator.
pub fn resume_with(
    dir: &Path,
    generations: Option<u64>,
    force: bool,
    threads: Option<usize>,
    hooks: RunHooks,
) -> Result<RunSummary> {
    super::limits::check_threads(threads)?;
    let run_json = dir.join("run.json");
    let text = std::fs::read_to_string(&run_json)
        .map_err(|e| Error::io(&run_json, "cannot read (is its folder a run folder?)", e))?;
    let mut info: RunInfo = serde_json::from_str(&text).map_err(|source| Error::Json {
        path: run_json.clone(),
        what: "invalid run.json",
        source,
    })?;
    let _lock = RunLock::acquire(dir)?;
    let cp_path = dir.join("checkpoint.json");
    let (cp, mismatch) = Checkpoint::<GripperInfo>::load_unverified(&cp_path)?;
    let mut forced_notes = vec![];
    if let Some(m) = mismatch {
        if !force {
            return Err(m.error(&cp_path));
        }
        forced_notes.push(format!(
            "forced: checkpoint content checksum mismatch (stored {}, content {})",
            m.stored.as_deref().map(|s| &s[..s.len().min(12)]).unwrap_or("none"),
            &m.computed[..12]
        ));
    }
    let modified = |what: &str| Error::RunDir {
        path: cp_path.clone(),
        message: format!("{what} differ from {} (the run folder was modified); refusing to resume", run_json.display()),
    };
    if cp.settings != info.settings || cp.settings_hash != settings_hash(&cp.settings, &cp.options) {
        return Err(modified("settings"));
    }
    // problem file: the original path, or the copy in the run folder if it is gone
    let (problem_path, note) = if info.problem_path.exists() {
        (info.problem_path.clone(), String::new())
    } else {
        (dir.join("problem.toml"), format!("{} not found; used the run's copy", info.problem_path.display()))
    };
    let problem = Problem::load(&problem_path)?;
    let now = sha256_hex(problem.source_text.as_bytes());
    let mut note = note;
    if now != cp.problem_hash {
        if !force {
            let message = format!(
                "the problem file changed since the run started (sha256 {} → {}); resuming would mix two problems. Use --force to resume with the new file (recorded in run.json)",
                &cp.problem_hash[..12],
                &now[..12]
            );
            return Err(Error::RunDir { path: problem_path, message });
        }
        note = format!("forced: problem file changed (sha256 {} → {})", &cp.problem_hash[..12], &now[..12]);
    }
    let checksum_forced = !forced_notes.is_empty();
    if !note.is_empty() {
        forced_notes.insert(0, note);
    }
    let note = forced_notes.join("; ");
    let recording = serde_json::to_value(info.recording).map_err(|source| Error::Json {
        path: run_json.clone(),
        what: "field `recording`",
        source,
    })?;
    if cp.options.get("recording") != Some(&recording) {
        return Err(modified("recording options"));
    }
    let total = generations.unwrap_or(info.generations);
    super::limits::check_population(cp.settings.pop_size, total, info.recording.enabled)?;
    if total < cp.state.generation {
        return Err(Error::Input(format!(
            "--generations {total}: the run already has {} generations",
            cp.state.generation
        )));
    }
    info.resumes.push(Resume {
        at_generation: cp.state.generation,
        generations: total,
        forced: (force && now != cp.problem_hash) || checksum_forced,
        note,
    });
    info.generations = total;
    info.status = RunStatus::Running;
    let gp = GripperProblem::new(problem);
    let state = cp.state.with_max_generations(total);
    drive(gp, cp.settings, state, info, dir, threads, hooks, cp.wall_s)
}

#[allow(clippy::too_many_arguments)]
fn drive(
    gp: GripperProblem,
    settings: Nsga2Settings,
    state: Nsga2State<GripperInfo>,
    mut info: RunInfo,
    out: &Path,
    threads: Option<usize>,
    hooks: RunHooks,
    wall_before: f64,
) -> Result<RunSummary> {
    let progress = ProgressObserver(Arc::new(Mutex::new(hooks.progress.unwrap_or_else(|| Box::new(())))));
    let note = |m: &str| progress.0.lock().expect("progress lock").note(m);
    let start = Instant::now();
    let pool = pool(threads)?;
    info.threads = pool.current_num_threads();
    let problem_hash = sha256_hex(gp.problem.source_text.as_bytes());
    let options = run_options(&gp, &info.recording);
    let mut gp = gp;
    if info.recording.enabled {
        gp.keep_trajectories = info.recording.trajectories;
    }
    // the recording first: a resume it refuses (an unreadable shard) leaves run.json as it was
    let recorder = if info.recording.enabled {
        let meta = recording_metadata(&gp, &settings, &info);
        let r = Recorder::open(out, gp.problem.clone(), meta, info.recording, state.generation)?;
        for w in &r.warnings {
            note(&format!("warning: {w}"));
        }
        Some(Arc::new(Mutex::new(r)))
    } else {
        None
    };
    write_json(&out.join("run.json"), &info)?;
    if let Some(n) = super::limits::threads_note(settings.pop_size, info.threads) {
        note(&n);
    }
    let archive = Arc::new(Mutex::new(if state.generation == 0 { Archive::default() } else { Archive::load(out)? }));
    let outputs = OutputsObserver { out: out.to_path_buf(), settings: settings.clone(), archive: archive.clone() };
    // outputs and archive, shard k, then checkpoint k, in that order on a background thread
    // while k+1 evaluates (src/run/persist.rs)
    let ckpt = CheckpointSpec {
        path: out.join("checkpoint.json"),
        problem_hash,
        settings: settings.clone(),
        options,
        wall_before,
        start,
    };
    let persister = Persister::start(Some(outputs), recorder.clone(), ckpt, info.threads)?;
    let (pers2, prog2) = (persister.clone(), progress.clone());
    let evaluator = hooks.evaluator.unwrap_or_else(|| gp.default_evaluator());
    let mut solver = Nsga2::with_evaluator(settings, evaluator);
    solver.stop = hooks.stop;
    let result = pool.install(|| execute(gp, solver, state, move |e| observe(observe(e, pers2), prog2)));
    // on success every output of the final state is written below: the persister need
    // not write the last views too
    let ok = result.is_ok();
    let result = match (result, persister.finish_with(!ok)) {
        (Ok(_), Err(e)) => Err(e),
        (r, _) => r,
    };
    if let Some(r) = &recorder {
        let r = r.lock().expect("recorder");
        info.recording_bytes += r.bytes;
        info.recording_s += r.seconds;
    }
    let (gp, st) = match result {
        Ok(r) => r,
        Err(e) => {
            // what the checkpoint holds: the last generation the persister made durable
            let done = persister.durable_generation();
            if done > info.completed_generations {
                info.completed_generations = done;
                info.evaluations = done * info.settings.pop_size as u64;
            }
            info.status = RunStatus::Interrupted;
            info.wall_s = wall_before + start.elapsed().as_secs_f64();
            let _ = write_json(&out.join("run.json"), &info);
            return Err(if out.join("checkpoint.json").exists() {
                Error::Stopped { path: out.to_path_buf(), source: Box::new(e) }
            } else {
                Error::StoppedBeforeCheckpoint { path: out.to_path_buf(), source: Box::new(e) }
            });
        }
    };
    let interrupted = matches!(st.get_termination_reason(), Some(argmin::core::TerminationReason::Interrupt));
    info.completed_generations = st.generation;
    info.evaluations = st.evaluations;
    info.wall_s = wall_before + start.elapsed().as_secs_f64();
    info.status = if interrupted { RunStatus::Interrupted } else { RunStatus::Finished };
    let archive = archive.lock().expect("archive").clone();
    write_outputs(out, &gp, &st, &archive)?;
    let front: Vec<u64> = super::outputs::final_front(&st).iter().map(|p| p.id).collect();
    let status =
        std::collections::BTreeMap::from([("status".to_string(), format!("{:?}", info.status).to_lowercase())]);
    crate::record::write_front(out, &info.recording, &front, st.generation, &status)?;
    write_json(&out.join("run.json"), &info)?;
    Ok(RunSummary {
        out: out.to_path_buf(),
        generations: st.generation,
        evaluations: st.evaluations,
        front_size: st.feasible_front().len(),
        feasible: st.population.iter().filter(|p| p.eval.cv.is_feasible()).count(),
        hv: st.hv_history.last().copied().unwrap_or(f64::NAN),
        archive_size: archive.members.len(),
        archive_hv: archive.hv_history.last().copied().unwrap_or(f64::NAN),
        interrupted,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// `optimise --out DIR` only into a new or empty folder, or one left by a run that never
/// reached its first checkpoint: never into a folder of other files.
fn check_new_run_folder(dir: &Path) -> Result<()> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list the run folder", e))?;
    let ours = ["run.json", "problem.toml", "recording", "checkpoint.json", LOCK_FILE];
    // what a run writes before its first checkpoint (and at its end); accepted only beside
    // the run.json of that run
    let outputs = [
        LAYOUT_FILE,
        "archive.json",
        "pareto.csv",
        "pareto_timings.csv",
        "archive.csv",
        "population.csv",
        "history.csv",
        "pareto_matrix.svg",
        "hypervolume.svg",
    ];
    let names: Vec<String> = rd.flatten().map(|f| f.file_name().to_string_lossy().to_string()).collect();
    let run_json = names.iter().any(|n| n == "run.json");
    let foreign: Vec<String> = names
        .into_iter()
        .filter(|n| {
            let tmp = n.starts_with('.') && n.ends_with(".tmp");
            !(ours.contains(&n.as_str()) || (run_json && outputs.contains(&n.as_str())) || tmp)
        })
        .collect();
    if foreign.is_empty() {
        return Ok(());
    }
    let mut shown: Vec<&str> = foreign.iter().map(String::as_str).take(3).collect();
    shown.sort();
    let message = format!(
        "--out: the folder is not empty and is not a gripopt run (it holds {}{}); give a new or empty folder",
        shown.join(", "),
        if foreign.len() > 3 { ", …" } else { "" }
    );
    Err(Error::RunDir { path: dir.to_path_buf(), message })
}

/// Metadata written into every shard of the recording.
fn recording_metadata(
    gp: &GripperProblem,
    settings: &Nsga2Settings,
    info: &RunInfo,
) -> std::collections::BTreeMap<String, String> {
    let mut meta = std::collections::BTreeMap::new();
    meta.insert("gripopt_version".to_string(), env!("CARGO_PKG_VERSION").to_string());
    meta.insert("problem".to_string(), gp.problem.name.clone());
    meta.insert("problem_sha256".to_string(), info.problem_sha256.clone());
    // plain structs of numbers, strings and enums: serialising cannot fail
    meta.insert("settings".to_string(), serde_json::to_string(settings).expect("settings serialise"));
    meta.insert("recording".to_string(), serde_json::to_string(&info.recording).expect("recording options serialise"));
    meta.insert(
        "time_convention".to_string(),
        "design k: log_time in [k s, k s + 1 s); field t = simulated time".to_string(),
    );
    meta
}

/// Run options hashed into checkpoints: pipeline settings and recording.
fn run_options(gp: &GripperProblem, rec: &RecordOptions) -> serde_json::Value {
    serde_json::json!({ "pipeline": "stages 0-3, stage 3 in pipeline mode", "rtol": gp.problem.solver.rtol, "atol": gp.problem.solver.atol, "max_steps": gp.problem.solver.max_steps, "recording": rec })
}

fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<()> {
    let mut s = serde_json::to_string_pretty(v).map_err(|source| Error::Json {
        path: path.to_path_buf(),
        what: "cannot serialise",
        source,
    })?;
    s.push('\n');
    write_atomic(path, s.as_bytes())
}
