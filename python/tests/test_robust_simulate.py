"""Problem.simulate(object=NAME) on a robust problem against `gripopt simulate --object
NAME --json --csv` (a separate process): the same record and trajectory; without object=
the reference [object] is simulated, with a GripoptWarning saying so."""

from __future__ import annotations

import warnings

import pandas as pd
import pytest

import gripopt
from conftest import BOTTLE, REPO
from test_simulate import same_record, untimed

KITCHEN = REPO / "problems" / "kitchen.toml"


def test_simulate_on_a_robust_object_equals_the_cli(cli_json, tmp_path):
    kitchen = gripopt.Problem.load(KITCHEN)
    csv = tmp_path / "can.csv"
    cli = cli_json("simulate", KITCHEN, "--object", "can", "--json", "--csv", csv)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # object= given: no note
        sim = kitchen.simulate(object="can")
    assert sim.record["object"] == cli["object"] == "can"
    assert same_record(untimed(sim.record), untimed(cli))
    want = pd.read_csv(csv, comment="#")
    assert list(sim.trajectory.columns) == list(want.columns) and len(want) > 10
    for col in want.columns:
        a, b = sim.trajectory[col].to_numpy(), want[col].to_numpy()
        assert [x.hex() for x in a] == [float(x).hex() for x in b], col
    # the reference [object] is another simulation, and says so
    with pytest.warns(gripopt.GripoptWarning, match=r"reference \[object\].*object=NAME.*can") as w:
        reference = kitchen.simulate()
    assert len(w) == 1 and w[0].filename == __file__
    assert "object" not in reference.record
    assert not same_record(untimed(reference.record), untimed(sim.record))


def test_a_bad_object_is_an_input_error_naming_it():
    kitchen = gripopt.Problem.load(KITCHEN)
    with pytest.raises(gripopt.InputError, match="no such robust object.*can") as e:
        kitchen.simulate(object="mug")
    assert e.value.field == "object"
    with pytest.raises(gripopt.InputError, match="not robust") as e:
        gripopt.Problem.load(BOTTLE).simulate(object="can")
    assert e.value.field == "object"
