#!/usr/bin/env bash
# Cost of a robust evaluation (docs/robust.md, "Cost"): designs of problems/kitchen.toml
# evaluated one after the other on one core (`gripopt evaluate --json`, one process per
# design, its CPU seconds user + sys by /usr/bin/time: on a shared box less
# inflated by other load than wall time) for K = 1, 8, 32 scenarios per object, with and without early stop. Designs: the
# front of the robust study's run (results/robust-study/kitchen, the good case: every
# scenario runs) and 40 random designs of the bounds (python's random, seed 1: what a first
# generation looks like). FRONT=N takes the front's first N designs (default 12: K = 32 on
# all 40 takes ~10 minutes on this box). Prints per set, K and early stop: designs, CPU seconds per
# design, scenarios run and saved, right-hand sides (centred, free) per design.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${GRIPOPT:-target/release/gripopt}
R=results/robust-study/cost
mkdir -p "$R"
grep -v '^#' results/robust-study/kitchen/pareto.csv | tail -n +2 | cut -d, -f8-13 | head -n "${FRONT:-12}" > "$R/front.txt"
python3 -c "
import random
random.seed(1)
lo=[0.030,0.045,0.015,0.2,0.2,90.0]; hi=[0.070,0.080,0.060,1.0,1.5,160.0]
for _ in range(40): print(','.join(repr(a+random.random()*(b-a)) for a,b in zip(lo,hi)))" > "$R/random.txt"
echo "set,K,early_stop,designs,cpu_s_per_design,scenarios_run,scenarios_saved,rhs_centred_per_design,rhs_free_per_design"
for set in front random; do
  for K in 1 8 32; do
    for es in true false; do
      f="$R/kitchen-$K-$es.toml"
      sed -e "s/^scenarios = 8 /scenarios = $K /" -e "s/^early_stop = true /early_stop = $es /" problems/kitchen.toml > "$f"
      rm -f "$R/cpu.txt"
      while IFS=, read -r l21 b t22 r p psi; do
        /usr/bin/time -a -o "$R/cpu.txt" -f "%U %S" taskset -c 0 "$B" evaluate "$f" --json --design "l21=$l21,b=$b,t22=$t22,r=$r,p=$p,psi_deg=$psi"
      done < "$R/$set.txt" > "$R/$set-$K-$es.jsonl"
      cpu=$(awk '{s += $1 + $2} END {print s}' "$R/cpu.txt")
      python3 - "$R/$set-$K-$es.jsonl" "$set" "$K" "$es" 0 "$cpu" <<'PY'
import json, sys
path, s, K, es, t0, t1 = sys.argv[1:]
dec = json.JSONDecoder(); text = open(path).read(); i = 0; recs = []
while i < len(text):
    while i < len(text) and text[i].isspace(): i += 1
    if i >= len(text): break
    r, i = dec.raw_decode(text, i); recs.append(r)
n = len(recs); rb = [r['robust'] for r in recs]
run = sum(x['scenarios_run'] for x in rb); saved = sum(x['scenarios_saved'] for x in rb)
rc = sum(x['rhs_evals'][0] for x in rb) / n; rf = sum(x['rhs_evals'][1] for x in rb) / n
print(f"{s},{K},{es},{n},{(float(t1)-float(t0))/n:.4f},{run},{saved},{rc:.0f},{rf:.0f}")
PY
    done
  done
done
