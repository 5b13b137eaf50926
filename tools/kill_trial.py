#!/usr/bin/env python3
"""Kill -9 trial of run folders (issue 24): kill `gripopt optimise` (and, in every other
trial, the `gripopt resume` that follows) at chosen moments, then finish the run the way
docs/cli.md tells a user to, and compare its outputs byte for byte with an uninterrupted run.

    tools/kill_trial.py BIN [--trials 30] [--problem problems/bottle-1l.toml] [--pop 32]
                            [--generations 12] [--seed 5] [--work DIR] [--first-ms 100]

The first third of the trials kill inside the first `--first-ms` milliseconds (folder
creation, the first run.json, the first generation); the others at moments spread over the
whole run; every other trial kills the `resume` that follows too. The last line tallies the
processes actually killed (one that ended before its moment is not counted). A trial
passes when the finished folder's pareto.csv, population.csv, archive.csv and history.csv
equal the reference run's byte for byte, its recording index lists the reference's shards
(generation, file, id range, designs: every design exactly once, every shard present), and
run.json's status, completed generations and evaluations are the reference's.
Exit status: 0 when every trial passes, 1 otherwise. Prints one line per trial.
"""

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

COMPARED = ["pareto.csv", "population.csv", "archive.csv", "history.csv"]


def run_args(bin_, problem, out, a):
    return [bin_, "optimise", problem, "--out", str(out), "--pop", str(a.pop), "--generations", str(a.generations),
            "--seed", str(a.seed), "--threads", "2"]


def start_and_kill(cmd, delay_s):
    """Start `cmd`, SIGKILL it after `delay_s` seconds (if it is still running); its exit code."""
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        p.wait(timeout=delay_s)
    except subprocess.TimeoutExpired:
        p.send_signal(signal.SIGKILL)
        p.wait()
    return p.returncode


def finish(bin_, problem, out, a, kill_resume_after=None):
    """Finish a killed run as docs/cli.md says: `resume`; a run stopped before its first
    checkpoint has nothing to resume and `optimise` reuses its folder. Returns a log of steps."""
    steps = []
    for _ in range(6):
        if kill_resume_after is not None:
            rc = start_and_kill([bin_, "resume", str(out)], kill_resume_after)
            steps.append(f"resume killed after {kill_resume_after * 1e3:.0f} ms (rc {rc})")
            kill_resume_after = None
            continue
        r = subprocess.run([bin_, "resume", str(out)], capture_output=True, text=True)
        steps.append(f"resume rc {r.returncode}")
        if r.returncode == 0:
            return steps, True
        if "nothing to resume" in r.stderr:
            o = subprocess.run(run_args(bin_, problem, out, a), capture_output=True, text=True)
            steps.append(f"optimise again rc {o.returncode}")
            if o.returncode == 0:
                return steps, True
            steps.append(o.stderr.strip().splitlines()[-1] if o.stderr.strip() else "")
            return steps, False
        steps.append(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else "")
        return steps, False
    return steps, False


def index_entries(folder):
    """The recording index's shards as (generation, file, first id, last id, designs), and
    whether each listed shard exists; None without an index."""
    idx = folder / "recording" / "index.jsonl"
    if not idx.exists():
        return None
    entries = []
    for line in idx.read_text().splitlines():
        if line.strip():
            v = json.loads(line)
            present = (folder / "recording" / v["file"]).is_file()
            entries.append((v["generation"], v["file"], v["first_id"], v["last_id"], v["designs"], present))
    return sorted(entries)


def run_totals(folder):
    """run.json's status, completed generations and evaluations."""
    try:
        v = json.loads((folder / "run.json").read_text())
    except (OSError, ValueError):
        return None
    return v.get("status"), v.get("completed_generations"), v.get("evaluations")


def compare(ref, got):
    """What differs between the finished folder `got` and the reference run: the CSVs byte
    for byte, the recording index (every design exactly once, every shard present), run.json's
    totals."""
    diffs = [f for f in COMPARED if (ref / f).read_bytes() != ((got / f).read_bytes() if (got / f).exists() else b"")]
    ri, gi = index_entries(ref), index_entries(got)
    if ri != gi:
        diffs.append(f"recording index ({len(gi or [])} shards, reference {len(ri or [])})")
    if gi:
        ids = [i for e in gi for i in range(e[2], e[3] + 1)]
        if len(ids) != len(set(ids)) or not all(e[5] for e in gi):
            diffs.append("recording index: a design twice or a shard missing")
    if run_totals(ref) != run_totals(got):
        diffs.append(f"run.json {run_totals(got)} (reference {run_totals(ref)})")
    return diffs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bin")
    ap.add_argument("--trials", type=int, default=30)
    ap.add_argument("--problem", default="problems/bottle-1l.toml")
    ap.add_argument("--pop", type=int, default=32)
    ap.add_argument("--generations", type=int, default=12)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--work", default="target/kill-trial")
    ap.add_argument("--first-ms", type=float, default=100.0)
    ap.add_argument("--rng", type=int, default=1, help="seed of the kill moments")
    a = ap.parse_args()
    bin_ = os.path.abspath(a.bin)
    work = Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    ref = work / "reference"
    t0 = time.monotonic()
    r = subprocess.run(run_args(bin_, a.problem, ref, a), capture_output=True, text=True)
    t_run = time.monotonic() - t0
    if r.returncode != 0:
        print(f"reference run failed (rc {r.returncode}): {r.stderr.strip()}")
        return 1
    print(f"reference run: {t_run:.2f} s")
    rng = random.Random(a.rng)
    early = max(1, a.trials // 3)
    failed = 0
    kills = {"optimise": 0, "first": 0, "resume": 0}
    for i in range(a.trials):
        d = rng.uniform(0.0, a.first_ms / 1e3) if i < early else rng.uniform(0.0, 0.95 * t_run)
        kill_resume = rng.uniform(0.0, 0.6 * t_run) if i % 2 == 1 else None
        out = work / f"trial-{i:02d}"
        rc = start_and_kill(run_args(bin_, a.problem, out, a), d)
        kills["optimise"] += rc == -signal.SIGKILL
        kills["first"] += rc == -signal.SIGKILL and d < a.first_ms / 1e3
        steps, ok = finish(bin_, a.problem, out, a, kill_resume)
        kills["resume"] += any("resume killed" in s and "(rc -9)" in s for s in steps)
        diffs = compare(ref, out) if ok else ["not finished"]
        status = "ok  " if not diffs else "FAIL"
        failed += bool(diffs)
        print(f"{status} trial {i:2d}: optimise killed after {d * 1e3:7.1f} ms (rc {rc}); {'; '.join(steps)}"
              + (f"; differs: {', '.join(diffs)}" if diffs else ""))
    print(f"kill trial: {a.trials - failed} passed, {failed} failed; processes killed by SIGKILL: "
          f"{kills['optimise']} optimise ({kills['first']} within the first {a.first_ms:.0f} ms), "
          f"{kills['resume']} resume (a process that had ended before its moment is not counted)")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
