"""A gripper design problem: load it, evaluate designs into DataFrames, simulate one."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import pandas as pd

from . import _gripopt
from ._frames import DESIGN_COLUMNS, DESIGN_NAMES, POSE_COLUMNS, SAMPLE_COLUMNS, frame
from .errors import InputError, _warn

#: Designs as accepted by :meth:`Problem.evaluate`: a DataFrame with the six named columns
#: (others are ignored), an (n, 6) array, a sequence of designs each a mapping by name, or
#: one design (a Series, a mapping by name, six values). ψ is ``psi_deg``, in degrees,
#: everywhere.
Designs = Union[
    pd.DataFrame,
    np.ndarray,
    Sequence[Sequence[float]],
    Sequence[Mapping[str, float]],
    pd.Series,
    Mapping[str, float],
    Sequence[float],
]


def _flag(name: str, value: Any) -> bool:
    """The yes/no argument ``name``: a bool (or a NumPy bool); anything else (``"no"``, 0,
    None) is an :class:`InputError` naming the argument."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InputError(f"{name} = {value!r}: must be True or False, not a {type(value).__name__}", field=name)


def _refuse_complex(dtype: Any, name: str) -> None:
    """Complex numbers are not designs (their imaginary part would be dropped). Any dtype,
    pandas' own (nullable ``Int64``, ``Float64``, ``string``, …) included."""
    if pd.api.types.is_complex_dtype(dtype):
        raise InputError(f"{name}: complex numbers (dtype {dtype}); a design's values are real", field=name)


def _numeric_column(designs: pd.DataFrame, name: str) -> pd.Series:
    """Column ``name`` as float64; a cell that is not a number is an :class:`InputError`
    naming the column and the row."""
    column = designs[name]
    _refuse_complex(column.dtype, name)
    if column.dtype == object and any(isinstance(v, (complex, np.complexfloating)) for v in column):
        raise InputError(f"designs: column `{name}` holds complex numbers; a design's values are real", field=name)
    try:
        return column.astype("float64")
    except (TypeError, ValueError):
        pass
    for k, (label, v) in enumerate(column.items()):
        try:
            float(v)
        except (TypeError, ValueError):
            raise InputError(
                f"designs: {_row_name(designs.index, k, label)}, `{name}` = {v!r} is not a number",
                field=name,
            ) from None
    raise InputError(f"designs: column `{name}` is not numbers (dtype {column.dtype})", field=name)


def _row_name(index: pd.Index, k: int, label: Any) -> str:
    """Row ``k`` as an error names it: its position, and its index label where the index
    is not the positions 0, 1, …"""
    if isinstance(index, pd.RangeIndex) and index.start == 0 and index.step == 1:
        return f"row {k}"
    return f"row {k} (index label {label!r})"


def design_frame(designs: Designs) -> pd.DataFrame:
    """``designs`` as a DataFrame of the six design columns (float64), one row per design;
    a DataFrame keeps its index. Raises :class:`InputError` for a missing column, a cell
    that is not a number (naming the column and the row) or a wrong shape."""
    names = list(DESIGN_NAMES)
    if isinstance(designs, (list, tuple)) and designs and all(isinstance(r, (Mapping, pd.Series)) for r in designs):
        designs = pd.DataFrame([dict(r) for r in designs])
    if isinstance(designs, pd.DataFrame):
        missing = [n for n in names if n not in designs.columns]
        if missing:
            raise InputError(
                f"designs: missing column(s) {', '.join(missing)} (a design is {', '.join(names)}; "
                "psi_deg is ψ in degrees)",
                field="designs",
            )
        twice = [n for n in names if list(designs.columns).count(n) > 1]
        if twice:
            raise InputError(
                f"designs: column(s) {', '.join(twice)} given more than once; a design has one of each",
                field=twice[0],
            )
        return pd.DataFrame({n: _numeric_column(designs, n).to_numpy() for n in names}, index=designs.index)
    if isinstance(designs, (pd.Series, Mapping)):
        row = pd.Series(designs)
        missing = [n for n in names if n not in row.index]
        if missing:
            raise InputError(f"design: missing {', '.join(missing)} (psi_deg is ψ in degrees)", field="design")
        return design_frame(pd.DataFrame([row[names].to_dict()]))
    try:
        kind = np.asarray(designs).dtype
    except (TypeError, ValueError):
        kind = np.dtype(object)  # ragged: refused below
    _refuse_complex(kind, "designs")
    try:
        a = np.asarray(designs, dtype="float64")
    except (TypeError, ValueError) as e:
        raise InputError(
            f"designs: {type(designs).__name__} is not designs ({e}): give a DataFrame with the columns "
            f"{', '.join(names)}, an (n, 6) array of numbers, mappings by name, or one design",
            field="designs",
        ) from None
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 6:
        raise InputError(
            f"designs: an array of shape {np.shape(designs)}, expected (n, 6) or (6,): {', '.join(names)}",
            field="designs",
        )
    return pd.DataFrame(a, columns=names)


def design_array(d: pd.DataFrame) -> np.ndarray:
    """The designs of :func:`design_frame` as a contiguous (n, 6) float64 array, every
    value finite: else an :class:`InputError` naming the first bad value's row (its
    position, and its index label where the index is not 0, 1, …) and column."""
    x = np.ascontiguousarray(d.to_numpy(dtype="float64"))
    bad = ~np.isfinite(x)
    if bad.any():
        k, i = (int(v) for v in np.argwhere(bad)[0])
        v = x[k, i]
        shown = "NaN" if v != v else ("inf" if v > 0 else "-inf")
        name = DESIGN_NAMES[i]
        raise InputError(
            f"designs: {_row_name(d.index, k, d.index[k])}, `{name}` = {shown} is not finite", field=name
        )
    return x


def _warn_outside(x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> None:
    """One :class:`GripoptWarning` where designs (rows of ``x``) lie outside the bounds,
    naming each column outside and how many rows: they are evaluated all the same (the
    bounds are the optimiser's search box, not validity), as ``gripopt evaluate`` warns."""
    outside = (x < lower) | (x > upper)
    if not outside.any():
        return
    rows = int(outside.any(axis=1).sum())
    columns = "; ".join(
        f"{name}: {int(outside[:, i].sum())} outside [{lower[i]:g}, {upper[i]:g}]"
        for i, name in enumerate(DESIGN_NAMES)
        if outside[:, i].any()
    )
    hint = " (psi_deg is ψ in degrees)" if outside[:, DESIGN_NAMES.index("psi_deg")].any() else ""
    _warn(
        f"designs: {rows} of {len(x)} row(s) outside the problem's bounds ({columns}){hint}; "
        "evaluating them anyway"
    )


def _one(design: Designs) -> np.ndarray:
    d = design_frame(design)
    if len(d) != 1:
        raise InputError(f"design: {len(d)} designs given, expected one")
    return np.ascontiguousarray(d.to_numpy()[0])


@dataclass(frozen=True)
class Bounds:
    """The design box (optimiser units: l21, b, t22 in m; r, p dimensionless; psi_deg in
    degrees), each bound a Series indexed by design name."""

    lower: pd.Series
    upper: pd.Series
    _native: Any

    def sample(self, n: int, seed: int = 1) -> pd.DataFrame:
        """``n`` designs drawn uniformly in the box from ``seed``'s stream (the designs of
        ``gripopt bench static --seed``)."""
        return pd.DataFrame(self._native.random_designs(n, seed), columns=list(DESIGN_NAMES))

    def to_frame(self) -> pd.DataFrame:
        """The bounds as a two-row DataFrame (``lower``, ``upper``)."""
        return pd.DataFrame({"lower": self.lower, "upper": self.upper}).T


@dataclass(frozen=True)
class Simulation:
    """One design simulated in a scene (diagnostic mode: to stability or t_max).

    Attributes:
        record: the record, as ``gripopt simulate --json`` prints it (a dict).
        trajectory: what ``gripopt simulate --csv`` writes: the grasp samples (finger 1,
            centred and offset scenes), or in the free scene the object's pose and the
            fingers' angles. Units in ``trajectory.attrs["units"]``.
        grasp: the grasp samples (in the free scene, the centred scene's prediction).
    """

    record: dict[str, Any]
    trajectory: pd.DataFrame
    grasp: pd.DataFrame


class Problem:
    """A gripper design problem (a problem file, checked where it is loaded).

    Load one with :meth:`load` (a file) or :meth:`from_toml` (its text). Problems pickle
    (as their TOML text, a robust problem's ``file = "…"`` objects with their cylinders as
    loaded: the object files are not read again), so they travel to Dask workers.
    """

    __slots__ = ("_native",)

    def __init__(self, native: Any) -> None:
        if not isinstance(native, _gripopt.Problem):
            hint = (
                f"; load a file with gripopt.Problem.load({native!r})"
                if isinstance(native, (str, os.PathLike))
                else ""
            )
            raise TypeError(
                "gripopt.Problem(...) wraps a loaded problem: use Problem.load(path) or "
                f"Problem.from_toml(text), not Problem({type(native).__name__}){hint}"
            )
        self._native = native

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Problem":
        """Load and validate a problem file (errors name the file and the field)."""
        return cls(_gripopt.Problem.load(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, path: Optional[Union[str, os.PathLike]] = None) -> "Problem":
        """Parse and validate problem text; ``path``, if given, is the file errors name.

        A robust object given by ``file = "can.toml"`` is read relative to ``path``'s
        folder, or without ``path`` relative to the current working directory (as the
        text would be read from a file there)."""
        return cls(_gripopt.Problem.from_toml(text, None if path is None else os.fspath(path)))

    def __reduce__(self) -> tuple[Any, ...]:
        # the text, and a robust problem's `file = "…"` objects as loaded (inline): an
        # unpickled problem never reads the object files again (another working directory,
        # another machine, or the files edited since give the same problem)
        return (_unpickled, (self.toml, self._native.inlined_toml, self.path))

    def __repr__(self) -> str:
        where = f" from {self.path}" if self.path else ""
        return f"<gripopt.Problem {self.name!r}{where}>"

    @property
    def name(self) -> str:
        """The problem's name."""
        return self._native.name

    @property
    def path(self) -> Optional[Path]:
        """The file it was loaded from (None: given as text)."""
        p = self._native.path
        return None if p is None else Path(p)

    @property
    def toml(self) -> str:
        """The problem's TOML text."""
        return self._native.toml

    @property
    def bounds(self) -> Bounds:
        """The design bounds."""
        n = list(DESIGN_NAMES)
        return Bounds(pd.Series(self._native.lower, index=n), pd.Series(self._native.upper, index=n), self._native)

    @property
    def method(self) -> str:
        """The integration method of its grasp simulations, ``[solver] method``:
        ``"radau5"``, ``"auto"`` (also when the file leaves it out: the default solver, with
        the default's tolerance scaling), ``"trbdf2"`` or ``"dopri5"`` (docs/problem-files.md)."""
        return self._native.method

    @property
    def nominal(self) -> pd.Series:
        """The nominal design (a Series by design name; ψ as psi_deg, degrees)."""
        return pd.Series(self._native.nominal, index=list(DESIGN_NAMES), name="nominal")

    def evaluate(
        self,
        designs: Designs,
        static_only: bool = False,
        threads: Optional[int] = None,
        *,
        first_id: int = 0,
    ) -> pd.DataFrame:
        """Evaluate designs through the staged pipeline, in parallel in Rust (the GIL is
        released), exactly as a run evaluates them.

        Args:
            designs: a DataFrame with the columns l21, b, t22, r, p, psi_deg (others are
                ignored; its index is kept), an (n, 6) array, or one design.
            static_only: stages 0–2 only (kinematics, singularities, statics, form
                closure; tens of µs a design), no grasp simulation: t_stab stays empty.
            threads: worker threads (None: all cores). Results do not depend on it.
            first_id: the id of the first design (the ``id`` column counts on from it).

        Returns:
            One row per design, in order, with the columns and units of a run's
            population.csv (docs/outputs.md; ``df.attrs["units"]``): id, generation (0: not
            from a run), rank (empty: not ranked), feasible, failed_stage, violation,
            reason, the design, derived lengths, form_closed, the four objectives,
            sim_steps, sim_rhs_evals, force_model. Empty values (NaN / <NA>) were not
            computed.
        """
        rows, _, _ = self._evaluate_batch(designs, static_only, threads, first_id)
        return rows

    def _evaluate_batch(
        self,
        designs: Designs,
        static_only: bool = False,
        threads: Optional[int] = None,
        first_id: int = 0,
        warn_outside: bool = True,
    ) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
        """The rows, the minimised objectives (n, 4) and the constrained-domination key
        (n, 2: stages not reached, violation) of ``designs`` (``warn_outside``: warn of
        designs outside the bounds; a Dask chunk does not, its batch did)."""
        static_only = _flag("static_only", static_only)
        d = design_frame(designs)
        x = design_array(d)
        if warn_outside:
            _warn_outside(x, self._native.lower, self._native.upper)
        cols, f, key = self._native.evaluate(x, static_only, threads, first_id)
        return frame(cols, DESIGN_COLUMNS, index=d.index), f, key

    def record(self, design: Optional[Designs] = None, static_only: bool = False) -> dict[str, Any]:
        """The full evaluation record of one design (default: the nominal) as a dict: the
        JSON of ``gripopt evaluate --json`` (docs/outputs.md), values not computed None."""
        static_only = _flag("static_only", static_only)
        x = self._native.nominal if design is None else _one(design)
        _warn_outside(x[None, :], self._native.lower, self._native.upper)
        return self._native.record(x, static_only)

    def simulate(
        self,
        design: Optional[Designs] = None,
        scene: Optional[str] = None,
        rtol: Optional[float] = None,
        method: Optional[str] = None,
        object: Optional[str] = None,
    ) -> Simulation:
        """Simulate one design (default: the nominal) in a scene, as ``gripopt simulate``.

        Args:
            design: one design (a Series or mapping by name, or six values; psi_deg in degrees).
            scene: ``"centred"``, ``"offset:0.002"`` (object offset in metres), ``"free"``
                or ``"free:0.002"``; None: the problem's ``[scene]``.
            rtol: relative tolerance (None: the problem's ``solver.rtol``).
            method: ``"radau5"``, ``"auto"``, ``"trbdf2"`` (alias ``"tr-bdf2"``) or
                ``"dopri5"``, the names ``gripopt simulate --method`` takes; None: the
                problem's ``[solver] method`` (:attr:`method`; absent, the default solver,
                auto with the default's tolerance scaling; a method given here takes the
                tolerances as given).
            object: a robust problem's object by name (its ``[[robust.objects]]``
                ``name``), as ``gripopt simulate --object NAME``: the design on that object
                (its cylinder and grip torque, the spring sized at ``[hand] tau``), in its
                nominal scene; the record then has ``"object": NAME``. None: the reference
                ``[object]`` (on a robust problem with a :class:`GripoptWarning` saying so).

        Raises:
            InputError: the design is discarded before its grasp (stages 0–2), or a bad scene.
        """
        x = self._native.nominal if design is None else _one(design)
        real = (int, float, np.floating, np.integer)
        if rtol is not None and (isinstance(rtol, bool) or not isinstance(rtol, real)):
            raise InputError(f"rtol = {rtol!r}: must be a number (a relative tolerance) or None", field="rtol")
        if object is not None and not isinstance(object, str):
            raise InputError(f"object = {object!r}: must be a robust object's name (a str) or None", field="object")
        objects = self._native.robust_objects
        if object is None and objects:
            _warn(
                f"{self.path or self.name}: the problem has [robust]: simulate() simulates the reference [object] "
                f"only, not the robust objects or scenarios; object=NAME simulates the design on one of its "
                f"objects ({', '.join(objects)})"
            )
        _warn_outside(x[None, :], self._native.lower, self._native.upper)
        record, samples, poses = self._native.simulate(x, scene, None if rtol is None else float(rtol), method, object)
        grasp = frame(samples, SAMPLE_COLUMNS)
        trajectory = frame(poses, POSE_COLUMNS) if record.get("scene") == "free" else grasp
        return Simulation(record, trajectory, grasp)


def _unpickled(text: str, inlined: Optional[str], path: Optional[Path]) -> Problem:
    """The problem a pickle carried (:meth:`Problem.__reduce__`)."""
    return Problem(_gripopt.Problem.unpickled(text, inlined, None if path is None else os.fspath(path)))
