"""gripopt's evaluation spread over a Dask cluster (dask.distributed).

A batch of designs is cut into chunks; each chunk is one task that evaluates its designs
on a worker with :meth:`gripopt.Problem.evaluate` (in Rust, on all the worker's cores, the
GIL released); the chunks come back in order, so the result is the local evaluation's,
bit for bit: each design's evaluation is a deterministic function of the design alone.
The problem travels to the workers as its TOML text (problems pickle).

The same code runs on a laptop (``LocalCluster``) and on a batch system through
dask-jobqueue (``SLURMCluster``, ``PBSCluster``, …): see docs/python.md. On a worker, give
each task all the cores (``threads=None``, the default): concurrent tasks of one worker
share gripopt's one thread pool.
"""

from __future__ import annotations

import operator
import os
from typing import Any, Optional, Union

import numpy as np
import pandas as pd

from .errors import InputError
from .problem import Designs, Problem, _warn_outside, design_array, design_frame


def _chunk(
    problem: Problem, x: np.ndarray, static_only: bool, threads: Optional[int], first_id: int
) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """One task: the rows, minimised objectives and domination keys of a chunk."""
    return problem._evaluate_batch(x, static_only, threads, first_id, warn_outside=False)


def _chunk_size(n: Any) -> int:
    """``chunk_size`` as an int ≥ 1 (an int or a NumPy integer, not a bool), else an InputError."""
    try:
        k = operator.index(n)
    except TypeError:
        k = 0
    if isinstance(n, bool) or k < 1:
        raise InputError(f"chunk_size = {n!r}: must be an int of at least 1", field="chunk_size")
    return k


def _problem(problem: Any) -> Problem:
    """``problem`` as a :class:`Problem`: a problem file's path is loaded (as
    :func:`gripopt.optimise` takes it); anything else is a TypeError."""
    if isinstance(problem, Problem):
        return problem
    if isinstance(problem, (str, os.PathLike)):
        return Problem.load(problem)
    raise TypeError(
        f"problem: a gripopt.Problem or a problem file's path, not a {type(problem).__name__} "
        "(load one with gripopt.Problem.load(path))"
    )


def evaluate_batch(
    client: Any,
    problem: Union[Problem, str, os.PathLike],
    designs: Designs,
    *,
    static_only: bool = False,
    chunk_size: int = 1000,
    threads: Optional[int] = None,
    first_id: int = 0,
) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """:func:`evaluate` with the minimised objectives (n, 4) and gripopt's constrained
    domination key (n, 2) as well (what :class:`gripopt.pymoo.GripperProblem` needs).

    Args:
        client: the Dask client.
        problem: the problem, or a problem file's path (loaded here).
        designs: as for :meth:`gripopt.Problem.evaluate` (a DataFrame with the six design
            columns, whose index is kept, or an (n, 6) array).
        static_only: stages 0–2 only.
        chunk_size: designs per task (a few seconds of work each is a good size: ~1 000
            designs with the grasp simulation, ~100 000 static only).
        threads: threads per task (None: all the worker's cores).
        first_id: the first design's id.
    """
    problem = _problem(problem)
    d = design_frame(designs)
    # the whole batch checked here, before any work is sent: every value finite (an error
    # names the row in the batch, as Problem.evaluate does), then threads and first_id (an
    # empty batch evaluated locally)
    x = design_array(d)
    chunk_size = _chunk_size(chunk_size)
    problem._evaluate_batch(x[:0], static_only, threads, first_id)
    _warn_outside(x, problem._native.lower, problem._native.upper)
    last = np.iinfo(np.int64).max
    if len(x) and operator.index(first_id) + len(x) - 1 > last:
        rule = f"the last of {len(x)} designs would have an id beyond {last} (int64)"
        raise InputError(f"first_id = {first_id}: {rule}", field="first_id")
    starts = range(0, len(x), chunk_size)
    futures = [
        client.submit(_chunk, problem, x[a : a + chunk_size], static_only, threads, first_id + a, pure=False)
        for a in starts
    ]
    parts = client.gather(futures)
    if not parts:
        return problem._evaluate_batch(x, static_only, threads, first_id, warn_outside=False)
    rows = pd.concat([p[0] for p in parts], ignore_index=True)
    rows.index = d.index
    rows.attrs = parts[0][0].attrs
    f = np.concatenate([p[1] for p in parts])
    key = np.concatenate([p[2] for p in parts])
    return rows, f, key


def evaluate(
    client: Any, problem: Union[Problem, str, os.PathLike], designs: Designs, **options: Any
) -> pd.DataFrame:
    """Evaluate ``designs`` on the cluster of ``client`` (a ``dask.distributed.Client``):
    the DataFrame :meth:`gripopt.Problem.evaluate` would give, identical to it. The
    arguments and the keyword options (``static_only``, ``chunk_size``, ``threads``,
    ``first_id``) are :func:`evaluate_batch`'s.
    """
    rows, _, _ = evaluate_batch(client, problem, designs, **options)
    return rows
