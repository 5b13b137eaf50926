"""Run folders a hostile user put together (hostile pass 35): a shard of another run is never
read as this run's design (run.json missing or damaged included); a `Run` reads the run it
was opened on, never another run its path holds later; an edited problem.toml, a damaged or
edited CSV view and a killed run are told as `gripopt replay` / `show` tell them; a fork
child evaluates; a pickled robust problem carries its objects."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

import gripopt
from conftest import BOTTLE, REPO, RUN_SETTINGS


@pytest.fixture(scope="module")
def other_run(cli, tmp_path_factory) -> Path:
    """A second run of the same problem and settings but another seed (its design ids are
    the same numbers as the first run's, naming other designs)."""
    out = tmp_path_factory.mktemp("cli-run-b") / "run"
    s = RUN_SETTINGS
    cli("optimise", BOTTLE, "--out", out, "--pop", s["pop"], "--generations", s["generations"], "--seed", 9)
    return out


def copy_run(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    (dst / ".lock").unlink(missing_ok=True)
    return dst


def generation_2_id(run: Path) -> int:
    """A design id recorded in the run's second shard."""
    lines = (run / "recording" / "index.jsonl").read_text().splitlines()
    entry = next(e for e in map(json.loads, lines) if e["generation"] == 2)
    return int(entry["first_id"])


def test_a_shard_of_another_run_is_refused_without_run_json(cli_run, other_run, tmp_path):
    a = copy_run(cli_run, tmp_path / "A")
    id = generation_2_id(a)
    ours = gripopt.Run(a).design(id).record
    theirs = gripopt.Run(other_run).design(id).record
    assert ours["parameters"] != theirs["parameters"], "the two runs' designs must differ for this test"
    shutil.copy(other_run / "recording" / "gen-00002.mcap", a / "recording" / "gen-00002.mcap")
    with pytest.raises(gripopt.RecordingError, match="written by another run"):
        gripopt.Run(a).design(id)
    text = (a / "run.json").read_text()
    null_id = json.dumps({**json.loads(text), "run_id": None})
    for damage in ("missing", "cut short", "run_id null"):
        if damage == "missing":
            (a / "run.json").unlink()
        else:
            (a / "run.json").write_text(text[:100] if damage == "cut short" else null_id)
        # opened after the damage: nothing pinned, the library's own check refuses
        with pytest.raises(gripopt.RunFolderError, match="run.json") as e:
            gripopt.Run(a).design(id)
        said = str(e.value)
        # a missing run.json: no run to open at all (issue 44 class 8)
        assert any(w in said for w in ("another run", "attributed", "this run's", "not a run folder")), said
        (a / "run.json").write_text(text)


def test_a_run_reads_the_run_it_was_opened_on(cli_run, other_run, tmp_path):
    swap = copy_run(cli_run, tmp_path / "swap")
    run = gripopt.Run(swap)
    id = int(run.front["id"].iloc[0])
    front = run.front
    shutil.move(swap, tmp_path / "swap.old")
    copy_run(other_run, swap)
    reads = {
        "info": lambda: run.info,
        "status": lambda: run.status,
        "problem": lambda: run.problem,
        "front": lambda: run.front,
        "population": lambda: run.population,
        "archive": lambda: run.archive,
        "history": lambda: run.history,
        "summary": lambda: run.summary,
        "design": lambda: run.design(id),
        "replay": lambda: run.replay(id),
        "resume": lambda: run.resume(generations=4),
    }
    for what, read in reads.items():
        with pytest.raises(gripopt.RunFolderError, match="now holds another run") as e:
            read()
        assert str(swap) in str(e.value), what
    # nothing was resumed in the folder: it is still the other run's, as copied
    assert gripopt.Run(swap).info["completed_generations"] == RUN_SETTINGS["generations"]
    # opened again: the run the folder holds now
    assert gripopt.Run(swap).info["run_id"] == run_id_of(other_run) != run_id_of(cli_run)
    # the run back: read again; then no run.json at all: refused
    shutil.rmtree(swap)
    shutil.move(tmp_path / "swap.old", swap)
    assert run.front.equals(front)
    (swap / "run.json").unlink()
    with pytest.raises(gripopt.RunFolderError, match="missing or unreadable"):
        run.front


def run_id_of(run: Path) -> str:
    return json.loads((run / "run.json").read_text())["run_id"]


def test_an_edited_problem_copy_is_refused(cli_run, tmp_path):
    p = copy_run(cli_run, tmp_path / "P")
    assert gripopt.Run(p).problem.toml == (p / "problem.toml").read_text()
    text = (p / "problem.toml").read_text()
    edited = text.replace("tau = 0.5 ", "tau = 0.6 ", 1)
    assert edited != text
    (p / "problem.toml").write_text(edited)
    with pytest.raises(gripopt.RunFolderError, match="edited") as e:
        gripopt.Run(p).problem
    assert e.value.path is not None and Path(e.value.path).name == "problem.toml"


@pytest.mark.parametrize("name, file", [("archive", "archive.csv"), ("front", "pareto.csv"), ("history", "history.csv")])
def test_a_table_whose_header_is_not_gripopts_is_refused(cli_run, tmp_path, name, file):
    e_dir = copy_run(cli_run, tmp_path / "E")
    (e_dir / file).write_text("foo\n")
    with pytest.raises(gripopt.RunFolderError, match="header") as e:
        getattr(gripopt.Run(e_dir), name)
    assert Path(e.value.path).name == file
    # a column renamed in a header otherwise right
    (e_dir / file).unlink()
    shutil.copy(cli_run / file, e_dir / file)
    text = (e_dir / file).read_text()
    (e_dir / file).write_text(text.replace(",generation,", ",gen,", 1).replace("generation,evaluations", "gen,evaluations"))
    with pytest.raises(gripopt.RunFolderError, match="header"):
        getattr(gripopt.Run(e_dir), name)


def test_a_view_edited_by_hand_warns_and_gives_the_checkpoints_designs(cli_run, tmp_path):
    e_dir = copy_run(cli_run, tmp_path / "E")
    front = gripopt.Run(e_dir).front
    lines = (e_dir / "pareto.csv").read_text().splitlines(keepends=True)
    k = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1  # first data line
    cells = lines[k].split(",")
    cells[0] = str(int(cells[0]) + 100000)  # the id changed by hand
    lines[k] = ",".join(cells)
    (e_dir / "pareto.csv").write_text("".join(lines))
    with pytest.warns(gripopt.GripoptWarning, match="pareto.csv does not hold the designs of checkpoint.json"):
        shown = gripopt.Run(e_dir).front
    assert shown.equals(front)
    # the views as written: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gripopt.Run(cli_run).front
        gripopt.Run(cli_run).archive


def test_a_killed_run_is_stopped_not_running(cli_run, tmp_path):
    k = copy_run(cli_run, tmp_path / "K")
    info = json.loads((k / "run.json").read_text())
    assert gripopt.Run(k).status == "finished"
    # run.json as a process killed with kill -9 leaves it: running, with no process holding
    # the folder's lock
    (k / "run.json").write_text(json.dumps({**info, "status": "running"}, indent=2))
    assert gripopt.Run(k).status == "stopped"


def test_a_killed_process_leaves_a_stopped_run(gripopt_bin, tmp_path):
    out = tmp_path / "K"
    proc = subprocess.Popen(
        [str(gripopt_bin), "optimise", str(BOTTLE), "--out", str(out), "--pop", "64", "--generations", "200"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        for _ in range(600):
            if (out / "run.json").exists():
                try:
                    if gripopt.Run(out).status == "running":
                        break
                except gripopt.GripoptError:
                    pass
            proc.poll()
            assert proc.returncode is None, "the run ended before it could be killed"
            subprocess.run(["sleep", "0.05"])
        assert gripopt.Run(out).status == "running"
    finally:
        proc.kill()
        proc.wait()
    assert gripopt.Run(out).status == "stopped"


FORK_SCRIPT = """
import multiprocessing, sys
from concurrent.futures import ProcessPoolExecutor
import gripopt

p = gripopt.Problem.load(sys.argv[1])
X = p.bounds.sample(100, seed=1)
p.evaluate(X.iloc[:1], static_only=True)  # the parent's global rayon pool started
with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork")) as ex:
    futures = [ex.submit(p.evaluate, chunk, static_only=True) for chunk in (X.iloc[:50], X.iloc[50:])]
    rows = sum(len(f.result()) for f in futures)
print(rows)
"""


@pytest.mark.skipif(sys.platform != "linux", reason="fork start method")
def test_a_forked_worker_evaluates_after_the_parent_did(problem, tmp_path):
    script = tmp_path / "fork.py"
    script.write_text(FORK_SCRIPT)
    try:
        p = subprocess.run(
            [sys.executable, str(script), str(BOTTLE)], capture_output=True, text=True, timeout=120, cwd=tmp_path
        )
    except subprocess.TimeoutExpired:
        pytest.fail("a forked worker's evaluate hangs (the parent's rayon pool does not survive fork)")
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "100"


KITCHEN = REPO / "problems" / "kitchen.toml"
CAN_INLINE = """name = "can"             # as can.toml: a 330 ml can, 0.34 kg
radius = 0.030
length = 0.115
density = 1050.0
grasp_height = 0.040
"""


def test_a_pickled_robust_problem_carries_its_object_files(tmp_path, monkeypatch):
    import pickle

    here = tmp_path / "here"
    here.mkdir()
    text = KITCHEN.read_text()
    assert CAN_INLINE in text
    (here / "kitchen-files.toml").write_text(text.replace(CAN_INLINE, 'name = "can"\nfile = "can.toml"\n'))
    shutil.copy(REPO / "problems" / "can.toml", here / "can.toml")
    monkeypatch.chdir(here)
    p = gripopt.Problem.load("kitchen-files.toml")
    before = p.evaluate(p.nominal)  # the can's own columns: its cylinder simulated
    blob = pickle.dumps(p)
    # elsewhere, the object file edited (another can): the pickle holds the can as loaded
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    can = (here / "can.toml").read_text()
    assert "radius = 0.030" in can
    (here / "can.toml").write_text(can.replace("radius = 0.030", "radius = 0.033", 1))
    edited = gripopt.Problem.load(here / "kitchen-files.toml").evaluate(p.nominal)
    assert not edited.equals(before), "the edit must change the can's results"
    monkeypatch.chdir(elsewhere)
    q = pickle.loads(blob)
    assert q.toml == p.toml and q.path == p.path and q.name == p.name
    assert q.evaluate(q.nominal).equals(before)
    # a problem without object files pickles as its text, as before
    r = pickle.loads(pickle.dumps(gripopt.Problem.load(BOTTLE)))
    assert r.toml == BOTTLE.read_text()
    np.testing.assert_array_equal(r.nominal.to_numpy(), gripopt.Problem.load(BOTTLE).nominal.to_numpy())


def test_empty_tables_have_the_columns_of_full_ones(problem, cli_run, tmp_path):
    X = problem.bounds.sample(3, seed=1)
    for static_only in (True, False):
        full = problem.evaluate(X, static_only=static_only)
        empty = problem.evaluate(np.zeros((0, 6)), static_only=static_only)
        assert len(empty) == 0
        assert empty.dtypes.to_dict() == full.dtypes.to_dict(), static_only
        assert empty.attrs["units"] == full.attrs["units"]
    kitchen = gripopt.Problem.load(KITCHEN)
    full = kitchen.evaluate(kitchen.nominal)
    empty = kitchen.evaluate(np.zeros((0, 6)))
    assert "can.p_stay" in empty.columns
    assert empty.dtypes.to_dict() == full.dtypes.to_dict()
    # an empty front: the population's columns and dtypes
    e_dir = copy_run(cli_run, tmp_path / "E")
    run = gripopt.Run(e_dir)
    population = run.population
    lines = (e_dir / "pareto.csv").read_text().splitlines(keepends=True)
    header = [line for line in lines if line.startswith("#")]
    names = next(line for line in lines if not line.startswith("#"))
    # a front with no design (as a run whose designs are all infeasible writes it); the
    # checkpoint's front is not empty, so it is read from a folder without a checkpoint
    (e_dir / "pareto.csv").write_text("".join(header) + names)
    (e_dir / "checkpoint.json").unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        front = gripopt.Run(e_dir).front
    assert len(front) == 0
    assert front.dtypes.to_dict() == population.dtypes.to_dict()
    history = gripopt.Run(cli_run).history
    (e_dir / "history.csv").write_text(
        "".join(line for line in (cli_run / "history.csv").read_text().splitlines(keepends=True)[:4] if line.startswith("#") or "generation," in line)
    )
    empty_history = gripopt.Run(e_dir).history
    assert len(empty_history) == 0 and empty_history.dtypes.to_dict() == history.dtypes.to_dict()


def test_a_folder_without_a_run_is_refused_when_opened(tmp_path, cli_run):
    """Origin: issue 44 class 8: `gripopt.Run(path)` of a folder that holds no run opened
    fine and failed later, at a read, with another exception. It is a RunFolderError naming
    the folder at once (an empty folder, a folder of other files; a run folder opens)."""
    empty = tmp_path / "empty"
    empty.mkdir()
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("not a run")
    for d in (empty, other):
        with pytest.raises(gripopt.RunFolderError, match=r"not a run folder \(no run.json\)") as e:
            gripopt.Run(d)
        assert str(d) in str(e.value)
    assert gripopt.Run(cli_run).info["completed_generations"] > 0


def test_the_lock_held_by_this_process_is_not_named_as_another(tmp_path):
    """Origin: issue 44 class 8: a run folder locked by another call in the same Python
    process (a run in another thread) was said to be in use by "another gripopt process (pid
    <this process>)". It says another call in this process holds it."""
    import os
    import threading

    out = tmp_path / "held"
    started, release = threading.Event(), threading.Event()

    def hold(report):
        started.set()
        release.wait(60)

    t = threading.Thread(
        target=lambda: gripopt.optimise(BOTTLE, out, pop=8, generations=2, seed=1, record=False, progress=hold)
    )
    t.start()
    try:
        assert started.wait(120), "the run did not start"
        with pytest.raises(gripopt.RunLockedError) as e:
            gripopt.resume(out)
        said = str(e.value)
        assert "another call in this process" in said and f"pid {os.getpid()}" in said, said
        assert "another gripopt process" not in said, said
    finally:
        release.set()
        t.join(120)
