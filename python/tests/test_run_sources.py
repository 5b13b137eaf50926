"""What a run from Python runs and records: exactly the Problem object's text, attributed
to the file it came from only while that file holds that text; arguments refused before
anything is written; a run folder's summary; messages in Python's words."""

from __future__ import annotations

import hashlib
import json
import shutil
import warnings
from pathlib import Path

import pandas as pd
import pytest

import gripopt
from conftest import BOTTLE, RUN_SETTINGS

#: The bottle problem with another torque: a different problem, valid.
TAU_09 = BOTTLE.read_text().replace("tau = 0.5 ", "tau = 0.9 ", 1)
QUICK = {"pop": 8, "generations": 1, "seed": 1, "record": False}


def sha256(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def run_json(out: Path) -> dict:
    return json.loads((out / "run.json").read_text())


def assert_ran(out: Path, text: str) -> None:
    """The run in `out` ran `text` (the hash of what the library loaded and ran) and names
    its copy in the folder, not another file, as its source."""
    info = run_json(out)
    assert info["problem_sha256"] == sha256(text)
    assert Path(info["problem_path"]) == (out / "problem.toml").absolute()
    assert (out / "problem.toml").read_text() == text


def test_text_named_after_an_existing_file_runs_the_text(tmp_path):
    assert TAU_09 != BOTTLE.read_text()
    named = tmp_path / "bottle-1l.toml"
    shutil.copy(BOTTLE, named)  # tau = 0.5 on disk
    q = gripopt.Problem.from_toml(TAU_09, named)
    out = tmp_path / "run"
    with pytest.warns(gripopt.GripoptWarning, match="not the problem's text"):
        run = gripopt.optimise(q, out, **QUICK)
    assert_ran(out, TAU_09)
    assert run.problem.toml == TAU_09
    # the file is not the run's source: editing it does not concern a resume
    named.write_text(BOTTLE.read_text().replace("tau = 0.5 ", "tau = 0.7 ", 1))
    assert gripopt.resume(out, generations=2).info["completed_generations"] == 2


def test_a_problem_edited_on_disk_after_loading_runs_as_loaded(tmp_path):
    mut = tmp_path / "mut.toml"
    shutil.copy(BOTTLE, mut)
    q = gripopt.Problem.load(mut)
    mut.write_text(TAU_09)
    out = tmp_path / "run"
    with pytest.warns(gripopt.GripoptWarning, match="mut.toml"):
        gripopt.optimise(q, out, **QUICK)
    assert_ran(out, BOTTLE.read_text())


def test_text_named_after_no_file_starts_a_run(tmp_path):
    q = gripopt.Problem.from_toml(TAU_09, "virtual.toml")
    out = tmp_path / "run"
    gripopt.optimise(q, out, **QUICK)
    assert_ran(out, TAU_09)


def test_a_problem_whose_file_is_unchanged_names_the_file(tmp_path):
    # as `gripopt optimise FILE`: the file is the source, and a resume sees its edits
    own = tmp_path / "own.toml"
    shutil.copy(BOTTLE, own)
    out = tmp_path / "run"
    with warnings.catch_warnings():
        warnings.simplefilter("error", gripopt.GripoptWarning)
        gripopt.optimise(gripopt.Problem.load(own), out, **QUICK)
    assert Path(run_json(out)["problem_path"]) == own.absolute()
    own.write_text(TAU_09)
    with pytest.raises(gripopt.RunFolderError, match="changed since the run started"):
        gripopt.resume(out, generations=2)


def test_a_refused_run_leaves_no_copy_behind(tmp_path):
    out = tmp_path / "run"
    q = gripopt.Problem.from_toml(TAU_09)
    with pytest.raises(gripopt.InputError) as e:
        gripopt.optimise(q, out, **{**QUICK, "pop": 2})
    assert not out.exists()
    # and in Python's words: an argument, not a command-line flag
    assert e.value.field == "pop" and str(e.value).startswith("argument `pop` = 2: must be at least 4")
    assert "command line" not in str(e.value) and "--" not in str(e.value)
    with pytest.raises(gripopt.InputError) as e:
        gripopt.optimise(q, out, **{**QUICK, "record": {"every": 0}})
    assert e.value.field == "record" and str(e.value).startswith('argument `record["every"]` = 0: must be at least 1')
    with pytest.raises(gripopt.InputError) as e:
        gripopt.optimise(q, out, **{**QUICK, "record": {"every": 2}})
    assert "--" not in str(e.value) and 'record={…, "resolution": "full"}' in str(e.value)
    assert not out.exists()
    gripopt.optimise(q, out, **QUICK)  # the same call, corrected, starts it
    assert_ran(out, TAU_09)


@pytest.mark.parametrize("progress", [5, "print", [1]])
def test_a_progress_that_is_not_callable_is_refused_before_the_run(tmp_path, progress):
    out = tmp_path / "run"
    with pytest.raises(gripopt.InputError, match=r"^progress = .*: must be a callable") as e:
        gripopt.optimise(BOTTLE, out, **{**QUICK, "progress": progress})
    assert e.value.field == "progress" and not out.exists()
    gripopt.optimise(BOTTLE, out, **QUICK)  # a retry with the same folder runs


def test_a_record_that_is_not_options_is_refused(tmp_path):
    for bad in [5, "none", ["every"]]:
        with pytest.raises(gripopt.InputError, match=r"^record = ") as e:
            gripopt.optimise(BOTTLE, tmp_path / "run", **{**QUICK, "record": bad})
        assert e.value.field == "record"
    assert not (tmp_path / "run").exists()


def test_a_run_opened_from_its_folder_has_its_summary(cli_run):
    s = gripopt.Run(cli_run).summary
    assert s is not None
    info = run_json(cli_run)
    csv = lambda name: pd.read_csv(cli_run / name, comment="#")  # noqa: E731
    history = csv("history.csv")
    assert s["generations"] == RUN_SETTINGS["generations"] == info["completed_generations"]
    assert s["evaluations"] == RUN_SETTINGS["pop"] * RUN_SETTINGS["generations"]
    assert s["front_size"] == len(csv("pareto.csv")) and s["archive_size"] == len(csv("archive.csv"))
    assert s["feasible"] == history["feasible"].iloc[-1]
    # pareto.csv's hypervolume (the reported front), at least the population's front's
    assert s["hypervolume"] == history["pareto_hypervolume"].iloc[-1] >= history["hypervolume"].iloc[-1]
    assert s["archive_hypervolume"] == history["archive_hypervolume"].iloc[-1]
    assert s["interrupted"] is False and s["wall_s"] == info["wall_s"]


def test_resume_messages_name_python_arguments(cli_run, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(cli_run, out)
    with pytest.raises(gripopt.InputError, match=r"^generations = 1: the run already has 3 generations"):
        gripopt.resume(out, generations=1)
