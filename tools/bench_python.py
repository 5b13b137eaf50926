"""Throughput of the Python package's static evaluation against `gripopt bench static`
(docs/benchmarks.md, "Python package"). Not a test.

The same designs (the bench's stream, seed 1) through stages 0-2 on one thread:

- wall clock (default): `rounds` alternations of `gripopt bench static` (5 repetitions
  each) and `problem.evaluate(designs, static_only=True, threads=1)` (5 repetitions each,
  the DataFrame built), so both see the same machine load; designs/s at the min and median
  time and their ratio; then `problem.evaluate` on 1 and on all cores (threads=None).
- `--callgrind`: instructions per design (valgrind; repeatable on a loaded machine): the
  bench's timed loop (`--toggle-collect` on its function: 5 x N evaluations) against the
  whole `problem.evaluate` call, measured as the difference of two runs of this script
  that differ only by that call (imports and the problem's loading cancel out).

Usage: python tools/bench_python.py [GRIPOPT_BINARY] [--n N] [--rounds R] [--callgrind]
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import time

import gripopt

BENCH_LINE = re.compile(r"min-time (\d+)\s+median-time (\d+)")
IR = re.compile(r"I\s+refs:\s+([\d,]+)")


def bench_static(binary: str, problem: str, n: int) -> tuple[int, int]:
    """`gripopt bench static`'s designs/s at the min and median time."""
    out = subprocess.run(
        [binary, "bench", "static", problem, "--n", str(n), "--seed", "1"], capture_output=True, text=True, check=True
    ).stdout
    m = BENCH_LINE.search(out)
    assert m, f"no designs/s in the bench's output:\n{out}"
    return int(m.group(1)), int(m.group(2))


def evaluate_rate(problem: gripopt.Problem, designs, threads) -> float:
    """designs/s of one `problem.evaluate(..., static_only=True)` call."""
    t = time.perf_counter()
    problem.evaluate(designs, static_only=True, threads=threads)
    return len(designs) / (time.perf_counter() - t)


def wall_clock(a: argparse.Namespace) -> None:
    problem = gripopt.Problem.load(a.problem)
    designs = problem.bounds.sample(a.n, seed=1)
    bench_min, bench_med, py, py_all = [], [], [], []
    for _ in range(a.rounds):
        b_min, b_med = bench_static(a.gripopt, a.problem, a.n)
        bench_min.append(b_min)
        bench_med.append(b_med)
        py += [evaluate_rate(problem, designs, 1) for _ in range(5)]
        py_all += [evaluate_rate(problem, designs, None) for _ in range(5)]
    b_min, b_med = max(bench_min), statistics.median(bench_med)
    p_min, p_med = max(py), statistics.median(py)
    print(f"{a.n} designs, static pipeline (stages 0-2), {a.rounds} rounds x 5 repetitions each")
    print(f"  gripopt bench static (1 thread)       designs/s: min-time {b_min:.0f}  median-time {b_med:.0f}")
    print(f"  problem.evaluate, threads=1           designs/s: min-time {p_min:.0f}  median-time {p_med:.0f}")
    print(f"  ratio: min-time {p_min / b_min:.1%}  median-time {p_med / b_med:.1%}")
    cores = os.cpu_count()
    print(
        f"  problem.evaluate, threads=None ({cores} cores) designs/s: min-time {max(py_all):.0f}  "
        f"median-time {statistics.median(py_all):.0f}  ({max(py_all) / p_min:.2f}x threads=1 at min-time)"
    )


def callgrind_total(cmd: list[str], extra: list[str]) -> int:
    """Instructions valgrind's callgrind counts for `cmd`."""
    p = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *extra, *cmd],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONHASHSEED": "0"},
    )
    m = IR.search(p.stderr)
    assert p.returncode == 0 and m, f"{' '.join(cmd)} under callgrind:\n{p.stderr[-2000:]}"
    return int(m.group(1).replace(",", ""))


def callgrind(a: argparse.Namespace) -> None:
    bench = callgrind_total(
        [a.gripopt, "bench", "static", a.problem, "--n", str(a.n), "--seed", "1"],
        ["--collect-atstart=no", "--toggle-collect=gripopt::bench::static_eval::static_pipeline"],
    )
    me = [sys.executable, __file__, a.gripopt, "--n", str(a.n), "--problem", a.problem, "--child"]
    without, with_call = callgrind_total([*me, "0"], []), callgrind_total([*me, "1"], [])
    per_bench = bench / (5 * a.n)
    per_py = (with_call - without) / a.n
    print(f"{a.n} designs, static pipeline (stages 0-2), 1 thread, callgrind instructions per design")
    print(f"  gripopt bench static              {per_bench:,.0f}")
    print(f"  problem.evaluate (whole call)     {per_py:,.0f}")
    print(f"  throughput ratio (bench / Python instructions): {per_bench / per_py:.1%}")


def child(a: argparse.Namespace) -> None:
    """The program callgrind counts: everything but the evaluation, and with `--child 1` it."""
    problem = gripopt.Problem.load(a.problem)
    designs = problem.bounds.sample(a.n, seed=1)
    problem.evaluate(designs.iloc[:2], static_only=True, threads=1)  # first-call paths
    if a.child == "1":
        problem.evaluate(designs, static_only=True, threads=1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("gripopt", nargs="?", default="target/release/gripopt")
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--problem", default="problems/bottle-1l.toml")
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--child", choices=["0", "1"], help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child is not None:
        child(a)
    elif a.callgrind:
        callgrind(a)
    else:
        wall_clock(a)


if __name__ == "__main__":
    main()
