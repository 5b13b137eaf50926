"""gripopt's evaluation as a pymoo problem, so that any pymoo algorithm runs on it.

:class:`GripperProblem` is a vectorised pymoo ``Problem``: six variables in the problem's
bounds (l21, b, t22 in m; r, p; psi_deg in degrees), four objectives in minimisation form
and one inequality constraint that encodes gripopt's constraint domination.

Objectives (``F``), as gripopt's own NSGA-II ranks them (MODEL.md §10)::

    F = (−max_offset [m], alpha [-], −mean_force [N], t_stab [s])

where a value was not computed (an infeasible design), the finite placeholder gripopt
uses; pymoo's survival and tournaments compare infeasible designs by their constraint
violation only, never by these.

Constraint (``G``, one column; pymoo's ``CV`` = max(0, G)): gripopt's constraint
domination (MODEL.md §10) says a feasible design beats an infeasible one, an infeasible
design that failed at a later stage beats one that failed earlier, and between two that
failed at the same stage the smaller violation wins. pymoo compares infeasible designs by
the single number ``CV``, so the pair (stages not reached, violation) is encoded as::

    G = 0                                  feasible
    G = s + ½·v/(1 + v)                    infeasible: s = 4 − failed_stage ∈ {1, …, 4},
                                           v ≥ 0 the violation at that stage (its units)

``s`` is an integer and ½·v/(1 + v) ∈ [0, ½), so a later failed stage always has the
smaller ``G`` whatever the violations (the stage bands never overlap), and within a stage
``G`` grows with ``v`` (strictly, to double precision: two violations closer than ~1e-16·s
in ½·v/(1 + v) tie). Every comparison pymoo makes on ``CV`` is then gripopt's comparison.
See :func:`constraint_violation`.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem as _PymooProblem

from .problem import Problem

#: The objectives' names in ``F``'s order (minimisation form).
OBJECTIVES: tuple[str, ...] = ("-max_offset", "alpha", "-mean_force", "t_stab")


def constraint_violation(key: np.ndarray) -> np.ndarray:
    """``G`` of designs from gripopt's constrained-domination key, an (n, 2) array of
    (stages not reached, violation): 0 when feasible (no stage short), else
    ``s + ½·v/(1 + v)`` (see the module's documentation)."""
    key = np.asarray(key, dtype="float64")
    s, v = key[:, 0], key[:, 1]
    return np.where(s > 0, s + 0.5 * (v / (1.0 + v)), 0.0)


def natural_objectives(F: np.ndarray) -> pd.DataFrame:
    """``F`` (minimisation form) back in the objectives' natural sense and units:
    max_offset [m], alpha [-], mean_force [N], t_stab [s]. A feasible design that is not
    form closed at the centred object has max_offset = −Δ_off (``criteria.offset_step``),
    the value gripopt ranks it by (MODEL.md §6.7); its row leaves max_offset empty."""
    F = np.asarray(F, dtype="float64")
    return pd.DataFrame(
        {"max_offset": -F[:, 0], "alpha": F[:, 1], "mean_force": -F[:, 2], "t_stab": F[:, 3]}
    )


class GripperProblem(_PymooProblem):
    """gripopt's gripper problem for pymoo: each batch of designs is evaluated in Rust, in
    parallel, exactly as gripopt's own optimiser evaluates a generation (all four stages).

    Args:
        problem: the :class:`gripopt.Problem`.
        threads: worker threads per batch, or with a client per Dask task (None: all the
            machine's or the worker's cores).
        client: a ``dask.distributed.Client``: batches are split into chunks of
            ``chunk_size`` designs and evaluated on the cluster (:mod:`gripopt.dask`);
            results are identical to a local evaluation.
        chunk_size: designs per Dask task.
        **kwargs: passed to pymoo's ``Problem``.

    After each evaluation, :attr:`last_rows` holds the batch's rows (a run's
    population.csv columns) for inspection.
    """

    def __init__(
        self,
        problem: Problem,
        threads: Optional[int] = None,
        client: Any = None,
        chunk_size: int = 64,
        **kwargs: Any,
    ) -> None:
        b = problem.bounds
        super().__init__(
            n_var=6,
            n_obj=4,
            n_ieq_constr=1,
            xl=b.lower.to_numpy(),
            xu=b.upper.to_numpy(),
            vtype=float,
            **kwargs,
        )
        self.problem = problem
        self.threads = threads
        self.client = client
        self.chunk_size = chunk_size
        self.last_rows: Optional[pd.DataFrame] = None

    def _evaluate(self, x: np.ndarray, out: dict[str, Any], *args: Any, **kwargs: Any) -> None:
        if self.client is not None:
            from .dask import evaluate_batch

            rows, f, key = evaluate_batch(self.client, self.problem, x, chunk_size=self.chunk_size, threads=self.threads)
        else:
            rows, f, key = self.problem._evaluate_batch(x, threads=self.threads)
        self.last_rows = rows
        out["F"] = f
        out["G"] = constraint_violation(key)[:, None]
