"""Run the Python of docs/python.md: every ```python block (not ```python no-run), in
order, in one session, in a temporary folder, with RUN (a run folder written by the
tests), GRIPOPT (the gripopt command) and PROBLEM (problems/bottle-1l.toml) set.

Usage: python tools/check_python_docs.py RUN_DIR GRIPOPT_BINARY
Fails (exit 1) when a block raises or what the page says it shows is not there.
"""
import os
import re
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
DOC = os.path.join(ROOT, "docs", "python.md")


def blocks() -> list:
    """The page's runnable python blocks, in order."""
    found = re.findall(r"^```python( no-run)?\n(.*?)^```", open(DOC, encoding="utf-8").read(), re.S | re.M)
    return [code for skip, code in found if not skip]


def main(run: str, gripopt_bin: str) -> None:
    runnable = blocks()
    if len(runnable) < 6:
        sys.exit(f"{DOC}: expected the page's runnable python blocks, found {len(runnable)}")
    s = {"RUN": run, "GRIPOPT": gripopt_bin, "PROBLEM": os.path.join(ROOT, "problems", "bottle-1l.toml")}
    os.environ.setdefault("MPLBACKEND", "Agg")
    with tempfile.TemporaryDirectory() as d:
        os.chdir(d)
        for k, code in enumerate(runnable, 1):
            t = time.perf_counter()
            try:
                exec(compile(code, f"{DOC} (python block {k})", "exec"), s)
            except Exception:
                print(f"docs/python.md: python block {k} failed:\n{code}", file=sys.stderr)
                raise
            print(f"docs/python.md: block {k} ran in {time.perf_counter() - t:.1f} s")
        assert os.path.getsize("front.png") > 0, "the front's plot"
        assert os.path.isfile(os.path.join("my-run", "run.json")), "the run started from Python"
        os.chdir(ROOT)
    # what the page says each block shows
    assert len(s["statics"]) == 900 and list(s["statics"].columns[:2]) == ["id", "generation"], "the grid"
    assert len(s["grasps"]) > 0 and s["grasps"]["feasible"].any(), "the grid's grasps"
    assert len(s["sim"].trajectory) > 10 and s["sim"].trajectory["t"].is_monotonic_increasing, "a simulation"
    assert list(s["free"].trajectory.columns[:4]) == ["t", "gx", "gy", "gz"], "the free scene's poses"
    assert len(s["front"]) > 0 and s["front"]["mean_force"].is_monotonic_decreasing, "the run's front"
    assert len(s["traj"]) > 10 and s["traj"]["t"].is_monotonic_increasing, "a recorded trajectory"
    assert len(s["rows"]) == 50_000, "the Dask evaluation"
    print(f"docs/python.md: {len(runnable)} blocks ran: ok")


# Dask starts its workers as new processes that import this module: run only as a script
if __name__ == "__main__":
    main(os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]))
