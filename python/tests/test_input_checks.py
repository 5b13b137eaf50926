"""Designs and options that are not what a function takes: an InputError naming the
argument, the column and the row (by position, and by index label where the index is not
0, 1, …), raised before any work is sent anywhere."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest

import gripopt
import gripopt.dask


class RecordingClient:
    """A stand-in for a Dask client that records what is sent to it."""

    def __init__(self) -> None:
        self.submitted: list = []

    def submit(self, *args, **kwargs):
        self.submitted.append(args)
        return len(self.submitted) - 1

    def gather(self, futures):
        raise AssertionError("nothing should be gathered")


def batch_with_nan(problem, n=40, at=30, column="t22"):
    x = pd.DataFrame(np.tile(problem.nominal.to_numpy(), (n, 1)), columns=list(gripopt.DESIGN_NAMES))
    x.loc[at, column] = np.nan
    return x


def test_dask_checks_the_whole_batch_before_sending_it(problem):
    x = batch_with_nan(problem)
    with pytest.raises(gripopt.InputError, match=r"row 30, `t22` = NaN is not finite") as local:
        problem.evaluate(x, static_only=True)
    client = RecordingClient()
    with pytest.raises(gripopt.InputError) as there:
        gripopt.dask.evaluate(client, problem, x, static_only=True, chunk_size=8)
    assert str(there.value) == str(local.value) and there.value.field == "t22"
    assert client.submitted == []


def test_a_bad_row_is_named_by_its_index_label_too(problem):
    x = batch_with_nan(problem).set_axis(range(100, 140))
    for evaluate in (
        lambda: problem.evaluate(x, static_only=True),
        lambda: gripopt.dask.evaluate(RecordingClient(), problem, x, static_only=True, chunk_size=8),
    ):
        with pytest.raises(gripopt.InputError, match=r"row 30 \(index label 130\), `t22` = NaN is not finite"):
            evaluate()


def test_dask_checks_the_last_id_before_sending(problem):
    client = RecordingClient()
    two = pd.DataFrame([problem.nominal, problem.nominal])
    with pytest.raises(gripopt.InputError, match="the last of 2 designs"):
        gripopt.dask.evaluate(client, problem, two, first_id=2**63 - 1, chunk_size=1)
    assert client.submitted == []


def test_a_list_of_mappings_is_designs(problem):
    nominal = dict(problem.nominal)
    other = {**nominal, "r": 0.5}
    got = problem.evaluate([nominal, other], static_only=True)
    pdt.assert_frame_equal(got, problem.evaluate(pd.DataFrame([nominal, other]), static_only=True), check_exact=True)


def test_cells_that_are_not_numbers_name_the_column_and_row(problem):
    x = pd.DataFrame([problem.nominal] * 3).reset_index(drop=True).astype(object)
    x.loc[1, "psi_deg"] = "wide"
    with pytest.raises(gripopt.InputError, match=r"^designs: row 1, `psi_deg` = 'wide' is not a number") as e:
        problem.evaluate(x, static_only=True)
    assert e.value.field == "psi_deg"
    with pytest.raises(gripopt.InputError, match=r"^designs: row 0 \(index label 'a'\), `b` = NaN is not finite"):
        problem.evaluate(pd.DataFrame([{**dict(problem.nominal), "b": None}], index=["a"]).astype(object))
    for bad in [[{"l21": object()}], [[1, 2], [3]], ["a"] * 6, object()]:
        with pytest.raises(gripopt.InputError, match="^design"):
            problem.evaluate(bad, static_only=True)


def test_nullable_and_string_columns_are_numbers_or_named_errors(problem):
    """Origin: issue 44 class 8 (a raw TypeError from pandas' own dtypes). A design table in
    pandas' nullable or string dtypes is evaluated as its numbers; a missing or non-numeric
    cell is an InputError naming the column and the row, as docs/python.md promises."""
    nominal = pd.DataFrame([problem.nominal] * 2).reset_index(drop=True)
    want = problem.evaluate(nominal, static_only=True)
    for dtype in ["Float64", "string"]:
        got = problem.evaluate(nominal.astype(dtype), static_only=True)
        pdt.assert_frame_equal(got, want, check_exact=True)
    ints = nominal.copy()
    ints["psi_deg"] = pd.array([130, 131], dtype="Int64")
    assert len(problem.evaluate(ints, static_only=True)) == 2
    ints.loc[1, "psi_deg"] = pd.NA
    with pytest.raises(gripopt.InputError, match=r"^designs: row 1, `psi_deg` = NaN is not finite") as e:
        problem.evaluate(ints, static_only=True)
    assert e.value.field == "psi_deg"
    text = nominal.astype("string")
    text.loc[0, "b"] = "wide"
    with pytest.raises(gripopt.InputError, match=r"^designs: row 0, `b` = 'wide' is not a number"):
        problem.evaluate(text, static_only=True)


def test_natural_objectives_take_one_design_or_many():
    from gripopt.pymoo import natural_objectives

    F = np.array([-0.002, 0.1, -5.0, 0.03])
    one = natural_objectives(F)
    pdt.assert_frame_equal(one, natural_objectives(F[None, :]))
    assert one.iloc[0].tolist() == [0.002, 0.1, 5.0, 0.03]
    assert list(one.columns) == ["max_offset", "alpha", "mean_force", "t_stab"]
    for bad in [np.zeros(3), np.zeros((2, 3)), np.zeros((1, 1, 4)), ["x"] * 4]:
        with pytest.raises(gripopt.InputError, match="^F: "):
            natural_objectives(bad)


def test_gripper_problem_refuses_options_pymoo_would_swallow(problem):
    from gripopt.pymoo import GripperProblem

    with pytest.raises(gripopt.InputError, match=r"^static_only = 'yes': not an option of GripperProblem") as e:
        GripperProblem(problem, static_only="yes")
    assert e.value.field == "static_only"
    with pytest.raises(gripopt.InputError, match=r"^n_var = 3: set by GripperProblem"):
        GripperProblem(problem, n_var=3)
    with pytest.raises(gripopt.InputError, match=r"^threads = 0"):
        GripperProblem(problem, threads=0)
    with pytest.raises(gripopt.InputError, match=r"^chunk_size = 0"):
        GripperProblem(problem, chunk_size=0)
    with pytest.raises(gripopt.InputError, match=r"^client = 'local'"):
        GripperProblem(problem, client="local")
    with pytest.raises(gripopt.InputError, match=r"^problem = "):
        GripperProblem("problems/bottle-1l.toml")
    assert GripperProblem(problem, callback=None, threads=1).n_obj == 4  # pymoo's own options pass


def test_robust_counts_are_int64():
    from conftest import REPO

    kitchen = gripopt.Problem.load(REPO / "problems" / "kitchen.toml")
    rows = kitchen.evaluate(kitchen.nominal)
    counts = ["scenarios_run", "scenarios_saved"] + [c for c in rows.columns if c.endswith((".stays", ".scenarios"))]
    assert len(counts) == 2 + 2 * 4, list(rows.columns)
    for c in counts:
        assert rows[c].dtype == "Int64", (c, rows[c].dtype)
    r = kitchen.record(kitchen.nominal)["robust"]  # the record's counts, as the JSON gives them
    assert rows["scenarios_run"].iloc[0] == r["scenarios_run"]
    for o in r["objects"]:
        assert rows[f"{o['name']}.stays"].iloc[0] == o["stays"]
        assert rows[f"{o['name']}.scenarios"].iloc[0] == o["scenarios"]
    # the probability columns stay float64
    assert rows[[c for c in rows.columns if c.endswith(".p_stay")]].dtypes.eq("float64").all()


def test_robust_columns_carry_units_and_meanings():
    from conftest import REPO

    kitchen = gripopt.Problem.load(REPO / "problems" / "kitchen.toml")
    rows = kitchen.evaluate(kitchen.nominal)
    units, meanings = rows.attrs["units"], rows.attrs["meanings"]
    missing = [c for c in rows.columns if not units.get(c) or not meanings.get(c)]
    assert not missing, missing
    # docs/robust.md: per object, the displacement in m, the mean force in N, t_stab in s
    objects = {c.rsplit(".", 1)[0] for c in rows.columns if c.endswith(".p_stay")}
    assert len(objects) == 4, objects
    for o in objects:
        assert (units[f"{o}.max_displacement"], units[f"{o}.mean_force"], units[f"{o}.t_stab"]) == ("m", "N", "s")
        assert units[f"{o}.p_stay"] == "-" and meanings[f"{o}.p_stay"].startswith(f"{o}: ")
    assert units["scenarios_run"] == "-"  # the design-level robust columns too


def test_problem_of_a_path_is_a_type_error_naming_load(tmp_path):
    # hostile pass 34: Problem("file.toml") was accepted and failed at its first use with
    # AttributeError: 'str' object has no attribute 'method'
    for given in ["problems/bottle-1l.toml", tmp_path / "p.toml"]:
        with pytest.raises(TypeError, match=r"Problem\.load\("):
            gripopt.Problem(given)
    with pytest.raises(TypeError, match="not Problem\\(int\\)"):
        gripopt.Problem(3)
