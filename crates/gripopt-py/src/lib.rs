//! `gripopt._gripopt`, the native module of the `gripopt` Python package (python/gripopt):
//! the library's application layer for Python — problems evaluated and simulated with the
//! GIL released, runs started and resumed with a progress callback and ctrl-c, run folders
//! read back — handing tables over as typed columns that the Python side turns into pandas
//! DataFrames, and records as Python objects. Errors become the exceptions of
//! `gripopt.errors`. docs/python.md.

mod args;
mod errors;
mod fork;
mod frame;
mod problem;
mod records;
mod run;
mod toml_field;

use pyo3::prelude::*;

/// A table's columns as (name, unit, meaning) for Python.
fn columns(cols: &[gripopt::Column]) -> Vec<(&'static str, &'static str, &'static str)> {
    cols.to_vec()
}

/// The native module.
#[pymodule]
fn _gripopt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    fork::note_import();
    m.add_class::<problem::PyProblem>()?;
    m.add_class::<run::PyRunFolder>()?;
    m.add_function(wrap_pyfunction!(run::optimise, m)?)?;
    m.add_function(wrap_pyfunction!(run::resume, m)?)?;
    m.add("DESIGN_NAMES", gripopt::DESIGN_NAMES.to_vec())?;
    m.add("DESIGN_COLUMNS", columns(&gripopt::DESIGN_COLUMNS))?;
    m.add("HISTORY_COLUMNS", columns(&gripopt::HISTORY_COLUMNS))?;
    m.add("SAMPLE_COLUMNS", columns(&gripopt::SAMPLE_COLUMNS))?;
    m.add("FINGER2_COLUMNS", columns(&gripopt::FINGER2_COLUMNS))?;
    m.add("POSE_COLUMNS", columns(&gripopt::POSE_COLUMNS))?;
    // a robust problem's design-table columns: these, then each object's `NAME.column`
    m.add("ROBUST_COLUMNS", gripopt::app::ROBUST_COLUMNS.to_vec())?;
    m.add("OBJECT_COLUMNS", gripopt::app::OBJECT_COLUMNS.to_vec())?;
    // the four objectives: (name, unit, meaning, sense), sense "maximise" or "minimise"
    let objectives: Vec<_> =
        gripopt::app::OBJECTIVES.iter().map(|o| (o.name, o.unit, o.meaning, o.sense.word())).collect();
    m.add("OBJECTIVES", objectives)?;
    // the JSON schema of a recorded design's `/designs` message (the keys of RunFolder.design's record)
    m.add("DESIGN_SCHEMA", records::to_python(m.py(), &gripopt::app::design_schema(gripopt::Method::Radau5))?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
