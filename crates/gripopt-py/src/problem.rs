//! `_gripopt.Problem`: a problem file, evaluated and simulated through the library's
//! application layer with the GIL released (the Python side, `gripopt.Problem`, makes the
//! DataFrames).

use crate::args;
use crate::errors::{argument, input, problem_error, IntoPy};
use crate::frame::Table;
use gripopt::app::{EvaluatedRow, NoSuchObject, SceneChoice, SimulateRequest};
use gripopt::{DesignParameters, Method, Problem, Stages, DESIGN_NAMES};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::path::{Path, PathBuf};

/// A loaded, validated problem file.
#[pyclass(name = "Problem", module = "gripopt._gripopt", frozen)]
pub struct PyProblem {
    pub problem: Problem,
    /// The file it was read from (None: TOML text).
    pub path: Option<PathBuf>,
}

/// What errors name when the problem came as text.
const TEXT: &str = "<problem text>";

/// The rows of an (n, 6) array as designs (ψ in degrees); every value finite.
fn designs_of(a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<DesignParameters>> {
    let a = a.as_array();
    if a.ncols() != 6 {
        return Err(input(format!("designs: {} columns, expected 6 ({})", a.ncols(), DESIGN_NAMES.join(", "))));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (k, row) in a.rows().into_iter().enumerate() {
        let x: [f64; 6] = std::array::from_fn(|i| row[i]);
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(input(format!("designs: row {k}, `{}` = {} is not finite", DESIGN_NAMES[i], x[i])));
        }
        out.push(DesignParameters::from_array(&x));
    }
    Ok(out)
}

/// One design (six values, ψ in degrees).
fn design_of(a: &PyReadonlyArray1<'_, f64>) -> PyResult<DesignParameters> {
    let a = a.as_array();
    if a.len() != 6 {
        return Err(input(format!("design: {} values, expected 6 ({})", a.len(), DESIGN_NAMES.join(", "))));
    }
    let x: [f64; 6] = std::array::from_fn(|i| a[i]);
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(input(format!("design: `{}` = {} is not finite", DESIGN_NAMES[i], x[i])));
    }
    Ok(DesignParameters::from_array(&x))
}

/// The rows as columns; no row: the columns and types of one (the library's template row
/// of the batch: the nominal design's stages 0-2, with a robust problem's columns where
/// `stages` simulates), with no values: an empty batch has the columns of any other.
fn rows_table(p: &Problem, rows: &[EvaluatedRow], stages: Stages) -> gripopt::Result<Table> {
    let table = if rows.is_empty() {
        let template = gripopt::app::row_template(p, stages)?;
        Table::of_or_like(&[], || Some(template))
    } else {
        Table::of(rows.iter().map(|r| &r.row))
    };
    table.map_err(|e| gripopt::Error::Input(format!("a row as columns: {e}")))
}

/// About how long one part of a batch runs (s) before Python handles its signals (ctrl-c).
const PART_SECONDS: f64 = 0.25;

/// `xs` evaluated as [`gripopt::evaluate_rows`] does, in parts of about [`PART_SECONDS`]
/// each with the GIL released, Python's signal handlers run between parts: ctrl-c raises
/// KeyboardInterrupt within a part's time, not at the batch's end. Each design's row is a
/// function of the design and its id alone, so the rows are the same whatever the parts
/// (their sizes follow the measured time) and the thread count. An empty batch is one
/// empty part (its arguments are checked all the same).
fn evaluate_interruptibly(
    py: Python<'_>,
    p: &Problem,
    xs: &[DesignParameters],
    first_id: u64,
    stages: Stages,
    threads: Option<usize>,
) -> PyResult<Vec<EvaluatedRow>> {
    let pool = crate::fork::Pool::new();
    let workers = threads.unwrap_or_else(|| pool.run(rayon::current_num_threads)).max(1);
    let mut rows = Vec::with_capacity(xs.len());
    let mut size = 4 * workers;
    loop {
        let start = rows.len();
        let part = &xs[start..xs.len().min(start + size)];
        let t = std::time::Instant::now();
        let id = first_id + start as u64;
        rows.extend(py.detach(|| pool.run(|| gripopt::evaluate_rows(p, part, id, stages, threads))).py()?);
        if rows.len() >= xs.len() {
            return Ok(rows);
        }
        py.check_signals()?;
        // the next part: about PART_SECONDS of work at this part's pace, at most 4 times
        // this one (a design's cost varies), never fewer designs than threads
        let scale = (PART_SECONDS / t.elapsed().as_secs_f64().max(1e-6)).clamp(0.25, 4.0);
        size = ((part.len() as f64 * scale) as usize).max(workers);
    }
}

/// The index of the robust object `name` of `p`: else an input error naming `object`.
fn object_index(p: &Problem, name: &str) -> PyResult<usize> {
    gripopt::app::object_index(p, name).map_err(|why| match why {
        NoSuchObject::NotRobust => {
            let why = "the problem is not robust (no [robust] section): its one object is its [object]";
            argument(
                "object",
                format!("object = {name:?}: {why}; object= picks one of a robust problem's [[robust.objects]]"),
            )
        }
        NoSuchObject::Unknown(names) => argument(
            "object",
            format!(
                "object = {name:?}: no such robust object; the problem's [[robust.objects]] are: {}",
                names.join(", ")
            ),
        ),
    })
}

/// A simulation's record as `gripopt simulate --json --object NAME` has it: the object
/// first (absent: the reference `[object]`), then the record.
#[derive(serde::Serialize)]
struct SimulationJson<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    object: Option<&'a str>,
    #[serde(flatten)]
    record: &'a gripopt::SimulationRecord,
}

impl PyProblem {
    /// The problem of a file.
    pub fn from_file(path: &Path) -> PyResult<Self> {
        let problem = Problem::load(path).map_err(|e| {
            // the text the error is about (read again: only on the error's path)
            let text = std::fs::read_to_string(path).ok();
            problem_error(e, text.as_deref(), path)
        })?;
        Ok(PyProblem { problem, path: Some(path.to_path_buf()) })
    }
}

#[pymethods]
impl PyProblem {
    /// Load and validate a problem file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        Self::from_file(&path)
    }

    /// Parse and validate problem text; `path`, if given, is what errors name.
    #[staticmethod]
    #[pyo3(signature = (text, path=None))]
    fn from_toml(text: &str, path: Option<PathBuf>) -> PyResult<Self> {
        let shown = path.clone().unwrap_or_else(|| PathBuf::from(TEXT));
        let problem = Problem::from_toml_str(text, &shown).map_err(|e| problem_error(e, Some(text), &shown))?;
        Ok(PyProblem { problem, path })
    }

    /// What a pickle carries besides the text: the text with each robust object given by
    /// `file = "…"` written inline (None: no such object).
    #[getter]
    fn inlined_toml(&self) -> PyResult<Option<String>> {
        gripopt::app::inlined_text(&self.problem).py()
    }

    /// The problem a pickle carried: `text` itself, or (`inlined` given) the problem of the
    /// inlined text with `text` as its own, each object's `file` as `text` names it: the
    /// object files are not read.
    #[staticmethod]
    #[pyo3(signature = (text, inlined, path=None))]
    fn unpickled(text: &str, inlined: Option<&str>, path: Option<PathBuf>) -> PyResult<Self> {
        let Some(inlined) = inlined else { return Self::from_toml(text, path) };
        let shown = path.clone().unwrap_or_else(|| PathBuf::from(TEXT));
        let problem = gripopt::app::from_inlined(text, inlined, &shown).py()?;
        Ok(PyProblem { problem, path })
    }

    /// The problem's name.
    #[getter]
    fn name(&self) -> &str {
        &self.problem.name
    }
    /// The file it was read from, or None.
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }
    /// The problem's TOML text.
    #[getter]
    fn toml(&self) -> &str {
        &self.problem.source_text
    }
    /// Lower bounds (optimiser units: m, m, m, -, -, deg).
    #[getter]
    fn lower<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.problem.bounds.lo)
    }
    /// Upper bounds.
    #[getter]
    fn upper<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.problem.bounds.hi)
    }
    /// The integration method of its grasp simulations (`solver.method`; absent: the default,
    /// auto with the default's tolerance scaling).
    #[getter]
    fn method(&self) -> &'static str {
        self.problem.solver.method.as_str()
    }
    /// The names of a robust problem's objects (`[[robust.objects]]`), None: not robust.
    #[getter]
    fn robust_objects(&self) -> Option<Vec<String>> {
        self.problem.robust.as_ref().map(|r| r.objects.iter().map(|o| o.name.clone()).collect())
    }
    /// The nominal design (ψ in degrees).
    #[getter]
    fn nominal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.problem.nominal.to_array())
    }

    /// Evaluate designs (n, 6) in parallel with the GIL released: their rows as columns,
    /// the minimised objectives (n, 4) and the constrained-domination key (n, 2: stages
    /// not reached, violation).
    #[pyo3(signature = (designs, static_only=false, threads=None, first_id=0))]
    #[allow(clippy::type_complexity)]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        designs: PyReadonlyArray2<'py, f64>,
        static_only: bool,
        #[pyo3(from_py_with = args::threads)] threads: Option<usize>,
        #[pyo3(from_py_with = args::first_id)] first_id: u64,
    ) -> PyResult<(Bound<'py, PyList>, Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        let xs = designs_of(&designs)?;
        if let Some(last) = xs.len().checked_sub(1) {
            if first_id.checked_add(last as u64).is_none_or(|id| id > i64::MAX as u64) {
                let rule = format!("the last of {} designs would have an id beyond {} (int64)", xs.len(), i64::MAX);
                return Err(argument("first_id", format!("first_id = {first_id}: {rule}")));
            }
        }
        let p = &self.problem;
        let rows = evaluate_interruptibly(py, p, &xs, first_id, Stages::of(static_only), threads)?;
        let (table, f, k) = py
            .detach(|| -> gripopt::Result<_> {
                let table = crate::fork::fork_safe(|| rows_table(p, &rows, Stages::of(static_only)))?;
                let (mut f, mut k) = (Vec::with_capacity(4 * rows.len()), Vec::with_capacity(2 * rows.len()));
                for r in &rows {
                    f.extend(r.minimised);
                    k.extend([f64::from(r.infeasibility.stages_short), r.infeasibility.violation]);
                }
                Ok((table, f, k))
            })
            .py()?;
        let n = xs.len();
        let f = PyArray1::from_vec(py, f).reshape([n, 4])?;
        let k = PyArray1::from_vec(py, k).reshape([n, 2])?;
        Ok((table.into_py(py)?, f, k))
    }

    /// The evaluation record of one design (`gripopt evaluate --json`), as Python objects.
    #[pyo3(signature = (design, static_only=false))]
    fn record<'py>(
        &self,
        py: Python<'py>,
        design: PyReadonlyArray1<'py, f64>,
        static_only: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let x = design_of(&design)?.design();
        let (p, stages) = (&self.problem, Stages::of(static_only));
        let r = py.detach(|| crate::fork::fork_safe(|| gripopt::evaluate(p, &x, stages)));
        crate::records::to_python(py, &gripopt::app::evaluation_record(p, &r, stages))
    }

    /// Simulate one design in a scene (None: the problem's) in diagnostic mode, as
    /// `gripopt simulate --json --csv` does: the record (Python objects), the grasp samples
    /// and (free scene) the object's poses as columns. `object`: one of a robust problem's
    /// objects by name (`simulate --object NAME`; None: the reference `[object]`).
    #[pyo3(signature = (design, scene=None, rtol=None, method=None, object=None))]
    #[allow(clippy::type_complexity)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        design: PyReadonlyArray1<'py, f64>,
        scene: Option<&str>,
        rtol: Option<f64>,
        method: Option<&str>,
        object: Option<&str>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyList>, Bound<'py, PyList>)> {
        let x = design_of(&design)?.design();
        let p = &self.problem;
        let scene = scene.map(SceneChoice::parse).transpose().py()?;
        // None: the problem's solver.method
        let method = match method {
            None => None,
            Some(m) => {
                Some(Method::parse(m).ok_or_else(|| input(format!("method `{m}`: must be {}", Method::accepted())))?)
            }
        };
        if let Some(r) = rtol {
            gripopt::app::check_rtol(r).map_err(|rule| argument("rtol", format!("rtol = {r}: {rule}")))?;
        }
        let s = &p.solver;
        let m = method.unwrap_or(s.method);
        m.check_atol(s.atol).map_err(|rule| {
            input(format!("method `{m}`: the problem's solver.atol {}: {rule}", gripopt::app::fmt_num(s.atol)))
        })?;
        if let Some(name) = object {
            object_index(p, name)?;
        }
        let req = SimulateRequest { scene, object: object.map(String::from), rtol, method, contacts: true };
        let sim = py.detach(|| crate::fork::fork_safe(|| gripopt::simulate(p, &x, &req))).py()?;
        let traj = Table::of_samples(&sim.trajectory.samples);
        let names = gripopt::POSE_COLUMNS.map(|c| c.0);
        let poses = Table::of_numbers(&names, sim.poses.iter().map(gripopt::pose_values));
        let record = SimulationJson { object: sim.object.as_deref(), record: &sim.record };
        Ok((crate::records::to_python(py, &record)?, traj.into_py(py)?, poses.into_py(py)?))
    }

    /// `n` designs (n, 6) drawn uniformly in the bounds from `seed`'s stream (those of
    /// `gripopt bench static --seed`).
    fn random_designs<'py>(
        &self,
        py: Python<'py>,
        #[pyo3(from_py_with = args::design_count)] n: usize,
        #[pyo3(from_py_with = args::seed)] seed: u64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let mut flat: Vec<f64> = Vec::new();
        // n is at most isize::MAX / 48 (args::design_count), so n * 6 doubles is a valid
        // size; whether the memory is there is asked here, not found out by an abort.
        flat.try_reserve_exact(n * 6).map_err(|_| {
            PyMemoryError::new_err(format!("n = {n}: {:.3e} bytes of designs do not fit in memory", n as f64 * 48.0))
        })?;
        flat.extend(gripopt::random_designs(&self.problem, n, seed).flat_map(|d| d.to_array()));
        PyArray1::from_vec(py, flat).reshape([n, 6])
    }
}
