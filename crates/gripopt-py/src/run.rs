//! Runs from Python: `optimise` / `resume` through the facade's `Optimiser` (a progress
//! callback, the stop flag set by ctrl-c or by the callback's exception) and
//! `_gripopt.RunFolder`, a run folder read back through the library's reader.

use crate::args;
use crate::errors::{input, to_py, IntoPy};
use crate::frame::Table;
use crate::problem::PyProblem;
use gripopt::run::{DesignRow, HistoryRow};
use gripopt::{GenerationReport, Optimiser, Progress, RecordOptions, RunFolder, RunSummary};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A Python dict of `"key" => value` pairs, in that order (each value converted by PyO3;
/// a failed conversion returns its error from the enclosing function).
macro_rules! py_dict {
    ($py:expr, { $($key:literal => $value:expr),+ $(,)? }) => {{
        let d = PyDict::new($py);
        $(d.set_item($key, $value)?;)+
        d
    }};
}

/// How often the waiting thread lets Python run its signal handlers (ctrl-c).
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// The run's progress, told to a Python callable; an exception it raises stops the run
/// after the generation's checkpoint and is raised again when the run has stopped. Notes
/// are kept for the caller's thread, which issues them as Python warnings
/// (`gripopt.errors.GripoptWarning`) at the caller's line: the run's thread has no Python
/// caller (a warning issued there is reported at `sys:1`).
struct PyProgress {
    callback: Option<Py<PyAny>>,
    stop: Arc<AtomicBool>,
    raised: Arc<Mutex<Option<PyErr>>>,
    notes: Arc<Mutex<Vec<String>>>,
}

impl PyProgress {
    fn keep(&self, e: PyErr) {
        self.stop.store(true, Ordering::SeqCst);
        let mut r = self.raised.lock().expect("progress error");
        if r.is_none() {
            *r = Some(e);
        }
    }
}

impl Progress for PyProgress {
    fn generation(&mut self, g: &GenerationReport) -> Result<(), String> {
        let Some(cb) = &self.callback else { return Ok(()) };
        let r = Python::attach(|py| -> PyResult<()> {
            let d = py_dict!(py, {
                "generation" => g.generation,
                "max_generations" => g.max_generations,
                "evaluations" => g.evaluations,
                "population" => g.population,
                "feasible" => g.feasible,
                "hypervolume" => g.hypervolume,
            });
            cb.call1(py, (d,))?;
            Ok(())
        });
        if let Err(e) = r {
            self.keep(e);
        }
        Ok(())
    }
    fn note(&mut self, message: &str) {
        self.notes.lock().expect("run notes").push(message.to_string());
    }
}

/// Run `opt` on a thread of its own while this one, the caller's, lets Python handle
/// signals: ctrl-c (KeyboardInterrupt) sets the stop flag, the run ends after the
/// generation's checkpoint (resumable), and the KeyboardInterrupt is raised then, with a
/// note saying so. The run's own error comes first, then the callback's exception.
fn drive(py: Python<'_>, opt: Optimiser, callback: Option<Py<PyAny>>, out: &Path) -> PyResult<RunSummary> {
    let stop = Arc::new(AtomicBool::new(false));
    let raised = Arc::new(Mutex::new(None));
    let notes = Arc::new(Mutex::new(Vec::new()));
    let progress = PyProgress { callback, stop: stop.clone(), raised: raised.clone(), notes: notes.clone() };
    // the notes so far as warnings, on this (the caller's) thread; a warning turned into an
    // error (a warnings filter) stops the run as the callback's exception does
    let warn_notes = |py: Python<'_>| {
        let taken = std::mem::take(&mut *notes.lock().expect("run notes"));
        if let Err(e) = taken.iter().try_for_each(|n| warn(py, n)) {
            stop.store(true, Ordering::SeqCst);
            raised.lock().expect("progress error").get_or_insert(e);
        }
    };
    let opt = opt.progress(progress).stop_flag(stop.clone());
    let mut interrupt: Option<PyErr> = None;
    let joined = py.detach(|| {
        std::thread::scope(|s| {
            let run = s.spawn(move || crate::fork::fork_safe(|| opt.run()));
            while !run.is_finished() {
                std::thread::sleep(SIGNAL_POLL);
                Python::attach(warn_notes);
                if interrupt.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        stop.store(true, Ordering::SeqCst);
                        interrupt = Some(e);
                    }
                }
            }
            run.join()
        })
    });
    let result = joined.unwrap_or_else(|panic| std::panic::resume_unwind(panic));
    warn_notes(py);
    let summary = result.py()?;
    if let Some(e) = raised.lock().expect("progress error").take() {
        return Err(e);
    }
    if let Some(e) = interrupt {
        let note = format!(
            "gripopt: the run stopped after generation {}'s checkpoint; gripopt.resume({:?}) continues it",
            summary.generations,
            out.display().to_string()
        );
        let _ = e.value(py).call_method1("add_note", (note,));
        return Err(e);
    }
    Ok(summary)
}

/// The summary as a dict.
fn summary_dict<'py>(py: Python<'py>, s: &RunSummary) -> PyResult<Bound<'py, PyDict>> {
    Ok(py_dict!(py, {
        "out" => &s.out,
        "generations" => s.generations,
        "evaluations" => s.evaluations,
        "front_size" => s.front_size,
        "feasible" => s.feasible,
        "hypervolume" => s.hv,
        "archive_size" => s.archive_size,
        "archive_hypervolume" => s.archive_hv,
        "interrupted" => s.interrupted,
        "wall_s" => s.wall_s,
    }))
}

/// Recording options: None = the defaults, "none" = nothing recorded, else a JSON object
/// of fields over the defaults (`gripopt optimise --record-*`; checked by the library).
fn record_options(record: Option<&str>) -> PyResult<RecordOptions> {
    let Some(text) = record else { return Ok(RecordOptions::default()) };
    if text == "none" {
        return Ok(RecordOptions::none());
    }
    let bad = |m: String| input(format!("record: {m}"));
    let mut v = serde_json::to_value(RecordOptions::default()).map_err(|e| bad(e.to_string()))?;
    let given: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(text).map_err(|e| bad(format!("not a mapping of options: {e}")))?;
    let fields = v.as_object_mut().expect("options are an object");
    for (k, x) in given {
        if !fields.contains_key(&k) {
            let known: Vec<&str> = fields.keys().map(String::as_str).filter(|k| *k != "epoch_s").collect();
            return Err(bad(format!("unknown option `{k}` (known: {})", known.join(", "))));
        }
        fields.insert(k, x);
    }
    let options: RecordOptions = serde_json::from_value(v).map_err(|e| bad(e.to_string()))?;
    options.validate().py()?;
    Ok(options)
}

/// The problem file a run of `problem` starts from, and records as its source: the file it
/// was loaded from where that file still holds exactly the problem's text (as `gripopt
/// optimise FILE`: run.json names the file, a resume follows its edits); otherwise (text,
/// a name with no such file, a file edited since, or other text named after a file) the
/// problem's own text written into `out` as problem.toml, which `out` must then be new or
/// empty for: the run records that copy as its source, never a file whose content it did
/// not run. The second value is a note for the caller where a file was set aside.
fn problem_file(problem: &PyProblem, out: &Path) -> PyResult<(PathBuf, Option<String>)> {
    let text = &problem.problem.source_text;
    let mut note = None;
    if let Some(p) = &problem.path {
        match std::fs::read(p) {
            Ok(bytes) if bytes == text.as_bytes() => return Ok((p.clone(), None)),
            Ok(_) => {
                note = Some(format!(
                    "{}: the file's content is not the problem's text (edited since the problem was loaded, or the text was only named after it); the run uses the problem's text, written to {} as its source",
                    p.display(),
                    out.join(gripopt::run::PROBLEM_FILE).display()
                ))
            }
            Err(_) => {}
        }
    }
    let empty = match std::fs::read_dir(out) {
        Ok(mut rd) => rd.next().is_none(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
        Err(e) => return Err(to_py(gripopt::Error::io(out, "cannot list the run folder", e))),
    };
    if !empty {
        let why = match &problem.path {
            None => "a problem given as text".to_string(),
            Some(p) => {
                format!("a problem whose text is not the content of {} (no such file, or another text)", p.display())
            }
        };
        return Err(to_py(gripopt::Error::RunDir {
            path: out.to_path_buf(),
            message: format!("not empty: {why} starts a run only in a new or empty folder (its text is written there as problem.toml); load the problem from its file instead"),
        }));
    }
    std::fs::create_dir_all(out).map_err(|e| to_py(gripopt::Error::io(out, "cannot create the run folder", e)))?;
    let file = out.join(gripopt::run::PROBLEM_FILE);
    std::fs::write(&file, text).map_err(|e| to_py(gripopt::Error::io(&file, "cannot write", e)))?;
    Ok((file, note))
}

/// A run that stopped before it wrote run.json (a problem refused by the run, say) leaves
/// nothing of its own in `out`: the problem's copy written for it is taken back, and the
/// folder if this call created it, so that the same call can be made again.
fn take_back_copy(file: &Path, out: &Path, created: bool) {
    if out.join(gripopt::run::RUN_FILE).exists() {
        return;
    }
    let _ = std::fs::remove_file(file);
    if created {
        let _ = std::fs::remove_dir(out); // only if empty
    }
}

/// After a run from the problem's own file: the file the run read (its copy in `out`)
/// must be the problem's text; a file replaced between the check and the run's start is
/// named, so that a run of other text is never returned as the problem's.
fn check_ran_text(problem: &PyProblem, file: &Path, out: &Path) -> PyResult<()> {
    let copy = out.join(gripopt::run::PROBLEM_FILE);
    match std::fs::read(&copy) {
        Ok(bytes) if bytes == problem.problem.source_text.as_bytes() => Ok(()),
        _ => Err(to_py(gripopt::Error::RunDir {
            path: out.to_path_buf(),
            message: format!(
                "{} changed while the run started: the run (attributed to that file, as its run.json says) is not of the problem given",
                file.display()
            ),
        })),
    }
}

/// A `GripoptWarning` with `message`, reported at the caller's line (the first frame
/// outside the package: `gripopt.errors._warn`).
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    py.import("gripopt.errors")?.call_method1("_warn", (message,))?;
    Ok(())
}

/// Start a run of `problem` in `out`: its summary.
#[pyfunction]
#[pyo3(signature = (problem, out, pop=100, generations=50, seed=1, threads=None, record=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn optimise<'py>(
    py: Python<'py>,
    problem: &PyProblem,
    out: PathBuf,
    #[pyo3(from_py_with = args::pop)] pop: usize,
    #[pyo3(from_py_with = args::generations)] generations: u64,
    #[pyo3(from_py_with = args::seed)] seed: u64,
    #[pyo3(from_py_with = args::threads)] threads: Option<usize>,
    record: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let rec = record_options(record)?;
    gripopt::run::check_population(pop, generations, rec.enabled).py()?;
    let created = !out.exists();
    let (file, note) = problem_file(problem, &out)?;
    let copied = problem.path.as_deref() != Some(file.as_path());
    let mut opt = Optimiser::new(&file, &out).pop(pop).generations(generations).seed(seed).record(rec);
    if let Some(t) = threads {
        opt = opt.threads(t);
    }
    let ran = note.map_or(Ok(()), |n| warn(py, &n)).and_then(|()| drive(py, opt, progress, &out));
    let s = match ran {
        Ok(s) => s,
        Err(e) => {
            if copied {
                take_back_copy(&file, &out, created);
            }
            return Err(e);
        }
    };
    if !copied {
        check_ran_text(problem, &file, &out)?;
    }
    summary_dict(py, &s)
}

/// Resume the run in `path` (to `generations` in all, or the run's own total).
#[pyfunction]
#[pyo3(signature = (path, generations=None, threads=None, force=false, progress=None))]
pub fn resume<'py>(
    py: Python<'py>,
    path: PathBuf,
    #[pyo3(from_py_with = args::generations_or_none)] generations: Option<u64>,
    #[pyo3(from_py_with = args::threads)] threads: Option<usize>,
    force: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opt = Optimiser::resume(&path).force(force);
    if let Some(g) = generations {
        opt = opt.generations(g);
    }
    if let Some(t) = threads {
        opt = opt.threads(t);
    }
    let s = drive(py, opt, progress, &path)?;
    summary_dict(py, &s)
}

/// A run folder, read through the library, pinned to the run it held when opened
/// ([`RunFolder::open_pinned`]): a folder replaced by another run is an error, never read
/// as the opened run's.
#[pyclass(name = "RunFolder", module = "gripopt._gripopt", frozen)]
pub struct PyRunFolder {
    folder: RunFolder,
}

/// Why the view `file` (of table `name`) does not hold the designs of the run's checkpoint,
/// and the checkpoint's rows of the table (None: it does, there is no checkpoint yet, or a
/// process runs the run).
fn view_differs(f: &RunFolder, name: &str, file: &str) -> gripopt::Result<Option<(String, Vec<DesignRow>)>> {
    if matches!(f.state()?, gripopt::run::RunState::Running(_)) {
        return Ok(None);
    }
    let Some(t) = f.checkpoint_tables()? else { return Ok(None) };
    let rows = match name {
        "front" => t.front,
        "archive" => t.archive,
        _ => t.population,
    };
    Ok(f.view_differs(file, &rows, t.generation)?.map(|why| (why, rows)))
}

fn json<T: serde::Serialize>(v: &T) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
}

/// `rows` as columns; none: the columns of `template()` (a row of the same table), with
/// no values.
fn columns<'py, T: serde::Serialize + serde::de::DeserializeOwned>(
    py: Python<'py>,
    rows: &[T],
    template: impl FnOnce() -> Option<T>,
) -> PyResult<Bound<'py, PyList>> {
    Table::of_or_like(rows, template).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?.into_py(py)
}

#[pymethods]
impl PyRunFolder {
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        Ok(PyRunFolder { folder: RunFolder::open_pinned(path).py()? })
    }
    /// The folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.folder.dir().to_path_buf()
    }
    /// run.json as JSON text.
    fn info(&self) -> PyResult<String> {
        json(&self.folder.info().py()?)
    }
    /// The run's problem in force (its copy in the folder), checked against the hash
    /// run.json recorded: an edited copy is an error naming it (as replay and verify).
    fn problem(&self) -> PyResult<PyProblem> {
        let (problem, file) = self.folder.problem_in_force().py()?;
        Ok(PyProblem { problem, path: Some(file) })
    }
    /// What the run is doing, as `gripopt show` says it: running, stopped (killed or
    /// crashed: run.json says running but no process holds the folder), interrupted,
    /// finished.
    fn state(&self) -> PyResult<&'static str> {
        Ok(self.folder.state().py()?.word())
    }
    /// A table as columns: `front`, `population`, `archive` or `history`. A design table
    /// that does not hold the designs of the run's checkpoint (an older copy, or edited by
    /// hand) gives the checkpoint's designs, with a `GripoptWarning` saying so, as `gripopt
    /// show` does (not while a process runs the run: its views follow its checkpoints).
    fn table<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyList>> {
        let f = &self.folder;
        let (rows, file) = match name {
            "front" => (f.front().py()?, "pareto.csv"),
            "population" => (f.population().py()?, "population.csv"),
            "archive" => (f.archive().py()?, "archive.csv"),
            "history" => {
                let template = HistoryRow {
                    generation: 0,
                    evaluations: 0,
                    feasible: 0,
                    hypervolume: 0.0,
                    archive_hypervolume: None,
                    pareto_hypervolume: None,
                };
                return columns(py, &f.history().py()?, || Some(template));
            }
            _ => return Err(input(format!("table `{name}`: must be front, population, archive or history"))),
        };
        let rows = match py.detach(|| view_differs(f, name, file)).py()? {
            Some((why, checkpoint_rows)) => {
                warn(py, &format!("{}: {why}", f.dir().display()))?;
                checkpoint_rows
            }
            None => rows,
        };
        // an empty front or archive has the columns of the population's rows (a robust
        // problem's included)
        let template = || f.population().ok().and_then(|p| p.into_iter().next());
        columns(py, &rows, template)
    }
    /// Design `id` as recorded: its `/designs` message (JSON text), its trajectory as
    /// columns, the resolution and the shard.
    #[allow(clippy::type_complexity)]
    fn design<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = args::design_id)] id: u64,
    ) -> PyResult<(String, Bound<'py, PyList>, String, PathBuf)> {
        let f = &self.folder;
        let rec = py.detach(|| f.design(id)).py()?;
        let traj = Table::of_samples(&rec.samples);
        let res = serde_json::to_value(rec.resolution).ok().and_then(|v| v.as_str().map(String::from));
        Ok((json(&rec.record)?, traj.into_py(py)?, res.unwrap_or_default(), rec.file))
    }
    /// Re-simulate design `id` and compare it with its recording.
    fn replay<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = args::design_id)] id: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let f = &self.folder;
        let r = py.detach(|| crate::fork::fork_safe(|| f.replay(id))).py()?;
        Ok(py_dict!(py, {
            "verified" => r.verified,
            "max_difference" => r.max_difference,
            "compared" => r.compared,
            "values_compared" => r.values_compared,
            "recomputed_feasible" => r.recomputed_feasible,
            "fresh" => json(&r.fresh)?,
            "file" => &r.recorded.file,
            // a recording by another simulator revision: agreement within the tolerance
            "agrees_across_revisions" => r.across_revisions.as_ref().map(|a| a.agrees()),
        }))
    }
}
