#!/usr/bin/env python3
"""Compare two gripopt binaries on the same designs: how far did the outputs move?

Runs `BIN simulate PROBLEM --scene free --design D --json` with both binaries for every
design of a designs CSV (one `--design` argument per row, column `design`; `gripopt bench
work-precision --sample N` writes the ensemble's as
results/bench/work_precision_ensemble_designs.csv). That one command gives the centred
scene's stage-3 outputs (t_stab, E_cyl, ... in diagnostic mode, no recording) and the free
scene's (max displacement of the object, ...). Prints, per output, the largest and the median
relative change |new - old| / |old| over the designs, and every design whose verdict
(outcome, feasibility, the free scene's flags) differs.

    tools/compare_baseline.py --old /path/to/gripopt-old --new target/release/gripopt \\
        --designs results/bench/work_precision_ensemble_designs.csv [--problem P] [--jobs 2]
"""
import argparse
import concurrent.futures
import csv
import json
import statistics
import subprocess
import sys

NUMERIC = [
    "t_stab",
    "e_cyl",
    "t_first_contact",
    "v_impact",
    "f_stab_1",
    "f_stab_2",
    "min_force_margin",
    "object_max_displacement",
    "object_max_tilt_deg",
    "object_final_displacement",
    "object_peak_e_trans",
    "object_peak_e_rot",
    "first_contact_t",
]
VERDICT = ["outcome", "feasible", "failed_stage", "moved", "toppled", "escaped", "rim_contact", "free_end"]


# the free scene's keys of issue 21's record (under "free_scene") by their flat names of 5d2a08e
FREE_RENAMED = {"end": "free_end", "t_first_contact": "first_contact_t"}


def flat(record):
    """The outputs under the flat names of 5d2a08e's `simulate --scene free --json`: since
    issue 21 the free scene's outputs are the sub-record "free_scene" (the top level is the
    centred grasp's, as before)."""
    free = record.pop("free_scene", None)
    if isinstance(free, dict):
        for k, v in free.items():
            record.setdefault(FREE_RENAMED.get(k, k), v)
    return record


def run(binary, problem, design):
    cmd = [binary, "simulate", problem, "--scene", "free", "--design", design, "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return {"error": f"exit {p.returncode}: {p.stderr.strip()[-300:]}"}
    return flat(json.loads(p.stdout))


def rel(new, old):
    if new is None or old is None:
        return None if new is None and old is None else float("inf")
    if old == new:
        return 0.0
    return abs(new - old) / abs(old) if old != 0 else float("inf")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="baseline binary")
    ap.add_argument("--new", default="target/release/gripopt", help="binary under test")
    ap.add_argument("--designs", default="results/bench/work_precision_ensemble_designs.csv")
    ap.add_argument("--problem", default="problems/bottle-1l.toml")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", help="also write the per-design figures here")
    a = ap.parse_args()
    with open(a.designs, newline="") as f:
        designs = [row["design"] for row in csv.DictReader(f)]
    if not designs:
        sys.exit(f"{a.designs}: no designs")
    jobs = [(b, d) for d in designs for b in (a.old, a.new)]
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        results = list(ex.map(lambda j: run(j[0], a.problem, j[1]), jobs))
    changes = {k: [] for k in NUMERIC}
    differing, errors, rows, compared = [], [], [], set()
    for i, d in enumerate(designs):
        old, new = results[2 * i], results[2 * i + 1]
        if "error" in old or "error" in new:
            errors.append((d, old.get("error"), new.get("error")))
            continue
        row = {"design": d}
        for k in NUMERIC:
            if k not in old or k not in new:
                continue  # an output one of the binaries does not write
            r = rel(new[k], old[k])
            row[k] = r
            if r is not None:
                changes[k].append(r)
        # a verdict either binary does not write (5d2a08e has no "feasible") is not compared
        diff = [k for k in VERDICT if k in old and k in new and old[k] != new[k]]
        compared.update(k for k in VERDICT if k in old and k in new)
        if diff:
            differing.append((d, {k: (old.get(k), new.get(k)) for k in diff}))
        rows.append(row)
    print(f"{len(designs)} designs; old {a.old}; new {a.new}")
    print(f"{'output':<28} {'designs':>7} {'max rel. change':>16} {'median':>10}")
    for k in NUMERIC:
        v = changes[k]
        if v:
            print(f"{k:<28} {len(v):>7} {max(v):>16.3e} {statistics.median(v):>10.2e}")
    print(f"verdicts differing: {len(differing)} (compared: {', '.join(k for k in VERDICT if k in compared)})")
    for d, diff in differing:
        print(f"  {d}: {diff}")
    for d, eo, en in errors:
        print(f"  error on {d}: old {eo} new {en}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"designs": rows, "differing": differing, "errors": errors}, f, indent=1)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
