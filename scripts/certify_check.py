#!/usr/bin/env python3
"""An independent check of a robust run's reported front (docs/robust.md, "Certification"):
every design of RUN/pareto.csv evaluated on N scenarios per object drawn with another seed
than the run's (so on streams neither the search, the certification nor `gripopt verify`
ever used), every scenario run (no early stop), through the public `gripopt evaluate --json`.
Prints per design and object P(stay) over the N scenarios with its 95 % Clopper-Pearson
interval, whether the design keeps P(stay) >= p_min on every object, and the counts of
designs that keep, surely keep (every lower bound >= p_min) and surely fail (some upper
bound < p_min).

    scripts/certify_check.py RUN [--scenarios 256] [--seed 1000003] [--jobs 2] [--bin target/release/gripopt]
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import re
import subprocess
import sys
import tempfile


def binom_cdf(s, n, p):
    if s >= n:
        return 1.0
    if p <= 0.0:
        return 1.0
    if p >= 1.0:
        return 0.0
    return sum(math.comb(n, j) * p**j * (1 - p) ** (n - j) for j in range(s + 1))


def clopper_pearson(s, n, level=0.95):
    a = (1 - level) / 2

    def bisect(f):
        lo, hi = 0.0, 1.0
        for _ in range(100):
            m = (lo + hi) / 2
            if f(m) < 0:
                lo = m
            else:
                hi = m
        return (lo + hi) / 2

    lo = 0.0 if s == 0 else bisect(lambda p: 1 - binom_cdf(s - 1, n, p) - a)
    hi = 1.0 if s == n else bisect(lambda p: a - binom_cdf(s, n, p))
    return lo, hi


def check_problem(run, scenarios, seed):
    """The run's problem with its scenario draw replaced: `seed`, N scenarios per object, every one run."""
    text = open(os.path.join(run, "problem.toml")).read()
    for key, value in [("scenarios", str(scenarios)), ("seed", str(seed)), ("early_stop", "false")]:
        text, n = re.subn(rf"(?m)^{key}\s*=\s*[^#\n]*", f"{key} = {value} ", text, count=1)
        if n != 1:
            sys.exit(f"{run}/problem.toml: no `{key} =` line in [robust]")
    text = re.sub(r"(?m)^sampling\s*=\s*\"corners\"", 'sampling = "random"', text)
    return text


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--scenarios", type=int, default=256)
    ap.add_argument("--seed", type=int, default=1000003)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--bin", default="target/release/gripopt")
    a = ap.parse_args()
    rows = [r for r in csv.DictReader(l for l in open(os.path.join(a.run, "pareto.csv")) if not l.startswith("#"))]
    p_min = float(re.search(r"(?m)^p_min\s*=\s*([0-9.]+)", open(os.path.join(a.run, "problem.toml")).read()).group(1))
    tmp = tempfile.mkdtemp(prefix="certify-check-")
    problem = os.path.join(tmp, "check.toml")
    open(problem, "w").write(check_problem(a.run, a.scenarios, a.seed))
    names = ["l21", "b", "t22", "r", "p", "psi_deg"]

    def evaluate(row):
        design = ",".join(f"{n}={row[n]}" for n in names)
        out = subprocess.run([a.bin, "evaluate", problem, "--design", design, "--json"], capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"design {row['id']}: {out.stderr}")
        return row["id"], json.loads(out.stdout)

    keep = surely_keep = surely_fail = 0
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        for id, rec in ex.map(evaluate, rows):
            objs = rec["robust"]["objects"]
            lows, highs, shown = [], [], []
            for o in objs:
                s, n = o["stays"], o["scenarios"]
                lo, hi = clopper_pearson(s, n)
                lows.append(lo)
                highs.append(hi)
                shown.append(f"{o['name']} {s}/{n} [{lo:.3f}, {hi:.3f}]")
            k = all(o["stays"] / o["scenarios"] >= p_min for o in objs)
            keep += k
            surely_keep += all(lo >= p_min for lo in lows)
            surely_fail += any(hi < p_min for hi in highs)
            print(f"design {id}: {'keeps' if k else 'FAILS'}  " + "  ".join(shown), flush=True)
    n = len(rows)
    print(
        f"{keep} of {n} designs keep P(stay) >= {p_min} on every object over {a.scenarios} fresh scenarios "
        f"per object (seed {a.seed}); {surely_keep} surely keep, {surely_fail} surely fail (95 % Clopper-Pearson)"
    )


if __name__ == "__main__":
    main()
