#!/usr/bin/env python3
"""gripopt's optimiser against pymoo's NSGA-II, SMS-EMOA and NSGA-III on the same black box.

Every algorithm optimises the same problem file with the same population (100) and budget,
its designs evaluated by gripopt (pymoo's through the Python package's
``gripopt.pymoo.GripperProblem``: gripopt's evaluation in-process, objectives
(−max_offset, alpha, −mean_force, t_stab) and gripopt's constraint domination), over the
same seeds. Each run's hypervolume is measured as gripopt measures its own (history.csv:
objectives normalised by the run's ``hv_ideal``/``hv_ref`` from run.json, reference point
(1, …, 1), exact, moocore) at every budget given:

- ``front``: what the run reports. gripopt: pareto.csv (history.csv's
  ``pareto_hypervolume``; a gripopt before issue 42: the population's front, its
  ``hypervolume``); pymoo: the feasible non-dominated members of the population (``res.opt``);
- ``found``: every feasible non-dominated design the run evaluated (gripopt's archive.csv,
  ``archive_hypervolume``; for pymoo the same set, kept by this script).

The table gives the median [min, max] over the seeds, and for each other algorithm the
two-sided Mann–Whitney U test (scipy) of its values against the first algorithm's (the
binary under test). A gripopt run is reused when its folder holds a finished run with the
same settings; a pymoo run when its JSON result exists (delete OUT to measure afresh).

    .venv/bin/python tools/compare_pymoo.py BIN OUT [--baseline BIN2] [--seeds 1-11]
        [--budgets 1500,6000] [--pop 100] [--jobs 2] [--problem problems/bottle-1l.toml]

Needs ``make venv`` and ``make python`` (pymoo 0.6.2, moocore, scipy and the gripopt package
in .venv). Prints the Markdown table (docs/benchmarks.md) and writes OUT/table.md,
OUT/results.json.
"""
import argparse
import concurrent.futures
import csv
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PYMOO_ALGORITHMS = ("NSGA-II", "SMS-EMOA", "NSGA-III")


def seeds_of(text):
    a, _, b = text.partition("-")
    return list(range(int(a), int(b or a) + 1))


def history(folder):
    with open(os.path.join(folder, "history.csv")) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def gripopt_run(binary, problem, folder, seed, pop, generations):
    """One gripopt run (reused when finished with these settings): the hypervolumes by
    evaluations, {evaluations: (front, found)}."""
    info_path = os.path.join(folder, "run.json")
    done = False
    if os.path.exists(info_path):
        info = json.load(open(info_path))
        s = info["settings"]
        done = (info["status"] == "finished" and info["completed_generations"] == generations
                and s["seed"] == seed and s["pop_size"] == pop)
    if not done:
        if os.path.exists(folder):
            sys.exit(f"{folder}: holds another run; remove it or give another OUT")
        cmd = [binary, "optimise", problem, "--out", folder, "--pop", str(pop), "--generations", str(generations),
               "--seed", str(seed), "--record", "none", "--threads", "1"]
        subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    out = {}
    for row in history(folder):
        # pareto.csv's hypervolume; before issue 42 pareto.csv was the population's front
        front = row.get("pareto_hypervolume") or row["hypervolume"]
        out[int(row["evaluations"])] = (float(front), float(row["archive_hypervolume"]))
    return out


def normalisation(folder):
    s = json.load(open(os.path.join(folder, "run.json")))["settings"]
    return s["hv_ideal"], s["hv_ref"]


def pymoo_run(name, problem_path, seed, pop, budget, ideal, ref, result_path):
    """One pymoo run to `budget` evaluations, its hypervolumes after every generation (in a
    worker process, one evaluation thread)."""
    if os.path.exists(result_path):
        return {int(k): tuple(v) for k, v in json.load(open(result_path)).items()}
    import numpy as np
    import moocore
    import gripopt
    from gripopt.pymoo import GripperProblem
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.algorithms.moo.nsga3 import NSGA3
    from pymoo.algorithms.moo.sms import SMSEMOA
    from pymoo.core.callback import Callback
    from pymoo.optimize import minimize
    from pymoo.util.ref_dirs import get_reference_directions

    ideal, ref = np.asarray(ideal), np.asarray(ref)

    def hv(F):
        if len(F) == 0:
            return 0.0
        P = (np.asarray(F) - ideal) / (ref - ideal)
        P = P[np.all(P < 1.0, axis=1)]
        return float(moocore.hypervolume(P, ref=np.ones(len(ideal)))) if len(P) else 0.0

    class Record(Callback):
        """The hypervolume of the population's feasible front and of every feasible
        non-dominated design evaluated so far, after each generation."""

        def __init__(self):
            super().__init__()
            self.found = np.empty((0, len(ideal)))
            self.out = {}

        def notify(self, algorithm):
            off = algorithm.off if algorithm.off is not None else algorithm.pop
            F, cv = off.get("F"), off.get("CV")[:, 0]
            both = np.vstack([self.found, F[cv <= 0.0]])
            self.found = both[moocore.is_nondominated(both)] if len(both) else both
            pop = algorithm.pop
            feasible = pop.get("F")[pop.get("CV")[:, 0] <= 0.0]
            front = feasible[moocore.is_nondominated(feasible)] if len(feasible) else feasible
            self.out[algorithm.evaluator.n_eval] = (hv(front), hv(self.found))

    if name == "NSGA-II":
        algorithm = NSGA2(pop_size=pop)
    elif name == "SMS-EMOA":
        algorithm = SMSEMOA(pop_size=pop)
    else:
        # 84 Das–Dennis directions in 4 objectives (6 partitions), the population rounded up
        algorithm = NSGA3(ref_dirs=get_reference_directions("das-dennis", len(ideal), n_partitions=6), pop_size=pop)
    problem = GripperProblem(gripopt.Problem.load(problem_path), threads=1)
    record = Record()
    minimize(problem, algorithm, ("n_eval", budget), seed=seed, callback=record, verbose=False)
    with open(result_path, "w") as f:
        json.dump(record.out, f)
    return record.out


def at(series, evaluations):
    """The values of the first generation that reached `evaluations`."""
    k = min((e for e in series if e >= evaluations), default=None)
    if k is None:
        sys.exit(f"no generation reached {evaluations} evaluations")
    return series[k]


def check_black_box(folder, problem_path):
    """The designs of gripopt's pareto.csv, evaluated through gripopt.pymoo, have the
    objectives the run recorded (the same black box)."""
    import numpy as np
    import pandas as pd
    import gripopt
    from gripopt.pymoo import GripperProblem

    front = pd.read_csv(os.path.join(folder, "pareto.csv"), comment="#").head(5)
    x = front[["l21", "b", "t22", "r", "p", "psi_deg"]].to_numpy()
    out = {}
    GripperProblem(gripopt.Problem.load(problem_path), threads=1)._evaluate(x, out)
    want = np.c_[-front.max_offset.fillna(0.0), front.alpha, -front.mean_force, front.t_stab]
    form_closed = front.form_closed.to_numpy(dtype=bool)
    got = out["F"]
    if not np.allclose(got[form_closed], want[form_closed], rtol=1e-12, atol=0.0):
        sys.exit(f"gripopt.pymoo's objectives differ from {folder}/pareto.csv's:\n{got}\n{want}")


def mann_whitney(a, b):
    from scipy.stats import mannwhitneyu

    return float(mannwhitneyu(a, b, alternative="two-sided").pvalue)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("binary")
    ap.add_argument("out")
    ap.add_argument("--baseline", help="a second gripopt binary, e.g. the commit before issue 42")
    ap.add_argument("--baseline-label", default="gripopt 64f5714 (NSGA-II)")
    ap.add_argument("--label", default="gripopt (default)")
    ap.add_argument("--problem", default="problems/bottle-1l.toml")
    ap.add_argument("--seeds", default="1-11")
    ap.add_argument("--budgets", default="1500,6000")
    ap.add_argument("--pop", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--algorithms", default=",".join(PYMOO_ALGORITHMS))
    a = ap.parse_args()
    seeds, budgets = seeds_of(a.seeds), [int(b) for b in a.budgets.split(",")]
    problem = os.path.abspath(a.problem)
    generations = -(-max(budgets) // a.pop)
    os.makedirs(a.out, exist_ok=True)
    binaries = [(a.label, os.path.abspath(a.binary))]
    if a.baseline:
        binaries.append((a.baseline_label, os.path.abspath(a.baseline)))
    series = {}
    with concurrent.futures.ProcessPoolExecutor(a.jobs) as pool:
        jobs = {}
        for k, (label, binary) in enumerate(binaries):
            for s in seeds:
                folder = os.path.join(os.path.abspath(a.out), f"gripopt-{k}", f"s{s}")
                os.makedirs(os.path.dirname(folder), exist_ok=True)
                jobs[pool.submit(gripopt_run, binary, problem, folder, s, a.pop, generations)] = (label, s)
        for j in concurrent.futures.as_completed(jobs):
            series[jobs[j]] = j.result()
        first = os.path.join(os.path.abspath(a.out), "gripopt-0", f"s{seeds[0]}")
        ideal, ref = normalisation(first)
        check_black_box(first, problem)
        jobs = {}
        names = [n for n in a.algorithms.split(",") if n]
        for name in names:
            for s in seeds:
                path = os.path.join(os.path.abspath(a.out), f"pymoo-{name}-s{s}.json")
                job = pool.submit(pymoo_run, name, problem, s, a.pop, max(budgets), ideal, ref, path)
                jobs[job] = (f"pymoo {name}", s)
        for j in concurrent.futures.as_completed(jobs):
            series[jobs[j]] = j.result()
    labels = [b[0] for b in binaries] + [f"pymoo {n}" for n in names]
    results = {}
    lines = []
    for budget in budgets:
        lines.append(f"\n{budget} evaluations (population {a.pop}, seeds {a.seeds}):\n")
        lines.append("| algorithm | front: median [min, max] | p vs first | found: median [min, max] | p vs first |")
        lines.append("|---|---|---|---|---|")
        values = {lb: [at(series[(lb, s)], budget) for s in seeds] for lb in labels}
        results[budget] = {lb: {"front": [v[0] for v in vs], "found": [v[1] for v in vs]} for lb, vs in values.items()}
        base = results[budget][labels[0]]
        for lb in labels:
            cells = []
            for kind in ("front", "found"):
                v = results[budget][lb][kind]
                cells.append(f"{statistics.median(v):.4f} [{min(v):.4f}, {max(v):.4f}]")
                cells.append("—" if lb == labels[0] else f"{mann_whitney(base[kind], v):.2g}")
            lines.append(f"| {lb} | " + " | ".join(cells) + " |")
    text = "\n".join(lines).lstrip("\n") + "\n"
    print(text)
    with open(os.path.join(a.out, "table.md"), "w") as f:
        f.write(text)
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump({str(k): v for k, v in results.items()}, f, indent=1)


if __name__ == "__main__":
    main()
