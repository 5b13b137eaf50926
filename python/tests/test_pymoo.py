"""gripopt.pymoo.GripperProblem: pymoo algorithms run on gripopt's evaluation, and the
constraint encoding orders designs as gripopt's constraint domination does."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.algorithms.moo.nsga3 import NSGA3
from pymoo.optimize import minimize
from pymoo.util.ref_dirs import get_reference_directions

import gripopt
from gripopt.pymoo import GripperProblem, constraint_violation, natural_objectives


def gripopt_key(s: float, v: float) -> tuple[float, float]:
    """gripopt's order of infeasibility (optim::Infeasibility::cmp_key): stages not
    reached, then violation; smaller is better."""
    return (s, v)


def test_the_encoding_is_gripopts_constraint_domination():
    rng = np.random.default_rng(1)
    stages = rng.integers(0, 5, 400).astype(float)
    viol = np.where(stages > 0, np.concatenate([rng.exponential(1.0, 200), 10.0 ** rng.uniform(-9, 6, 200)]), 0.0)
    key = np.column_stack([stages, viol])
    g = constraint_violation(key)
    assert np.all((g <= 0) == (stages == 0))  # feasible ⇔ CV = 0
    for i, j in itertools.combinations(range(len(g)), 2):
        a, b = gripopt_key(*key[i]), gripopt_key(*key[j])
        if a < b:
            assert g[i] < g[j], (key[i], key[j])
        elif a > b:
            assert g[i] > g[j], (key[i], key[j])
    # a later failed stage beats an earlier one whatever the violations
    assert constraint_violation(np.array([[1.0, 1e300], [2.0, 0.0]]))[0] < constraint_violation(np.array([[2.0, 0.0]]))[0]


def test_the_batch_key_matches_the_rows(problem):
    x = np.vstack([problem.bounds.sample(40, seed=3).to_numpy(), problem.nominal.to_numpy()])
    rows, f, key = problem._evaluate_batch(x)
    feasible = rows["feasible"].to_numpy()
    assert np.array_equal(key[:, 0] == 0, feasible)
    failed = rows["failed_stage"].to_numpy(dtype="float64", na_value=np.nan)
    assert np.array_equal(key[~feasible, 0], 4 - failed[~feasible])
    assert np.array_equal(key[~feasible, 1], rows["violation"].to_numpy()[~feasible])
    nat = natural_objectives(f[feasible])
    for col in ["alpha", "mean_force", "t_stab"]:
        assert np.array_equal(nat[col].to_numpy(), rows.loc[feasible, col].to_numpy())
    # max_offset: a design not form closed at the centred object is ranked with −Δ_off
    # (MODEL.md §6.7), a placeholder: natural_objectives and its row leave max_offset empty
    closed = rows.loc[feasible, "form_closed"].to_numpy(dtype=bool)
    assert np.array_equal(nat["max_offset"].to_numpy()[closed], rows.loc[feasible, "max_offset"].to_numpy()[closed])
    assert (f[feasible][~closed, 0] > 0).all()  # −(−Δ_off): how the optimiser ranks it
    assert nat["max_offset"][~closed].isna().all() and rows.loc[feasible, "max_offset"][~closed].isna().all()
    assert (~closed).any() and closed.any()
    assert np.isfinite(f).all()


def test_nsga2_runs_on_gripopts_evaluation(problem):
    gp = GripperProblem(problem)
    res = minimize(gp, NSGA2(pop_size=16), ("n_gen", 4), seed=1, verbose=False)
    assert res.algorithm.evaluator.n_eval == 64
    assert res.F is not None and res.F.shape[1] == 4 and (res.CV <= 0).all()
    # the front's designs evaluate (again, in gripopt) to feasible designs with those objectives
    again = problem.evaluate(res.X)
    assert again["feasible"].all()
    assert np.array_equal(natural_objectives(res.F)["mean_force"].to_numpy(), again["mean_force"].to_numpy())
    assert gp.last_rows is not None and len(gp.last_rows) == 16


def test_another_algorithm_nsga3(problem):
    ref = get_reference_directions("das-dennis", 4, n_partitions=2)
    res = minimize(GripperProblem(problem), NSGA3(ref_dirs=ref, pop_size=12), ("n_gen", 3), seed=2, verbose=False)
    assert res.pop is not None and len(res.pop) == 12


def test_natural_objectives_leave_the_offset_placeholder_empty(problem):
    """Origin: issue 44 class 8: natural_objectives showed the −Δ_off placeholder (−0.25 mm)
    of a feasible design not form closed, which every other output leaves empty. Such a
    design's max_offset is NaN, as its row's is; the other objectives are its row's."""
    x = problem.bounds.sample(400, seed=3)
    rows, F, _ = problem._evaluate_batch(x, static_only=True, warn_outside=False)
    not_closed = rows["feasible"].astype(bool) & ~rows["form_closed"].fillna(True).astype(bool)
    assert not_closed.any(), "the sample has a feasible design not form closed"
    nat = natural_objectives(F)
    step = float(problem.toml.split("offset_step")[1].split("=")[1].split()[0])
    assert np.allclose(F[not_closed.to_numpy(), 0], step)  # its rank: the placeholder
    assert nat["max_offset"][not_closed.to_numpy()].isna().all()
    feasible = rows["feasible"].astype(bool).to_numpy()
    np.testing.assert_array_equal(nat["max_offset"][feasible].to_numpy(), rows["max_offset"][feasible].to_numpy())
    np.testing.assert_array_equal(nat["alpha"][feasible].to_numpy(), rows["alpha"][feasible].to_numpy())
