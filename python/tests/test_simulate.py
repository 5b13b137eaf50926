"""Problem.simulate against `gripopt simulate --json --csv` (a separate process): the
record and every trajectory value bit for bit, in each scene."""

from __future__ import annotations

import pandas as pd
import pytest

import gripopt
from conftest import same_float


def untimed(rec: dict) -> dict:
    rec = dict(rec)
    rec.pop("cpu_s", None)
    if isinstance(rec.get("free_scene"), dict):
        rec["free_scene"] = {k: v for k, v in rec["free_scene"].items() if k != "cpu_s"}
    return rec


def same_record(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_record(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_record(x, y) for x, y in zip(a, b))
    return same_float(a, b)


@pytest.mark.parametrize("scene", ["centred", "offset:0.002", "free"])
def test_simulation_equals_the_cli(problem, cli_json, tmp_path, scene):
    csv = tmp_path / "traj.csv"
    cli = cli_json("simulate", "problems/bottle-1l.toml", "--scene", scene, "--json", "--csv", csv)
    sim = problem.simulate(scene=scene)
    assert same_record(untimed(sim.record), untimed(cli))
    want = pd.read_csv(csv, comment="#")
    table = gripopt.POSE_COLUMNS if scene == "free" else gripopt.SAMPLE_COLUMNS
    if scene.startswith("offset"):  # finger 2 moves on its own there: its columns follow
        table = tuple(table) + tuple(gripopt.FINGER2_COLUMNS)
    assert list(sim.trajectory.columns) == list(want.columns) == [c[0] for c in table]
    assert len(sim.trajectory) == len(want) > 10
    for col in want.columns:
        a, b = sim.trajectory[col].to_numpy(), want[col].to_numpy()
        assert [x.hex() for x in a] == [float(x).hex() for x in b], col
    assert sim.trajectory.attrs["units"]["t"] == "s"
    if scene == "free":
        assert sim.record["scene"] == "free" and sim.trajectory.attrs["units"]["tilt_deg"] == "deg"
        assert len(sim.grasp) > 10 and list(sim.grasp.columns)[:3] == ["t", "q11", "q21"]
    else:
        assert sim.grasp is sim.trajectory
    if scene.startswith("offset"):
        assert sim.record["scene"] == "offset" and sim.record["x_off"] == 0.002


def test_bad_scenes_and_discarded_designs_are_input_errors(problem):
    with pytest.raises(gripopt.InputError, match="must be centred, offset:X or free"):
        problem.simulate(scene="sideways")
    with pytest.raises(gripopt.InputError, match="not a number"):
        problem.simulate(scene="offset:far")
    discarded = problem.evaluate(problem.bounds.sample(50, seed=1), static_only=True).query("failed_stage == 1")
    with pytest.raises(gripopt.InputError, match="discarded at stage 1"):
        problem.simulate(discarded.iloc[0])
    with pytest.raises(gripopt.InputError, match="rtol") as e:
        problem.simulate(rtol=2.0)
    assert e.value.field == "rtol"
    with pytest.raises(gripopt.InputError, match="method"):
        problem.simulate(method="euler")


def test_the_problems_solver_method_is_the_default(problem, cli_json, tmp_path):
    """`[solver] method = "auto"`: Problem.method says it, simulate() uses it (the record of
    `gripopt simulate --json` on the same file), an explicit method overrides it; a file
    without the key runs the default, auto with the default's tolerance scaling (session 38:
    not the named auto's record)."""
    text = problem.toml.replace("\n[solver]\n", '\n[solver]\nmethod = "auto"\n', 1)
    path = tmp_path / "auto.toml"
    path.write_text(text)
    auto = gripopt.Problem.load(path)
    assert (problem.method, auto.method) == ("auto", "auto")
    sim = auto.simulate()
    assert sim.record["method"] == "auto"
    assert same_record(untimed(sim.record), untimed(cli_json("simulate", path, "--json")))
    radau = auto.simulate(method="radau5")
    assert radau.record["method"] == "radau5" and radau.record["steps"] != sim.record["steps"]
    assert same_record(untimed(radau.record), untimed(problem.simulate(method="radau5").record))
    default = problem.simulate()
    assert default.record["method"] == "auto" and default.record["steps"] != sim.record["steps"]
    assert same_record(untimed(default.record), untimed(cli_json("simulate", "problems/bottle-1l.toml", "--json")))
    with pytest.raises(gripopt.ProblemError, match="solver.method"):
        gripopt.Problem.from_toml(text.replace('"auto"', '"euler"'))


def test_method_names_are_the_command_lines(problem, cli_json):
    """`method=` takes what `gripopt simulate --method` takes, the alias `tr-bdf2` too (the
    same record as the CLI's with that spelling); a bad name's error lists them all. An auto
    record counts its switches and explicit steps; a single method's has no such keys."""
    alias = problem.simulate(method="tr-bdf2")
    assert alias.record["method"] == "trbdf2"
    assert same_record(untimed(alias.record), untimed(problem.simulate(method="trbdf2").record))
    cli = cli_json("simulate", "problems/bottle-1l.toml", "--method", "tr-bdf2", "--json")
    assert same_record(untimed(alias.record), untimed(cli))
    with pytest.raises(gripopt.InputError) as e:
        problem.simulate(method="tr_bdf2")
    for name in ['"radau5"', '"auto"', '"trbdf2"', '"tr-bdf2"', '"dopri5"']:
        assert name in str(e.value), (name, str(e.value))
    assert "switches" not in alias.record and "explicit_steps" not in alias.record
    auto = problem.simulate(method="auto").record
    assert auto["switches"] >= 1 and 0 < auto["explicit_steps"] <= auto["steps"]


def test_tr_bdf2_refuses_an_atol_its_error_estimate_cannot_meet(problem):
    """TR-BDF2 takes solver.atol >= 1e-11 (below it its steps collapse: hostile pass 34);
    `method="trbdf2"` on a problem at 1e-13 (which the default solver runs) says so, naming
    the method."""
    tight = gripopt.Problem.from_toml(problem.toml.replace("atol = 1e-9", "atol = 1e-13", 1))
    assert tight.simulate().record["method"] == "auto"
    with pytest.raises(gripopt.InputError, match=r"trbdf2.*atol 1e-13.*>= 1e-11"):
        tight.simulate(method="trbdf2")
    with pytest.raises(gripopt.InputError, match=r"solver\.atol"):
        gripopt.Problem.from_toml(tight.toml.replace("[solver]\n", '[solver]\nmethod = "trbdf2"\n', 1))
