"""Columns handed over by the native module as pandas DataFrames, with units.

The native module gives each table as ``(name, kind, values, missing)`` tuples derived
from the library's row types (so the columns follow the rows' fields); here they become
DataFrame columns: floats as float64 (NaN: not computed), optional integers and booleans
as pandas' nullable ``Int64`` / ``boolean`` (``<NA>``: not computed), text as strings.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
import pandas as pd

from . import _gripopt

Columns = Sequence[tuple[str, str, Any, Optional[np.ndarray]]]
ColumnTable = Sequence[tuple[str, str, str]]


def units_of(table: ColumnTable) -> dict[str, str]:
    """``{column: unit}`` of a column table such as ``DESIGN_COLUMNS``."""
    return {name: unit for name, unit, _ in table}


def meanings_of(table: ColumnTable) -> dict[str, str]:
    """``{column: meaning}`` of a column table."""
    return {name: meaning for name, _, meaning in table}


def _column(kind: str, values: Any, missing: Optional[np.ndarray]) -> Any:
    if kind == "i64" and missing is not None:
        return pd.arrays.IntegerArray(values, missing)
    if kind == "bool" and missing is not None:
        return pd.arrays.BooleanArray(values, missing)
    if kind == "str":
        return pd.array(values, dtype="str")
    return values


#: A robust problem's count columns (docs/robust.md): the library holds their cells as
#: numbers of the row's robust cells; as counts they are ``Int64`` (<NA>: not simulated).
ROBUST_COUNTS = ("scenarios_run", "scenarios_saved")
ROBUST_COUNT_SUFFIXES = (".stays", ".scenarios")


def _is_count(name: str, kind: str) -> bool:
    return kind == "f64" and (name in ROBUST_COUNTS or name.endswith(ROBUST_COUNT_SUFFIXES))


def _count(values: Any) -> Any:
    """A count column given as float64 (NaN: missing) as ``Int64``: exact, every count is
    a whole number far below 2**53."""
    v = np.asarray(values, dtype="float64")
    missing = np.isnan(v)
    whole = np.where(missing, 0.0, v)
    if not np.array_equal(whole, np.trunc(whole)):
        return values  # not counts: left as they are
    return pd.arrays.IntegerArray(whole.astype("int64"), missing)


def frame(columns: Columns, table: ColumnTable, index: Optional[pd.Index] = None) -> pd.DataFrame:
    """A DataFrame of native ``columns``; ``table`` gives the units and meanings put in
    ``df.attrs["units"]`` and ``df.attrs["meanings"]`` (and the columns of an empty table).
    A design table's robust count columns are ``Int64``; a trajectory's (``SAMPLE_COLUMNS``)
    finger-2 columns of the offset scene get theirs from ``FINGER2_COLUMNS``."""
    counts = table is DESIGN_COLUMNS
    if columns:
        data = {
            name: _count(values) if counts and _is_count(name, kind) else _column(kind, values, missing)
            for name, kind, values, missing in columns
        }
        df = pd.DataFrame(data, index=index)
    else:
        df = pd.DataFrame({name: pd.Series(dtype="float64") for name, _, _ in table}, index=index)
    if counts:
        known = {name for name, _, _ in table}
        table = tuple(table) + robust_columns([c for c in df.columns if c not in known])
    if table is SAMPLE_COLUMNS:
        # an offset-scene trajectory: finger 2's columns after finger 1's
        table = tuple(table) + FINGER2_COLUMNS
    df.attrs["units"] = {c: units_of(table).get(c, "") for c in df.columns}
    df.attrs["meanings"] = {c: meanings_of(table).get(c, "") for c in df.columns}
    return df


def robust_columns(names: Sequence[str]) -> tuple[tuple[str, str, str], ...]:
    """The unit and meaning of each robust column among ``names`` (docs/robust.md): the
    design-level ones, and each object's ``NAME.column`` (the object named in its meaning)."""
    design = {name: (unit, meaning) for name, unit, meaning in _gripopt.ROBUST_COLUMNS}
    per_object = {name: (unit, meaning) for name, unit, meaning in _gripopt.OBJECT_COLUMNS}
    found = []
    for c in names:
        if c in design:
            found.append((c, *design[c]))
        elif "." in c and c.rsplit(".", 1)[1] in per_object:
            obj, col = c.rsplit(".", 1)
            unit, meaning = per_object[col]
            found.append((c, unit, f"{obj}: {meaning}"))
    return tuple(found)


DESIGN_NAMES: tuple[str, ...] = tuple(_gripopt.DESIGN_NAMES)
DESIGN_COLUMNS: ColumnTable = tuple(_gripopt.DESIGN_COLUMNS)
HISTORY_COLUMNS: ColumnTable = tuple(_gripopt.HISTORY_COLUMNS)
SAMPLE_COLUMNS: ColumnTable = tuple(_gripopt.SAMPLE_COLUMNS)
#: Finger 2's columns of an offset-scene trajectory (after ``SAMPLE_COLUMNS``'s).
FINGER2_COLUMNS: ColumnTable = tuple(_gripopt.FINGER2_COLUMNS)
POSE_COLUMNS: ColumnTable = tuple(_gripopt.POSE_COLUMNS)
