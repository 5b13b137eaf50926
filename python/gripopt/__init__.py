"""gripopt for Python: the Rust library's face with pandas outputs.

Load a problem, evaluate designs into DataFrames with the columns and units of a run's
population.csv, simulate a design in a scene, run or resume gripopt's NSGA-II, read a
run folder back (tables, recorded grasps, replays), hand gripopt's evaluation to pymoo
(:mod:`gripopt.pymoo`) or spread it over a Dask cluster (:mod:`gripopt.dask`).

>>> import gripopt
>>> p = gripopt.Problem.load("problems/bottle-1l.toml")
>>> df = p.evaluate(p.bounds.sample(1000, seed=1), static_only=True)

Units: lengths in m, ψ as ``psi_deg`` in degrees, forces in N, times in s; every table
says so in ``df.attrs["units"]`` (docs/outputs.md, docs/python.md).
"""

from ._frames import DESIGN_COLUMNS, DESIGN_NAMES, FINGER2_COLUMNS, HISTORY_COLUMNS, POSE_COLUMNS, SAMPLE_COLUMNS
from ._gripopt import __version__
from .errors import (
    GripoptError,
    GripoptWarning,
    InputError,
    ProblemError,
    RecordingError,
    RunFolderError,
    RunLockedError,
    RunStoppedError,
)
from .problem import Bounds, Problem, Simulation
from .run import GenerationReport, RecordedDesign, Replay, Run, optimise, resume

__all__ = [
    "Bounds",
    "DESIGN_COLUMNS",
    "DESIGN_NAMES",
    "FINGER2_COLUMNS",
    "GenerationReport",
    "GripoptError",
    "GripoptWarning",
    "HISTORY_COLUMNS",
    "InputError",
    "POSE_COLUMNS",
    "Problem",
    "ProblemError",
    "RecordedDesign",
    "RecordingError",
    "Replay",
    "Run",
    "RunFolderError",
    "RunLockedError",
    "RunStoppedError",
    "SAMPLE_COLUMNS",
    "Simulation",
    "__version__",
    "optimise",
    "resume",
]
