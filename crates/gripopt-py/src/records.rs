//! Records into Python objects: a typed record (an evaluation or simulation record, a
//! `/designs` message, run.json) becomes dicts, lists, numbers, strings and None through its
//! serde form (`pythonize`), as its JSON has it — a value not computed is None, and so is a
//! number that is not finite (the JSON of the CLI writes it as null); a fixed-size array is a
//! list, as every other sequence — its keys in the record's order. No JSON text crosses.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyList, PyTuple};

/// `v` as Python objects (see the module's documentation).
pub fn to_python<'py, T: serde::Serialize + ?Sized>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let o = pythonize::pythonize(py, v).map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
    as_json(o)
}

/// `o` as its JSON has it: every float that is not finite None, every tuple a list, in
/// dicts and lists at any depth.
fn as_json(o: Bound<'_, PyAny>) -> PyResult<Bound<'_, PyAny>> {
    let py = o.py();
    let finite = o.cast::<PyFloat>().map(|f| f.value().is_finite());
    if let Ok(finite) = finite {
        return Ok(if finite { o } else { py.None().into_bound(py) });
    }
    if let Ok(t) = o.cast::<PyTuple>() {
        let items = t.iter().map(as_json).collect::<PyResult<Vec<_>>>()?;
        return Ok(PyList::new(py, items)?.into_any());
    }
    if let Ok(d) = o.cast::<PyDict>() {
        let items: Vec<_> = d.iter().collect();
        for (k, v) in items {
            d.set_item(k, as_json(v)?)?;
        }
    } else if let Ok(l) = o.cast::<PyList>() {
        let items: Vec<_> = l.iter().collect();
        for (i, v) in items.into_iter().enumerate() {
            l.set_item(i, as_json(v)?)?;
        }
    }
    Ok(o)
}
