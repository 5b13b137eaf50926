//! Runs from Python: `optimise` / `resume` through the application layer's `Optimiser` (a
//! progress callback, the stop flag set by ctrl-c or by the callback's exception; a run of a
//! problem held in memory as `app::ProblemRun` decides) and `_gripopt.RunFolder`, a run folder
//! read back through the library's reader.

use crate::args;
use crate::errors::{input, IntoPy};
use crate::frame::Table;
use crate::problem::PyProblem;
use crate::records::to_python;
use gripopt::app::ProblemRun;
use gripopt::{GenerationReport, HistoryRow, Optimiser, Progress, RecordOptions, RunFolder, RunSummary};
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
        "certified" => s.certification.as_ref().map(|c| c.certified),
        "certification_tested" => s.certification.as_ref().map(|c| c.tested),
    }))
}

/// Recording options: None = the defaults, False = nothing recorded, else a mapping of
/// run.json's `recording` fields over the defaults (`gripopt optimise --record-*`; checked
/// by the library).
fn record_options(record: Option<&Bound<'_, PyAny>>) -> PyResult<RecordOptions> {
    let Some(record) = record.filter(|r| !r.is_none()) else { return Ok(RecordOptions::default()) };
    if record.is_instance_of::<pyo3::types::PyBool>() {
        return Ok(if record.extract::<bool>()? { RecordOptions::default() } else { RecordOptions::none() });
    }
    let fields: serde_json::Map<String, serde_json::Value> =
        pythonize::depythonize(record).map_err(|e| input(format!("record: not a mapping of options: {e}")))?;
    gripopt::app::record_options(&fields).py()
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
    record: Option<Bound<'py, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let rec = record_options(record.as_ref())?;
    gripopt::app::check_population(pop, generations, rec.enabled).py()?;
    let run = ProblemRun::prepare(&problem.problem, problem.path.as_deref(), &out).py()?;
    let opt =
        Optimiser::new(run.file(), &out).pop(pop).generations(generations).seed(seed).record(rec).threads(threads);
    let ran = run.note.as_deref().map_or(Ok(()), |n| warn(py, n)).and_then(|()| drive(py, opt, progress, &out));
    let s = match ran {
        Ok(s) => run.finish(Ok(s)).py()?,
        Err(e) => {
            run.abandon();
            return Err(e);
        }
    };
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
    let mut opt = Optimiser::resume(&path).force(force).threads(threads);
    if let Some(g) = generations {
        opt = opt.generations(g);
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
        Ok(PyRunFolder { folder: gripopt::app::open_run(&path).py()? })
    }
    /// The folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.folder.dir().to_path_buf()
    }
    /// run.json, as Python objects.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.folder.info().py()?)
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
        if name == "history" {
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
        let (rows, why) = py.detach(|| gripopt::app::design_table(f, name)).py()?;
        if let Some(why) = why {
            warn(py, &why)?;
        }
        // an empty front or archive has the columns of the population's rows (a robust
        // problem's included)
        let template = || f.population().ok().and_then(|p| p.into_iter().next());
        columns(py, &rows, template)
    }
    /// Design `id` as recorded: its `/designs` message (Python objects), its trajectory as
    /// columns, the resolution and the shard.
    #[allow(clippy::type_complexity)]
    fn design<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = args::design_id)] id: u64,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyList>, Bound<'py, PyAny>, PathBuf)> {
        let f = &self.folder;
        let rec = py.detach(|| f.design(id)).py()?;
        let traj = Table::of_samples(&rec.samples);
        Ok((to_python(py, &rec.record)?, traj.into_py(py)?, to_python(py, &rec.resolution)?, rec.file))
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
            "fresh" => to_python(py, &r.fresh)?,
            "file" => &r.recorded.file,
            // a recording by another simulator revision: agreement within the tolerance
            "agrees_across_revisions" => r.across_revisions.as_ref().map(|a| a.agrees()),
        }))
    }
}
