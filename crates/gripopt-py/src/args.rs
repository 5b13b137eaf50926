//! Whole-number arguments (seeds, thread counts, sizes, ids) taken as any Python object and
//! checked here, so that a negative, too large or non-integer value is an `InputError`
//! naming the argument and its range, never PyO3's `OverflowError` or `TypeError`.
//!
//! Accepted: a Python `int` or an object with `__index__` (a NumPy integer). Refused: a
//! `bool` (`True` as a seed or a count is a slip, not a number), a `float` (even a whole
//! one: `1e3` as a population is a float's rounding away from a bug), text, None where a
//! number is required.

use crate::errors::argument;
use pyo3::prelude::*;
use pyo3::types::PyBool;

/// The argument `name` = `v` as a whole number in `min..=max`.
fn whole(name: &str, v: &Bound<'_, PyAny>, min: u64, max: u64) -> PyResult<u64> {
    let bad = |why: &str| {
        let shown = v.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".into());
        argument(name, format!("{name} = {shown}: must be an int from {min} to {max}{why}"))
    };
    if v.is_instance_of::<PyBool>() {
        return Err(bad(", not a bool"));
    }
    let index = v.py().import("operator")?.getattr("index")?;
    let Ok(i) = index.call1((v,)) else {
        let kind = v.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
        return Err(bad(&format!(", not a {kind}")));
    };
    match i.extract::<u64>() {
        Ok(n) if (min..=max).contains(&n) => Ok(n),
        _ => Err(bad("")),
    }
}

/// A whole number in `MIN..=MAX` (the range of a `u64` or of a `usize` at most).
fn ranged<T: TryFrom<u64>>(name: &str, v: &Bound<'_, PyAny>, min: u64, max: u64) -> PyResult<T> {
    let n = whole(name, v, min, max)?;
    T::try_from(n).map_err(|_| argument(name, format!("{name} = {n}: too large on this machine")))
}

/// `#[pyo3(from_py_with = args::NAME)]` extractors, one per argument name (the name is what
/// the error says), each with its range; the `Option` ones take None as "not given".
macro_rules! arguments {
    ($($(#[$doc:meta])* $f:ident: $t:ty = $name:literal, $min:expr, $max:expr;)*) => {$(
        $(#[$doc])*
        pub fn $f(v: &Bound<'_, PyAny>) -> PyResult<$t> {
            ranged($name, v, $min, $max)
        }
    )*};
}

arguments! {
    /// A seed: any `u64`.
    seed: u64 = "seed", 0, u64::MAX;
    /// A population size (the library checks its least and its memory).
    pop: usize = "pop", 0, u64::MAX;
    /// A number of generations (the library checks its least).
    generations: u64 = "generations", 0, u64::MAX;
    /// A design id of a run: any `u64`.
    design_id: u64 = "id", 0, u64::MAX;
    /// The first id of a batch: a DataFrame's id column is int64.
    first_id: u64 = "first_id", 0, i64::MAX as u64;
    /// A number of designs to draw: an (n, 6) float64 array must be addressable.
    design_count: usize = "n", 0, (isize::MAX as u64) / 48;
    /// A thread count: 1 to `gripopt::app::MAX_THREADS`.
    thread_count: usize = "threads", 1, gripopt::app::MAX_THREADS as u64;
}

/// A thread count or None (all cores).
pub fn threads(v: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    if v.is_none() {
        return Ok(None);
    }
    thread_count(v).map(Some)
}

/// A number of generations or None (the run's own).
pub fn generations_or_none(v: &Bound<'_, PyAny>) -> PyResult<Option<u64>> {
    if v.is_none() {
        return Ok(None);
    }
    generations(v).map(Some)
}
