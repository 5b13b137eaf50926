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

import inspect
from typing import Any, Optional

import numpy as np
import pandas as pd
from pymoo.core.problem import Problem as _PymooProblem

from . import _gripopt
from .errors import InputError
from .problem import Problem

#: The objectives as the library's table has them: (name, unit, meaning, sense), in ``F``'s
#: order; sense is ``"maximise"`` or ``"minimise"``.
_TABLE: tuple[tuple[str, str, str, str], ...] = tuple(_gripopt.OBJECTIVES)

#: The objectives' names in ``F``'s order (minimisation form: a maximised one negated).
OBJECTIVES: tuple[str, ...] = tuple(("-" if sense == "maximise" else "") + name for name, _, _, sense in _TABLE)


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
    form closed at the centred object is ranked by max_offset = −Δ_off
    (``criteria.offset_step``, MODEL.md §6.7), a placeholder, not a value: its max_offset
    is NaN here, as every other output leaves it empty (a real max_offset is ≥ 0)."""
    try:
        F = np.asarray(F, dtype="float64")
    except (TypeError, ValueError) as e:
        raise InputError(f"F: not an array of numbers ({e})", field="F") from None
    if F.ndim == 1 and F.shape[0] == len(OBJECTIVES):
        F = F[None, :]  # one design
    if F.ndim != 2 or F.shape[1] != len(OBJECTIVES):
        raise InputError(
            f"F: an array of shape {F.shape}, expected (n, 4) or (4,): {', '.join(OBJECTIVES)}", field="F"
        )
    natural = {
        name: (-F[:, k] if sense == "maximise" else F[:, k]) for k, (name, _, _, sense) in enumerate(_TABLE)
    }
    # the −Δ_off placeholder of a design not form closed is no offset (Objectives::reported)
    natural["max_offset"] = np.where(natural["max_offset"] >= 0, natural["max_offset"], np.nan)
    return pd.DataFrame(natural)


#: What GripperProblem sets in pymoo's ``Problem`` itself.
_SET_HERE = ("n_var", "n_obj", "n_ieq_constr", "n_eq_constr", "xl", "xu", "vtype", "vars", "elementwise")


def _pymoo_options() -> list[str]:
    """The keyword options pymoo's ``Problem`` names (not its ``**kwargs``), less those
    :class:`GripperProblem` sets."""
    params = inspect.signature(_PymooProblem.__init__).parameters.values()
    named = [p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name != "self"]
    return [n for n in named if n not in _SET_HERE]


def _check_options(problem: Any, threads: Any, client: Any, chunk_size: Any, kwargs: dict[str, Any]) -> None:
    """GripperProblem's arguments, checked before pymoo keeps them: an InputError names
    the first one at fault."""
    if not isinstance(problem, Problem):
        raise InputError(f"problem = {problem!r}: must be a gripopt.Problem", field="problem")
    allowed = _pymoo_options()
    for name in kwargs:
        if name not in allowed:
            why = (
                "set by GripperProblem from the gripopt problem"
                if name in _SET_HERE
                else "not an option of GripperProblem (problem, threads, client, chunk_size; it evaluates all "
                "four stages) nor of pymoo's Problem"
            )
            raise InputError(f"{name} = {kwargs[name]!r}: {why} (pymoo's: {', '.join(allowed)})", field=name)
    # threads: checked as Problem.evaluate checks it (an empty batch)
    problem._evaluate_batch(np.empty((0, 6)), threads=threads)
    from .dask import _chunk_size

    _chunk_size(chunk_size)
    if client is not None and not (callable(getattr(client, "submit", None)) and callable(getattr(client, "gather", None))):
        raise InputError(f"client = {client!r}: must be a dask.distributed Client, or None", field="client")


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
        **kwargs: pymoo ``Problem``'s own options (e.g. ``callback``,
            ``replace_nan_values_by``); any other keyword, or one this class sets itself
            (``n_var``, ``xl``, …), is an :class:`gripopt.InputError` naming it (pymoo would
            keep it silently). The evaluation always runs all four stages.

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
        _check_options(problem, threads, client, chunk_size, kwargs)
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
