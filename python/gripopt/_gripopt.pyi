"""Type stubs of gripopt's native module (crates/gripopt-py, PyO3). Use the package's
Python classes (gripopt.Problem, gripopt.Run, …): these are what they are built on.

A table is handed over as a list of columns ``(name, kind, values, missing)``: kind
``"f64"`` (a float64 array, NaN where missing), ``"i64"`` / ``"bool"`` (an int64 / bool
array; ``missing``, a bool array, when the field is optional, else None) or ``"str"`` (a
list of str or None).

Whole-number arguments (seed, threads, pop, generations, first_id, n, id) take an int or a
NumPy integer; anything else, a bool, or a value out of range is gripopt.errors.InputError
naming the argument (crates/gripopt-py/src/args.rs).
"""

from typing import Any, Callable, Optional, Union

import numpy as np
import numpy.typing as npt

Column = tuple[str, str, Union[npt.NDArray[Any], list[Optional[str]]], Optional[npt.NDArray[np.bool_]]]
ColumnInfo = tuple[str, str, str]

__version__: str
DESIGN_NAMES: list[str]
DESIGN_COLUMNS: list[ColumnInfo]
HISTORY_COLUMNS: list[ColumnInfo]
SAMPLE_COLUMNS: list[ColumnInfo]
# finger 2's own trajectory columns, after SAMPLE_COLUMNS in the offset scene (docs/outputs.md)
FINGER2_COLUMNS: list[ColumnInfo]
POSE_COLUMNS: list[ColumnInfo]
# a robust problem's design-table columns, then each object's `NAME.column` (docs/robust.md)
ROBUST_COLUMNS: list[ColumnInfo]
OBJECT_COLUMNS: list[ColumnInfo]

class Problem:
    """A loaded, validated problem file."""

    @staticmethod
    def load(path: str) -> Problem: ...
    @staticmethod
    def from_toml(text: str, path: Optional[str] = None) -> Problem: ...
    @staticmethod
    def unpickled(text: str, inlined: Optional[str], path: Optional[str] = None) -> Problem:
        """The problem a pickle carried (``inlined``: the text with `file =` objects inline)."""
    @property
    def inlined_toml(self) -> Optional[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> Optional[str]: ...
    @property
    def toml(self) -> str: ...
    @property
    def lower(self) -> npt.NDArray[np.float64]: ...
    @property
    def upper(self) -> npt.NDArray[np.float64]: ...
    @property
    def method(self) -> str: ...
    @property
    def robust_objects(self) -> Optional[list[str]]: ...
    @property
    def nominal(self) -> npt.NDArray[np.float64]: ...
    def evaluate(
        self,
        designs: npt.NDArray[np.float64],
        static_only: bool = False,
        threads: Optional[int] = None,
        first_id: int = 0,
    ) -> tuple[list[Column], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Rows as columns, minimised objectives (n, 4), domination key (n, 2)."""
    def record(self, design: npt.NDArray[np.float64], static_only: bool = False) -> str:
        """The record's JSON text (`gripopt evaluate --json`)."""
    def simulate(
        self,
        design: npt.NDArray[np.float64],
        scene: Optional[str] = None,
        rtol: Optional[float] = None,
        method: Optional[str] = None,
        object: Optional[str] = None,
    ) -> tuple[str, list[Column], list[Column]]:
        """The record's JSON text, the grasp samples, the free scene's poses."""
    def random_designs(self, n: int, seed: int) -> npt.NDArray[np.float64]: ...

class RunFolder:
    """A run folder, read through the library, pinned to the run it held when opened."""

    def __init__(self, path: str) -> None: ...
    @property
    def path(self) -> str: ...
    def info(self) -> str: ...
    def problem(self) -> Problem: ...
    def state(self) -> str: ...
    def table(self, name: str) -> list[Column]: ...
    def design(self, id: int) -> tuple[str, list[Column], str, str]: ...
    def replay(self, id: int) -> dict[str, Any]: ...

def optimise(
    problem: Problem,
    out: str,
    pop: int = 100,
    generations: int = 50,
    seed: int = 1,
    threads: Optional[int] = None,
    record: Optional[str] = None,
    progress: Optional[Callable[[dict[str, Any]], Any]] = None,
) -> dict[str, Any]: ...
def resume(
    path: str,
    generations: Optional[int] = None,
    threads: Optional[int] = None,
    force: bool = False,
    progress: Optional[Callable[[dict[str, Any]], Any]] = None,
) -> dict[str, Any]: ...
