"""Runs: a run folder written by `gripopt optimise` read back through Run (against its CSV
files read by pandas and `gripopt replay --csv`), runs started and resumed from Python
(identical to the CLI's), the progress callback, ctrl-c, errors."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest

import gripopt
from conftest import BOTTLE, REPO, RUN_SETTINGS, same_float


def same_table(got: pd.DataFrame, want: pd.DataFrame) -> None:
    """The same columns and values (bit for bit; empty = missing), whatever the dtypes."""
    assert list(got.columns) == list(want.columns)
    assert len(got) == len(want)
    for col in want.columns:
        for a, b in zip(got[col].tolist(), want[col].tolist()):
            assert same_float(a, b), f"{col}: {a!r} != {b!r}"


def test_run_reads_a_run_written_by_the_cli(cli_run):
    run = gripopt.Run(cli_run)
    assert run.status == "finished" and run.info["completed_generations"] == RUN_SETTINGS["generations"]
    assert run.problem.name == "bottle-1l"
    for name, table in [("pareto", run.front), ("population", run.population), ("archive", run.archive)]:
        same_table(table, pd.read_csv(cli_run / f"{name}.csv", comment="#"))
        assert table.attrs["units"]["psi_deg"] == "deg"
    same_table(run.history, pd.read_csv(cli_run / "history.csv", comment="#"))
    assert len(run.population) == RUN_SETTINGS["pop"]


def test_a_recorded_design_and_its_replay(cli_run, cli, tmp_path):
    run = gripopt.Run(cli_run)
    simulated = run.population.dropna(subset=["sim_steps"])
    assert len(simulated) > 0, "the run simulated no design"
    id = int(simulated["id"].iloc[0])
    d = run.design(id)
    assert d.record["id"] == id and d.resolution == "compact" and d.file.name.startswith("gen-")
    csv = tmp_path / "traj.csv"
    cli("replay", cli_run, "--design", id, "--csv", csv)
    want = pd.read_csv(csv, comment="#")
    assert list(d.trajectory.columns) == list(want.columns)
    assert len(d.trajectory) == len(want) > 2
    for col in want.columns:
        assert [x.hex() for x in d.trajectory[col]] == [float(x).hex() for x in want[col]], col
    r = run.replay(id)
    assert r.verified and r.max_difference == 0.0 and r.compared == len(want)
    assert r.record["steps"] == d.record["sim_steps"]
    assert r.agrees_across_revisions is None, "recorded by this simulator revision"
    assert run.design(float(id)).record["id"] == id, "a whole float (a DataFrame cell) is the id"
    for bad in (id + 0.5, -1, "x", True):
        with pytest.raises(gripopt.InputError, match="design id"):
            run.design(bad)


def test_a_recording_by_an_older_simulator_agrees_across_revisions(tmp_path):
    # a run recorded by gripopt 5d2a08e (simulator revision 1), as `gripopt replay` reads it
    run_dir = tmp_path / "full"
    shutil.copytree(REPO / "tests" / "fixtures" / "recorded-5d2a08e" / "full", run_dir)
    run = gripopt.Run(run_dir)
    simulated = run.population.dropna(subset=["sim_steps"])
    replays = [run.replay(int(i)) for i in simulated["id"]]
    assert replays and not any(r.verified for r in replays), "another revision: not bit for bit"
    assert all(r.agrees_across_revisions for r in replays)


def test_optimise_from_python_is_the_cli_run(cli_run, tmp_path):
    reports = []
    s = RUN_SETTINGS
    run = gripopt.optimise(BOTTLE, tmp_path / "py", pop=s["pop"], generations=s["generations"], seed=s["seed"], threads=2, progress=reports.append)
    assert [r.generation for r in reports] == list(range(1, s["generations"] + 1))
    assert reports[-1].evaluations == s["pop"] * s["generations"]
    assert run.summary["generations"] == s["generations"] and not run.summary["interrupted"]
    cli = gripopt.Run(cli_run)
    pdt.assert_frame_equal(run.population, cli.population, check_exact=True)
    pdt.assert_frame_equal(run.archive, cli.archive, check_exact=True)


def test_resume_continues_exactly(cli_run, tmp_path):
    s = RUN_SETTINGS
    problem = gripopt.Problem.from_toml(BOTTLE.read_text())  # text: its copy is written into the folder
    out = tmp_path / "resumed"
    gripopt.optimise(problem, out, pop=s["pop"], generations=s["generations"] - 1, seed=s["seed"])
    run = gripopt.resume(out, generations=s["generations"])
    assert run.info["resumes"][0]["at_generation"] == s["generations"] - 1
    pdt.assert_frame_equal(run.population, gripopt.Run(cli_run).population, check_exact=True)


def test_a_callback_exception_stops_the_run_resumably(tmp_path):
    def stop_at_2(report):
        if report.generation == 2:
            raise ValueError("enough")

    out = tmp_path / "stopped"
    with pytest.raises(ValueError, match="enough"):
        gripopt.optimise(BOTTLE, out, pop=8, generations=5, seed=1, record=False, progress=stop_at_2)
    run = gripopt.Run(out)
    assert run.status == "interrupted" and run.info["completed_generations"] == 2
    assert run.resume().info["completed_generations"] == 5


CTRL_C = textwrap.dedent(
    """
    import json, os, signal, sys
    import gripopt
    seen = []
    def progress(report):
        seen.append(report.generation)
        if report.generation == 2:
            os.kill(os.getpid(), signal.SIGINT)  # as ctrl-c in a terminal or a notebook's stop
    try:
        gripopt.optimise(sys.argv[1], sys.argv[2], pop=8, generations=40, seed=1, record=False, progress=progress)
        print(json.dumps({"interrupted": False}))
    except KeyboardInterrupt as e:
        print(json.dumps({"interrupted": True, "notes": getattr(e, "__notes__", []), "seen": seen}))
    """
)


def test_ctrl_c_stops_after_the_checkpoint_and_the_run_resumes(tmp_path):
    out = tmp_path / "ctrl-c"
    p = subprocess.run([sys.executable, "-c", CTRL_C, str(BOTTLE), str(out)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    said = json.loads(p.stdout)
    assert said["interrupted"], said
    assert "stopped after generation" in said["notes"][0] and "gripopt.resume" in said["notes"][0]
    run = gripopt.Run(out)
    done = run.info["completed_generations"]
    assert run.status == "interrupted" and 2 <= done < 40 and max(said["seen"]) == done
    assert len(run.history) == done
    assert run.resume(generations=done + 1).info["completed_generations"] == done + 1


def test_errors_name_the_file_and_field(tmp_path, cli_run):
    with pytest.raises(gripopt.InputError) as e:
        gripopt.Problem.load(tmp_path / "missing.toml")
    assert e.value.exit_code == 2 and e.value.path.endswith("missing.toml") and "missing.toml" in str(e.value)
    bad = BOTTLE.read_text().replace("radius = ", "radius = -", 1)
    with pytest.raises(gripopt.ProblemError) as e:
        gripopt.Problem.from_toml(bad, "mine.toml")
    assert e.value.field == "object.radius" and e.value.path == "mine.toml" and "object.radius" in str(e.value)
    with pytest.raises(gripopt.RunFolderError):
        gripopt.Run(tmp_path / "nothing")
    with pytest.raises(gripopt.RunFolderError, match="already holds a run"):
        gripopt.optimise(BOTTLE, cli_run, pop=8, generations=2)
    with pytest.raises(gripopt.RunFolderError, match="not empty"):
        gripopt.optimise(gripopt.Problem.from_toml(BOTTLE.read_text()), cli_run, pop=8, generations=2)
    with pytest.raises(gripopt.RecordingError):
        gripopt.Run(cli_run).design(10**6)
    with pytest.raises(gripopt.InputError, match="unknown option `colour`"):
        gripopt.optimise(BOTTLE, tmp_path / "r", record={"colour": "red"})
    assert issubclass(gripopt.RunLockedError, gripopt.RunFolderError)
    assert issubclass(gripopt.InputError, gripopt.GripoptError) and issubclass(gripopt.InputError, ValueError)


def test_problems_and_errors_pickle(problem):
    import pickle

    again = pickle.loads(pickle.dumps(problem))
    assert again.toml == problem.toml and again.path == problem.path
    x = problem.bounds.sample(20, seed=2)
    pdt.assert_frame_equal(again.evaluate(x, static_only=True), problem.evaluate(x, static_only=True), check_exact=True)
    e = pickle.loads(pickle.dumps(gripopt.ProblemError("f.toml: field `a` = 1: bad", "f.toml", "a", 2)))
    assert isinstance(e, gripopt.ProblemError) and e.field == "a" and e.exit_code == 2


def test_static_rows_of_a_run_equal_a_fresh_evaluation(cli_run):
    # population.csv's static values are what Problem.evaluate gives for the same designs
    run = gripopt.Run(cli_run)
    pop = run.population
    fresh = run.problem.evaluate(pop, first_id=0)
    for col in ["feasible", "failed_stage", "violation", "reason", "max_offset", "alpha", "mean_force", "t_stab", "sim_steps"]:
        same_table(fresh[[col]], pop[[col]])
    assert np.all(fresh["generation"] == 0) and fresh["rank"].isna().all()
