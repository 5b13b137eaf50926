"""Type stubs of gripopt's native module (crates/gripopt-py, PyO3). Use the package's
Python classes (gripopt.Problem, gripopt.Run, …): these are what they are built on.

A table is handed over as a list of columns ``(name, kind, values, missing)``: kind
``"f64"`` (a float64 array, NaN where missing), ``"i64"`` / ``"bool"`` (an int64 / bool
array; ``missing``, a bool array, when the field is optional, else None) or ``"str"`` (a
list of str or None).

Whole-number arguments (seed, threads, pop, generations, first_id, n, id) take an int or a
NumPy integer; anything else, a bool, or a value out of range is gripopt.errors.InputError
naming the argument (crates/gripopt-py/src/args.rs).

Records cross as Python objects (dicts, lists, numbers, str, None: a value not computed, as
the CLI's JSON has it). A recorded design's record follows the JSON schema the library
publishes for `/designs` (``DESIGN_SCHEMA``): ``DesignRecord`` lists its keys
(python/tests/test_api.py checks them against the schema).
"""

from typing import Any, Callable, Optional, TypedDict, Union

from typing_extensions import NotRequired

import numpy as np
import numpy.typing as npt

Column = tuple[str, str, Union[npt.NDArray[Any], list[Optional[str]]], Optional[npt.NDArray[np.bool_]]]
ColumnInfo = tuple[str, str, str]
#: An objective: name, unit, meaning, sense ("maximise" or "minimise").
ObjectiveInfo = tuple[str, str, str, str]

class Window(TypedDict):
    sec: int
    nsec: int

class Objectives(TypedDict):
    """The four objectives (``OBJECTIVES``' names), None where not computed."""

    max_offset: Optional[float]
    alpha: Optional[float]
    mean_force: Optional[float]
    t_stab: Optional[float]

class DesignRecord(TypedDict):
    """A recorded design's `/designs` message (``DESIGN_SCHEMA``): the schema's required keys
    always hold a value; the others are None where not computed (``robust``: absent outside
    a robust run; ``shown_scenario``: absent unless the design's window draws the scenario
    that decided its verdict, docs/recording.md)."""

    id: int
    generation: int
    problem: str
    window_start: Window
    window_start_s: float
    epoch_s: int
    parameters: dict[str, float]
    derived: dict[str, Optional[float]]
    stages_passed: int
    feasible: bool
    form_closed: Optional[bool]
    failed_stage: Optional[int]
    reason: Optional[str]
    violation: Optional[float]
    objectives: Objectives
    stage_seconds: dict[str, float]
    sim_steps: Optional[int]
    sim_rhs_evals: Optional[int]
    free_scene: Optional[dict[str, Any]]
    robust: NotRequired[dict[str, Any]]
    shown_scenario: NotRequired[dict[str, Any]]
    trajectory_samples: int

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
# the four objectives, in the order of the minimised objectives of Problem.evaluate
OBJECTIVES: list[ObjectiveInfo]
# the JSON schema of `/designs` (DesignRecord)
DESIGN_SCHEMA: dict[str, Any]

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
    def record(self, design: npt.NDArray[np.float64], static_only: bool = False) -> dict[str, Any]:
        """The record (`gripopt evaluate --json`)."""
    def simulate(
        self,
        design: npt.NDArray[np.float64],
        scene: Optional[str] = None,
        rtol: Optional[float] = None,
        method: Optional[str] = None,
        object: Optional[str] = None,
    ) -> tuple[dict[str, Any], list[Column], list[Column]]:
        """The record (`gripopt simulate --json`), the grasp samples, the free scene's poses."""
    def random_designs(self, n: int, seed: int) -> npt.NDArray[np.float64]: ...

class RunFolder:
    """A run folder, read through the library, pinned to the run it held when opened."""

    def __init__(self, path: str) -> None: ...
    @property
    def path(self) -> str: ...
    def info(self) -> dict[str, Any]: ...
    def problem(self) -> Problem: ...
    def state(self) -> str: ...
    def table(self, name: str) -> list[Column]: ...
    def design(self, id: int) -> tuple[DesignRecord, list[Column], str, str]: ...
    def replay(self, id: int) -> dict[str, Any]: ...

def optimise(
    problem: Problem,
    out: str,
    pop: int = 100,
    generations: int = 50,
    seed: int = 1,
    threads: Optional[int] = None,
    record: Union[bool, dict[str, Any], None] = None,
    progress: Optional[Callable[[dict[str, Any]], Any]] = None,
) -> dict[str, Any]: ...
def resume(
    path: str,
    generations: Optional[int] = None,
    threads: Optional[int] = None,
    force: bool = False,
    progress: Optional[Callable[[dict[str, Any]], Any]] = None,
) -> dict[str, Any]: ...
