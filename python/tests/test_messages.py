"""Hostile pass 36: what the package says about bad input and where — designs outside the
bounds warned of at the caller's line, the field of a problem file's TOML error, bad
arguments named, duplicated or complex design columns refused, run notes at the caller's
line, gripopt.dask taking a path, summary["out"] one type."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import gripopt
import gripopt.dask
from conftest import BOTTLE, REPO


def test_designs_outside_the_bounds_warn_once_naming_the_columns(problem):
    x = problem.bounds.sample(5, seed=1)
    x.loc[[1, 3], "psi_deg"] = np.radians(129.76)  # ψ given in radians
    x.loc[3, "r"] = 100.0
    with pytest.warns(gripopt.GripoptWarning) as w:
        rows = problem.evaluate(x, static_only=True)
    assert len(w) == 1 and w[0].filename == __file__
    m = str(w[0].message)
    assert "2 of 5 row(s) outside the problem's bounds" in m and "psi_deg: 2 outside [90, 160]" in m
    assert re.search(r"\br: 1 outside", m) and "l21" not in m and "degrees" in m
    assert len(rows) == 5  # evaluated all the same, as the CLI does
    one = problem.nominal.copy()
    one["psi_deg"] = 2.26
    for call in (lambda: problem.record(one, static_only=True), lambda: problem.simulate(one)):
        with pytest.warns(gripopt.GripoptWarning, match=r"1 of 1 row\(s\).*psi_deg") as w:
            try:
                call()
            except gripopt.InputError:
                pass  # discarded before its grasp: the warning came first
        assert len(w) == 1 and w[0].filename == __file__
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        problem.evaluate(problem.bounds.sample(50, seed=2), static_only=True)


TOML_ERRORS = [
    (lambda t: t.replace("[hand]\n", "[hand]\nfoo = 1\n", 1), "hand.foo", "unknown field `foo`"),
    (lambda t: re.sub(r"(?m)^tau\s*=.*\n", "", t, count=1), "hand.tau", "missing field `tau`"),
    (lambda t: re.sub(r"(?m)^tau\s*=.*$", 'tau = "x"', t, count=1), "hand.tau", "invalid type"),
    (lambda t: t + "\n[bogus]\na = 1\n", "bogus", "unknown field `bogus`"),
]


@pytest.mark.parametrize("edit, field, says", TOML_ERRORS)
def test_a_toml_error_names_its_field(tmp_path, edit, field, says):
    text = edit(BOTTLE.read_text())
    with pytest.raises(gripopt.ProblemError, match=says) as e:
        gripopt.Problem.from_toml(text)
    assert e.value.field == field
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(gripopt.ProblemError, match=says) as e:
        gripopt.Problem.load(path)
    assert (e.value.field, e.value.path) == (field, str(path))


def test_a_toml_error_in_a_robust_object_names_its_index():
    text = (REPO / "problems" / "kitchen.toml").read_text()
    i = text.index("density", text.index('name = "bottle-half"'))
    bad = text[:i] + 'density = "heavy"\n#' + text[i:]
    with pytest.raises(gripopt.ProblemError, match="invalid type") as e:
        gripopt.Problem.from_toml(bad, REPO / "problems" / "kitchen.toml")
    assert e.value.field == "robust.objects[1].density"
    with pytest.raises(gripopt.ProblemError) as e:
        gripopt.Problem.from_toml("[[[")  # not TOML: no field
    assert e.value.field is None


def test_bad_arguments_are_input_errors_naming_them(problem):
    with pytest.raises(gripopt.InputError, match=r"^rtol = 2") as e:
        problem.simulate(rtol=2.0)
    assert type(e.value) is gripopt.InputError and e.value.field == "rtol"
    with pytest.raises(gripopt.InputError, match=r"^rtol = 'tight'") as e:
        problem.simulate(rtol="tight")
    assert e.value.field == "rtol"
    for call in (
        lambda: problem.evaluate(problem.nominal, static_only="no"),
        lambda: problem.record(static_only="no"),
    ):
        with pytest.raises(gripopt.InputError, match=r"^static_only = 'no': must be True or False") as e:
            call()
        assert e.value.field == "static_only"


def test_duplicated_and_complex_design_columns_are_refused(problem):
    x = problem.bounds.sample(3, seed=1)
    twice = pd.concat([x, x[["l21"]]], axis=1)
    with pytest.raises(gripopt.InputError, match=r"column\(s\) l21 given more than once") as e:
        problem.evaluate(twice, static_only=True)
    assert e.value.field == "l21"
    with pytest.raises(gripopt.InputError, match="complex") as e:
        problem.evaluate(x.to_numpy() + 0j, static_only=True)
    assert e.value.field == "designs"
    c = x.copy()
    c["b"] = c["b"] + 1e-3j
    with pytest.raises(gripopt.InputError, match="complex") as e:
        problem.evaluate(c, static_only=True)
    assert e.value.field == "b"
    with pytest.raises(gripopt.InputError, match="complex"):
        problem.record(problem.nominal.to_numpy() + 0j)


def test_a_runs_notes_are_warnings_at_the_callers_line(tmp_path):
    with pytest.warns(gripopt.GripoptWarning, match="designs per thread") as w:
        run = gripopt.optimise(BOTTLE, tmp_path / "run", pop=4, generations=1, threads=2, record=False)
    assert w[0].filename == __file__, [(x.filename, x.lineno) for x in w]
    assert run.summary["generations"] == 1


def test_summary_out_is_a_path_from_the_call_and_from_the_folder(tmp_path):
    run = gripopt.optimise(BOTTLE, tmp_path / "run", pop=4, generations=1, threads=1, record=False)
    assert isinstance(run.summary["out"], Path)
    again = gripopt.Run(tmp_path / "run").summary
    assert isinstance(again["out"], Path) and again["out"] == run.summary["out"]


def test_dask_takes_a_problem_file_or_says_what_it_needs(problem):
    class NoCluster:  # an empty batch sends no task
        def submit(self, *a, **k):
            raise AssertionError("no task for an empty batch")

        def gather(self, futures):
            assert futures == []
            return []

    empty = problem.bounds.sample(0, seed=1)
    rows = gripopt.dask.evaluate(NoCluster(), str(BOTTLE), empty, static_only=True)
    assert list(rows.columns) == list(problem.evaluate(empty, static_only=True).columns)
    rows = gripopt.dask.evaluate(NoCluster(), BOTTLE, empty, static_only=True)
    with pytest.raises(TypeError, match=r"Problem\.load"):
        gripopt.dask.evaluate(NoCluster(), 42, empty)
