//! Optimisation runs in a run folder: start, checkpoint every generation, resume exactly,
//! write the final front and plots.
//!
//! Files in RUN_DIR: `problem.toml` (copy of the problem file), `run.json` (settings, seed,
//! versions, wall time, evaluations, resumes), `checkpoint.json`, `history.csv`,
//! `pareto.csv` (the final feasible non-dominated designs; deterministic, so a resumed run
//! writes the same bytes as an uninterrupted one), `pareto_timings.csv` (their wall-clock
//! stage timings, which are not deterministic), `population.csv` (the whole final
//! population with discard stages and reasons), `pareto_matrix.svg`, `hypervolume.svg`.

use super::archive::{Archive, Discards};
use super::checkpoint::{field_differences, settings_hash, sha256_hex, Checkpoint, RunOptions};
use super::contents::Scan;
use super::differences::{original_problem, settings_differences};
use super::gripper::{GripperInfo, GripperProblem};
use super::info::{new_run_id, write_json, Resume, RunInfo, RunStatus, RUN_FILE};
use super::lock::RunLock;
use super::observers::{OutputsObserver, Progress, ProgressObserver};
use super::outputs::write_outputs;
use super::persist::{CheckpointSpec, Committed, PersistHooks, Persister};
use super::problems::{check_copy, check_same_objects, switch, write_current};
use crate::error::{Error, Result};
use crate::optim::{execute, observe, Evaluator, Nsga2, Nsga2Settings, Nsga2State, Operators, Survival, Variation};
use crate::params::Problem;
use crate::record::{ProblemUse, RecordOptions, Recorder, RunMetadata};
use argmin::core::State;
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
    /// A new run's survival and variation (None: the defaults; e.g. NSGA-II's, crowding and
    /// SBX, to compare with a run of before issue 42). A resume keeps its checkpoint's.
    pub algorithm: Option<(Survival, Variation)>,
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
    /// Designs on the reported front (pareto.csv; the certified front where the run
    /// certifies).
    pub front_size: usize,
    /// Feasible members of the final population.
    pub feasible: usize,
    /// Normalised hypervolume of the search's reported front (pareto.csv; of a robust run
    /// that certifies, search_pareto.csv: the certified designs' objectives are estimated
    /// on other scenarios).
    pub hv: f64,
    /// Designs in the archive (every feasible non-dominated design evaluated).
    pub archive_size: usize,
    /// Normalised hypervolume of the archive.
    pub archive_hv: f64,
    /// Stopped by ctrl-c.
    pub interrupted: bool,
    /// Wall time of this process (s).
    pub wall_s: f64,
    /// Every design of the run counted by what discarded it ([`Discards::explain`] says why
    /// a run has no feasible design).
    pub discards: Discards,
    /// A robust run's certification stage (None: the problem does not certify, or the run
    /// was interrupted before it).
    pub certification: Option<super::CertificationSummary>,
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

/// Start a new run in `spec.out` (a new or empty folder, or one left by a run that never
/// reached its first checkpoint).
pub fn optimise(spec: &RunSpec) -> Result<RunSummary> {
    optimise_with(spec, RunHooks::default())
}

/// The problem file's path as run.json keeps it, for `resume` to find it from anywhere:
/// absolute, without `.` and `..`. A `..` is removed as written where that names the same
/// file (symbolic links in the path kept as the user gave them); after a symbolic link a `..`
/// leads where the link's target is, not where its removal would, so there the path is the
/// file system's ([`std::fs::canonicalize`]). Run folders of an earlier gripopt keep theirs
/// as written (absolute, `..` included): the file system resolves it on resume as before.
fn recorded_problem_path(given: &Path) -> PathBuf {
    let Ok(absolute) = std::path::absolute(given) else { return given.to_path_buf() };
    let mut lexical = PathBuf::new();
    for part in absolute.components() {
        match part {
            std::path::Component::ParentDir => {
                lexical.pop();
            }
            std::path::Component::CurDir => {}
            part => lexical.push(part),
        }
    }
    let resolved = |p: &Path| std::fs::canonicalize(p).ok();
    if lexical == absolute || resolved(&lexical).is_some_and(|l| Some(l) == resolved(&absolute)) {
        return lexical;
    }
    resolved(&absolute).unwrap_or(absolute)
}

/// The files of a run folder a run or resume rewrites besides its views (checked with
/// them before any work: [`crate::fsutil::check_rewritable`]).
const STATE_FILES: [&str; 4] = ["checkpoint.json", "run.json", "problem.toml", "recording/index.jsonl"];

/// [`optimise`] with the caller's progress, stop flag or evaluator.
///
/// run.json is written first (under the folder's lock), so that every other file of the
/// folder is attributable to the run it names.
pub fn optimise_with(spec: &RunSpec, hooks: RunHooks) -> Result<RunSummary> {
    spec.validate()?;
    let problem = Problem::load(&spec.problem_path)?;
    problem.check_self_contained(&spec.problem_path)?;
    // what the designs' records hold, before anything is written
    let size_note = super::limits::check_record_size(&problem, spec.pop, spec.record.enabled)?;
    if spec.out.exists() && !spec.out.is_dir() {
        return Err(Error::RunDir {
            path: spec.out.clone(),
            message: "is a file, not a folder: give a new or empty folder for the run".into(),
        });
    }
    super::contents::refuse_run_inside_run(&spec.out)?;
    std::fs::create_dir_all(&spec.out).map_err(|e| Error::io(&spec.out, "cannot create the run folder", e))?;
    // a folder another process holds is refused naming it, before its files (changing as
    // that process writes them) are looked at
    if let super::lock::LockHolder::Held(pid) = RunLock::holder(&spec.out)? {
        return Err(Error::Locked { path: spec.out.clone(), pid });
    }
    // refused before the lock's pid file is written into a folder that is not ours
    Scan::of(&spec.out)?.check_new_run_folder(&spec.problem_path)?;
    let lock = RunLock::acquire(&spec.out)?;
    // again under the lock: another process may have started meanwhile
    let earlier = Scan::of(&spec.out)?.check_new_run_folder(&spec.problem_path)?;
    let mut notes: Vec<String> = size_note.into_iter().collect();
    for f in &earlier.remove {
        // files of the earlier attempt that never reached its first checkpoint (content proven)
        std::fs::remove_file(f).map_err(|e| Error::io(f, "cannot remove a file of the earlier attempt", e))?;
    }
    for (folder, name) in &earlier.set_aside {
        // attributed only by a name or a title line: moved, never removed
        let to = crate::fsutil::set_aside(folder, name)?;
        notes.push(format!(
            "note: {} is not provably the earlier attempt's (a name or title line proves nothing): set aside as {}",
            folder.join(name).display(),
            to.display()
        ));
    }
    // a link at a name the run rewrites is refused before any work (never replaced)
    crate::fsutil::check_rewritable(&spec.out, &super::outputs::REWRITTEN_FILES)?;
    crate::fsutil::check_rewritable(&spec.out, &STATE_FILES)?;
    let gp = GripperProblem::new(problem);
    let settings = settings_for(&gp, spec.pop, spec.seed);
    let problem_sha256 = sha256_hex(gp.problem.source_text.as_bytes());
    let info = RunInfo {
        gripopt_version: env!("CARGO_PKG_VERSION").into(),
        run_id: new_run_id(&spec.out),
        problem_name: gp.problem.name.clone(),
        problem_path: recorded_problem_path(&spec.problem_path),
        problems: vec![ProblemUse { first_generation: 1, file: "problem.toml".into(), sha256: problem_sha256.clone() }],
        problem_sha256,
        settings: settings.clone(),
        generations: spec.generations,
        completed_generations: 0,
        evaluations: 0,
        checkpoint_sha256: None,
        threads: 0,
        wall_s: 0.0,
        status: RunStatus::Running,
        resumes: vec![],
        recording: spec.record.starting_now(),
        recording_bytes: 0,
        recording_s: 0.0,
        discards: Discards::default(),
    };
    write_json(&spec.out.join(RUN_FILE), &info)?;
    write_current(&spec.out, &info, &gp.problem)?;
    // a run that records nothing gets no layout: it would name channels no file has
    if spec.record.enabled {
        crate::record::write_layout(&spec.out, &spec.record, &gp.problem)?;
    }
    let recorder = open_recorder(&spec.out, &gp, &info, 0)?;
    let state = Nsga2State::new().with_max_generations(spec.generations);
    let (survival, variation) = hooks.algorithm.unwrap_or_default();
    let (survival, variation) = (Some(survival), Some(variation));
    let start =
        Start { settings, state, recorder, archive: Archive::default(), notes, wall_before: 0.0, survival, variation };
    drive(gp, info, &spec.out, spec.threads, hooks, lock, start)
}

/// Continue a stopped, killed or finished run; `generations` is the new total.
pub fn resume(dir: &Path, generations: Option<u64>, force: bool, threads: Option<usize>) -> Result<RunSummary> {
    resume_with(dir, generations, force, threads, RunHooks::default())
}

/// [`resume`] with the caller's progress, stop flag or evaluator.
///
/// Every file read back is checked against what wrote it: run.json and the checkpoint name
/// the same run; the checkpoint is not older than run.json's last one (unless forced); the
/// problem copy is the one recorded; the shards are this run's (see `record::recover_run`).
/// A refused resume changes nothing.
pub fn resume_with(
    dir: &Path,
    generations: Option<u64>,
    force: bool,
    threads: Option<usize>,
    hooks: RunHooks,
) -> Result<RunSummary> {
    super::limits::check_threads(threads)?;
    if !dir.exists() {
        // e.g. an optimise killed before it created its folder
        let message = "no such folder: nothing to resume (`gripopt optimise PROBLEM --out DIR` starts a run)";
        return Err(Error::RunDir { path: dir.to_path_buf(), message: message.into() });
    }
    if !dir.is_dir() {
        return Err(Error::RunDir { path: dir.to_path_buf(), message: "not a folder (is it a run folder?)".into() });
    }
    let lock = RunLock::acquire(dir)?;
    crate::fsutil::check_rewritable(dir, &super::outputs::REWRITTEN_FILES)?;
    crate::fsutil::check_rewritable(dir, &STATE_FILES)?;
    let scan = Scan::of(dir)?;
    if !scan.checkpoint {
        return Err(scan.no_checkpoint());
    }
    let run_json = dir.join(RUN_FILE);
    let mut info = match scan.run {
        Some(r) => r?,
        None => {
            return Err(Error::RunDir {
                path: run_json,
                message: "missing beside checkpoint.json: restore it (e.g. from a backup) to resume".into(),
            })
        }
    };
    let cp_path = dir.join("checkpoint.json");
    let (cp, cp_sha256, mismatch) = Checkpoint::<GripperInfo>::load_unverified(&cp_path)?;
    super::invariants::check_design_length(
        &cp.state,
        cp.archive.as_ref(),
        &cp_path,
        crate::params::DESIGN_NAMES.len(),
    )?;
    let mut notes = vec![];
    if let Some(m) = mismatch {
        if !force {
            return Err(m.error(&cp_path));
        }
        notes.push(format!(
            "forced: checkpoint content checksum mismatch (stored {}, content {})",
            m.stored.as_deref().map(|s| &s[..s.len().min(12)]).unwrap_or("none"),
            &m.computed[..12]
        ));
    }
    let modified = |found: Vec<String>| Error::RunDir {
        path: cp_path.clone(),
        message: format!("{}: the run folder was modified; refusing to resume", found.join("; ")),
    };
    if cp.settings != info.settings || cp.settings_hash != settings_hash(&cp.settings, &cp.options) {
        return Err(modified(settings_differences(&cp, &info, dir)));
    }
    if !info.run_id.is_empty() && cp.run_id != info.run_id {
        let message = if cp.run_id.is_empty() {
            format!("field `run_id` is missing or empty (run.json's `run_id` is {}): it names the run that wrote the checkpoint; restore this run's checkpoint.json", info.run_id)
        } else {
            format!(
                "written by another run (run id {:?}; run.json's is {}): restore this run's checkpoint.json",
                cp.run_id, info.run_id
            )
        };
        return Err(Error::Checkpoint { file: cp_path.clone(), message });
    }
    if cp.state.generation < info.completed_generations {
        if !force {
            return Err(Error::Checkpoint {
                file: cp_path.clone(),
                message: format!("holds generation {} but run.json records {} completed generations: an older checkpoint (restored from a backup?). Restore the latest one, or resume with --force to continue from generation {} (later generations are evaluated again and their shards replaced)", cp.state.generation, info.completed_generations, cp.state.generation),
            });
        }
        notes.push(format!(
            "forced: an older checkpoint (generation {} of {})",
            cp.state.generation, info.completed_generations
        ));
    } else if let Some(why) = super::attribution::run_json_mismatch(&info, cp.state.generation, &cp_sha256, false) {
        // run.json restored beside a newer checkpoint (or another copy's): resuming would
        // rewrite it without the resumes and wall time it lost
        if !force {
            let message = format!("{why}, or resume with --force to continue from checkpoint.json's generation {} (what run.json lost is not restored)", cp.state.generation);
            return Err(Error::RunDir { path: run_json, message });
        }
        notes.push(format!(
            "forced: run.json (generation {}) does not match checkpoint.json (generation {})",
            info.completed_generations, cp.state.generation
        ));
    }
    let Some(archive) = cp.archive.clone() else {
        return Err(Error::Checkpoint { file: cp_path, message: "holds no archive (field `archive`)".into() });
    };
    // the problem: the file the run started with, or the run's copy if it is gone
    let original = original_problem(&info);
    let problem_path = original.clone().unwrap_or_else(|| dir.join("problem.toml"));
    // a problem without `solver.method` keeps the method the run started with (RADAU5 for
    // a checkpoint that names none: the default before session 38)
    let problem = Problem::load(&problem_path)?.with_run_method(cp.options.method);
    problem.check_self_contained(&problem_path)?;
    check_copy(dir, &info, &problem)?;
    if original.is_none() {
        notes.push(format!("{} not found; used the run's copy", info.problem_path.display()));
    }
    let now = sha256_hex(problem.source_text.as_bytes());
    let problem_changed = now != cp.problem_hash;
    if problem_changed {
        if !force {
            let message = format!(
                "the problem file changed since the run started (sha256 {} → {}); resuming would mix two problems. Use --force to resume with the new file (recorded in run.json; the earlier problem is kept for the generations it evaluated)",
                &cp.problem_hash[..12],
                &now[..12]
            );
            return Err(Error::RunDir { path: problem_path, message });
        }
        // the problem the checkpoint's generation was evaluated with
        let before = crate::record::problem_of_generation(dir, cp.state.generation.max(1))?;
        check_same_objects(&before.problem, &problem, &problem_path)?;
        notes.insert(0, format!("forced: problem file changed (sha256 {} → {})", &cp.problem_hash[..12], &now[..12]));
    }
    if cp.options.recording != Some(info.recording) {
        let value = |r: &Option<RecordOptions>| {
            serde_json::to_value(r).map_err(|source| Error::Json {
                path: run_json.clone(),
                what: "field `recording`",
                source,
            })
        };
        let (ours, theirs) = (value(&cp.options.recording)?, value(&Some(info.recording))?);
        return Err(modified(field_differences("options.recording", &ours, &theirs, &|_| RUN_FILE.into())));
    }
    let total = generations.unwrap_or(info.generations);
    super::limits::check_population(cp.settings.pop_size, total, info.recording.enabled)?;
    super::invariants::check_id_budget(&cp.state, cp.settings.pop_size, &cp_path, total)?;
    let size_note = super::limits::check_record_size(&problem, cp.settings.pop_size, info.recording.enabled)?;
    if total < cp.state.generation {
        return Err(Error::Input(format!(
            "--generations {total}: the run already has {} generations",
            cp.state.generation
        )));
    }
    let gp = GripperProblem::new(problem);
    let at = cp.state.generation;
    // the recording first: a resume it refuses (an unreadable or foreign shard) changes nothing
    let mut probe = info.clone();
    probe.problem_sha256 = now;
    let recorder = open_recorder(dir, &gp, &probe, at)?;
    switch(dir, &mut info, at, &gp.problem)?;
    info.resumes.push(Resume {
        at_generation: at,
        generations: total,
        forced: problem_changed || notes.iter().any(|n| n.starts_with("forced")),
        note: notes.join("; "),
    });
    let notes: Vec<String> = notes.into_iter().map(|n| format!("note: {n}")).chain(size_note).collect();
    info.generations = total;
    info.status = RunStatus::Running;
    info.completed_generations = at;
    info.evaluations = cp.state.evaluations;
    // the checkpoint resumed from (after a forced resume from an older one, not the newer
    // one run.json named)
    info.checkpoint_sha256 = Some(cp_sha256);
    write_json(&run_json, &info)?;
    write_current(dir, &info, &gp.problem)?;
    let state = cp.state.with_max_generations(total);
    // the algorithm the run started with (absent: NSGA-II's, a run from before issue 42)
    let (survival, variation) = (cp.options.survival, cp.options.variation);
    let start =
        Start { settings: cp.settings, state, recorder, archive, notes, wall_before: cp.wall_s, survival, variation };
    drive(gp, info, dir, threads, hooks, lock, start)
}

/// The recorder of run `info` in `out` (None when recording is off), recovering the
/// recording of a run whose checkpoint covers `completed` generations.
fn open_recorder(out: &Path, gp: &GripperProblem, info: &RunInfo, completed: u64) -> Result<Option<Recorder>> {
    if !info.recording.enabled {
        return Ok(None);
    }
    let meta = recording_metadata(gp, info);
    Recorder::open(out, gp.problem.clone(), meta, info.recording, completed).map(Some)
}

/// What `drive` starts from: the optimiser's settings and state, the recorder, the archive,
/// the notes to tell and the wall seconds of earlier processes.
struct Start {
    settings: Nsga2Settings,
    state: Nsga2State<GripperInfo>,
    recorder: Option<Recorder>,
    archive: Archive,
    notes: Vec<String>,
    wall_before: f64,
    /// The run's survival, as its checkpoints state it (None: crowding).
    survival: Option<Survival>,
    /// The run's variation, as its checkpoints state it (None: SBX).
    variation: Option<Variation>,
}

/// Run the optimiser from `begin` in the locked folder `out`: the persister writes each
/// generation (outputs, shard, checkpoint, run.json) while the next evaluates; then the final
/// outputs, or run.json's `interrupted` and the error that stopped it.
fn drive(
    gp: GripperProblem,
    info: RunInfo,
    out: &Path,
    threads: Option<usize>,
    hooks: RunHooks,
    lock: RunLock,
    begin: Start,
) -> Result<RunSummary> {
    let progress = ProgressObserver(Arc::new(Mutex::new(hooks.progress.unwrap_or_else(|| Box::new(())))));
    let start = Instant::now();
    let pool = pool(threads)?;
    let (mut gp, mut info) = (gp, info);
    info.threads = pool.current_num_threads();
    if info.recording.enabled {
        gp.recording = info.recording;
    }
    let Start { settings, state, recorder, archive, notes, wall_before, survival, variation } = begin;
    let options = RunOptions { survival, variation, ..RunOptions::of(&gp.problem.solver, &info.recording) };
    let recorder = tell_notes(&progress, &notes, recorder, settings.pop_size, info.threads);
    let archive = Arc::new(Mutex::new(archive));
    let d = Driver { out, lock: Arc::new(lock), start, wall_before, archive, recorder };
    let (persister, committed) = d.start_persister(&gp, &settings, options, &info)?;
    let (pers2, prog2) = (persister.clone(), progress.clone());
    let evaluator = hooks.evaluator.unwrap_or_else(|| gp.default_evaluator());
    let mut solver = Nsga2::with_evaluator(settings, evaluator)
        .with_survival(survival.unwrap_or(Survival::Crowding))
        .with_variation(variation.unwrap_or(Variation::Sbx));
    solver.stop = hooks.stop;
    let mut result = pool.install(|| execute(gp, solver, state, move |e| observe(observe(e, pers2), prog2)));
    if let Ok((_, st)) = &mut result {
        // the persister has the last generation's designs (with their trajectories) until
        // its shard is written; the final outputs need only the population and archive
        st.last_evaluated = Vec::new();
    }
    // on success every output of the final state is written below: the persister need
    // not write the last views too
    let ok = result.is_ok();
    let result = match (result, persister.finish_with(!ok)) {
        (Ok(_), Err(e)) => Err(e),
        (r, _) => r,
    };
    let info = d.committed_info(&committed);
    // the folder moved away or replaced: nothing more is written at its path
    d.lock.check()?;
    match result {
        Ok((gp, st)) => d.finish(&gp, &st, info, &pool),
        Err(e) => Err(d.stopped(info, e)),
    }
}

/// Tell the run's notes, the recorder's warnings and the threads note (in that order); the
/// recorder, shared with the persister.
fn tell_notes(
    progress: &ProgressObserver,
    notes: &[String],
    recorder: Option<Recorder>,
    pop_size: usize,
    threads: usize,
) -> Option<Arc<Mutex<Recorder>>> {
    let note = |m: &str| progress.0.lock().expect("progress lock").note(m);
    for n in notes {
        note(n);
    }
    let recorder = recorder.map(|r| {
        for w in &r.warnings {
            note(&format!("warning: {w}"));
        }
        Arc::new(Mutex::new(r))
    });
    if let Some(n) = super::limits::threads_note(pop_size, threads) {
        note(&n);
    }
    recorder
}

/// A run being driven: its folder and lock, its clocks, and what the persister shares.
struct Driver<'a> {
    out: &'a Path,
    lock: Arc<RunLock>,
    /// This process's start.
    start: Instant,
    /// Wall seconds of earlier processes.
    wall_before: f64,
    archive: Arc<Mutex<Archive>>,
    recorder: Option<Arc<Mutex<Recorder>>>,
}

impl Driver<'_> {
    /// The persister (outputs and archive, shard k, then checkpoint k, in that order on a
    /// background thread while k+1 evaluates: src/run/persist.rs), and run.json as its last
    /// commit left it (run.json follows each checkpoint).
    fn start_persister(
        &self,
        gp: &GripperProblem,
        settings: &Nsga2Settings,
        options: RunOptions,
        info: &RunInfo,
    ) -> Result<(Persister, Arc<Mutex<RunInfo>>)> {
        let out = self.out;
        let outputs =
            OutputsObserver { out: out.to_path_buf(), settings: settings.clone(), archive: self.archive.clone() };
        let ckpt = CheckpointSpec {
            path: out.join("checkpoint.json"),
            problem_hash: sha256_hex(gp.problem.source_text.as_bytes()),
            settings: settings.clone(),
            options,
            wall_before: self.wall_before,
            start: self.start,
        };
        let shared = Arc::new(Mutex::new(info.clone()));
        let (run_file, sh, commit_lock) = (out.join(RUN_FILE), shared.clone(), self.lock.clone());
        let on_commit = move |c: &Committed| -> Result<()> {
            // the folder may have been moved since the checkpoint was written: never write
            // run.json into the folder that replaced it
            commit_lock.check()?;
            let mut i = sh.lock().expect("run.json");
            i.completed_generations = c.generation;
            i.evaluations = c.evaluations;
            i.wall_s = c.wall_s;
            i.checkpoint_sha256 = Some(c.checkpoint_sha256.clone());
            i.discards = c.discards.clone();
            write_json(&run_file, &*i)
        };
        let guard_lock = self.lock.clone();
        let persist_hooks = PersistHooks {
            run_id: info.run_id.clone(),
            guard: Some(Arc::new(move || guard_lock.check())),
            on_commit: Some(Box::new(on_commit)),
        };
        let persister = Persister::start_with(Some(outputs), self.recorder.clone(), ckpt, info.threads, persist_hooks)?;
        Ok((persister, shared))
    }

    /// run.json of the committed generations, with this process's recording counters added.
    fn committed_info(&self, committed: &Mutex<RunInfo>) -> RunInfo {
        let mut info = committed.lock().expect("run.json").clone();
        if let Some(r) = &self.recorder {
            let r = r.lock().expect("recorder");
            info.recording_bytes += r.bytes;
            info.recording_s += r.seconds;
        }
        info
    }

    /// A run stopped by `e`: run.json says `interrupted`; the error says whether a
    /// checkpoint resumes it.
    fn stopped(&self, mut info: RunInfo, e: Error) -> Error {
        let out = self.out;
        info.status = RunStatus::Interrupted;
        info.wall_s = self.wall_before + self.start.elapsed().as_secs_f64();
        let _ = write_json(&out.join(RUN_FILE), &info);
        if out.join("checkpoint.json").exists() {
            Error::Stopped { path: out.to_path_buf(), source: Box::new(e) }
        } else {
            Error::StoppedBeforeCheckpoint { path: out.to_path_buf(), source: Box::new(e) }
        }
    }

    /// The final outputs of the state `st` (tables, plots, front.mcap, run.json) and the
    /// run's summary.
    fn finish(
        &self,
        gp: &GripperProblem,
        st: &Nsga2State<GripperInfo>,
        mut info: RunInfo,
        pool: &rayon::ThreadPool,
    ) -> Result<RunSummary> {
        let out = self.out;
        // a stop asked for once every requested generation is done (ctrl-c during a resume
        // with nothing left to do, or after the last generation) interrupted nothing
        let interrupted = matches!(st.get_termination_reason(), Some(argmin::core::TerminationReason::Interrupt))
            && st.generation < st.max_generations;
        info.completed_generations = st.generation;
        info.evaluations = st.evaluations;
        info.wall_s = self.wall_before + self.start.elapsed().as_secs_f64();
        info.status = if interrupted { RunStatus::Interrupted } else { RunStatus::Finished };
        let archive = self.archive.lock().expect("archive").clone();
        info.discards = archive.discards.clone();
        write_outputs(out, gp, st, &archive)?;
        let search = super::archive::reported_front(st, Some(&archive));
        // a robust run that certifies reports the certified front (its stage after the search)
        let certification =
            if interrupted { None } else { pool.install(|| super::certify_run(out, gp, st, &archive, &search))? };
        let front: Vec<u64> = match &certification {
            Some(c) => c.front.clone(),
            None => search.iter().map(|p| p.id).collect(),
        };
        let status =
            RunMetadata { status: Some(format!("{:?}", info.status).to_lowercase()), ..RunMetadata::default() };
        crate::record::write_front(out, &info.recording, &front, st.generation, &status)?;
        self.lock.check()?;
        write_json(&out.join(RUN_FILE), &info)?;
        Ok(RunSummary {
            out: out.to_path_buf(),
            generations: st.generation,
            evaluations: st.evaluations,
            front_size: front.len(),
            feasible: st.population.iter().filter(|p| p.eval.cv.is_feasible()).count(),
            hv: if archive.front.is_some() { archive.front_hv_history.last() } else { st.hv_history.last() }
                .copied()
                .unwrap_or(f64::NAN),
            archive_size: archive.members.len(),
            archive_hv: archive.hv_history.last().copied().unwrap_or(f64::NAN),
            interrupted,
            wall_s: self.start.elapsed().as_secs_f64(),
            discards: archive.discards,
            certification,
        })
    }
}

/// Metadata written into every shard of the recording: the run (its id, problem and the
/// problem's hash, settings, recording options; the shard adds its contents and time convention).
fn recording_metadata(gp: &GripperProblem, info: &RunInfo) -> RunMetadata {
    RunMetadata {
        gripopt_version: Some(env!("CARGO_PKG_VERSION").to_string()),
        simulator_revision: Some(crate::sim::revision_of(&gp.problem.solver)),
        run_id: Some(info.run_id.clone()),
        problem: Some(gp.problem.name.clone()),
        problem_sha256: Some(info.problem_sha256.clone()),
        // plain structs of numbers, strings and enums: serialising cannot fail
        settings: Some(serde_json::to_string(&info.settings).expect("settings serialise")),
        recording: Some(serde_json::to_string(&info.recording).expect("recording options serialise")),
        ..RunMetadata::default()
    }
}
