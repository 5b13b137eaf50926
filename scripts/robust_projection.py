#!/usr/bin/env python3
"""Projected time of a 100 000-design robust night (docs/robust.md, "Cost").

Reads what scripts/robust_cost.sh wrote (results/robust-study/cost: the front designs'
records at K = 1, 8, 32 without early stop, and its CSV on stdin or as the first argument)
and replays one generation of `pop` front-like designs as the robust evaluator runs it
(src/run/robust_eval.rs): (design, scenario) tasks round by round, each task's cost its
right-hand sides times the CPU seconds per right-hand side fitted on the cost CSV, list
scheduling on P threads (a free worker takes the next task). Prints per K and P the
generation's work, its makespan, the scheduling efficiency and the night's hours, plain
and divided by the machine ceiling that `gripopt bench scaling` measured on the lent
16-core VM (docs/benchmarks.md: n independent 1-thread runs at once, 60 % at 16).
"""
import csv
import heapq
import json
import sys

R = "results/robust-study/cost"
NIGHT = 100_000
CEILING = 0.60


def records(path):
    dec, text, i, out = json.JSONDecoder(), open(path).read(), 0, []
    while i < len(text):
        while i < len(text) and text[i].isspace():
            i += 1
        if i >= len(text):
            break
        r, i = dec.raw_decode(text, i)
        out.append(r)
    return out


def makespan(tasks, p):
    """Greedy list scheduling of `tasks` (in their order) on p workers."""
    free = [0.0] * p
    heapq.heapify(free)
    for t in tasks:
        heapq.heappush(free, heapq.heappop(free) + t)
    return max(free)


def main():
    rows = list(csv.DictReader(open(sys.argv[1]) if len(sys.argv) > 1 else sys.stdin))
    front = [r for r in rows if r["set"] == "front" and r["early_stop"] == "false"]
    # CPU seconds per design = a + b * (right-hand sides per design), least squares
    xs = [float(r["rhs_centred_per_design"]) + float(r["rhs_free_per_design"]) for r in front]
    ys = [float(r["cpu_s_per_design"]) for r in front]
    n, mx, my = len(xs), sum(xs) / len(xs), sum(ys) / len(ys)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
    a = my - b * mx
    print(f"fit over {n} rows: cpu_s/design = {a:.4f} + {b * 1e6:.3f} us x rhs")
    print("K,pop,threads,work_s,makespan_s,sched_eff,night_h,night_h_at_ceiling")
    for k in (1, 8, 32):
        recs = records(f"{R}/front-{k}-false.jsonl")
        pop = 40
        designs = [recs[i % len(recs)] for i in range(pop)]
        # tasks: round by round (scenario k of every object), within a round the designs
        # slowest first (the cost model's aim; exact costs here)
        per = [[(s["rhs_evals"][0] + s["rhs_evals"][1]) * b for s in d["robust"]["scenarios"]] for d in designs]
        rounds = max(len(p) for p in per)
        nobj = len(designs[0]["robust"]["objects"])
        tasks = [max(a, 0.0)] * pop  # the first pass: stages 0-2 of every design
        for rnd in range(0, rounds, nobj):
            batch = [sum(p[rnd:rnd + nobj]) for p in per]  # a design's round: one task per scenario
            for d in sorted(range(pop), key=lambda i: -batch[i]):
                tasks.extend(per[d][rnd:rnd + nobj])
        work = sum(tasks)
        for p in (1, 2, 16, 64):
            m = makespan(tasks, p) if p > 1 else work
            eff = work / (p * m)
            hours = NIGHT / pop * m / 3600
            at_ceiling = hours / CEILING if p > 2 else hours
            print(f"{k},{pop},{p},{work:.2f},{m:.3f},{eff:.3f},{hours:.2f},{at_ceiling:.2f}")


if __name__ == "__main__":
    main()
