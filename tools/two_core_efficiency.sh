#!/usr/bin/env bash
# Parallel efficiency of a default run on two cores, as issue 15 defines it, with the
# 1-core time taken on ONE core (the background persister included):
#   T1 = taskset -c 0   gripopt optimise … --threads 1
#   T2 = taskset -c 0,1 gripopt optimise … --threads 2
#   Tind = two independent 1-thread runs at once, one per core (the machine's own ceiling)
# Repetitions are interleaved; prints min / median of each and the efficiencies.
# Usage: tools/two_core_efficiency.sh [BIN] [REPS] [extra optimise flags, e.g. --record none]
set -euo pipefail
BIN=${1:-target/release/gripopt}; REPS=${2:-7}; shift $(( $# > 2 ? 2 : $# )) || true
EXTRA=("$@")
P=problems/bottle-1l.toml; ARGS=(--pop 128 --generations 10 --seed 1)
D=$(mktemp -d); trap 'rm -rf "$D"' EXIT
now() { date +%s%N; }
run() { rm -rf "$3"; taskset -c "$1" "$BIN" optimise "$P" "${ARGS[@]}" ${EXTRA[@]+"${EXTRA[@]}"} --threads "$2" --out "$3" >/dev/null 2>&1; }
t1=(); t2=(); ti=()
for r in $(seq "$REPS"); do
  s=$(now); run 0 1 "$D/a"; t1+=($(( $(now) - s )))
  s=$(now); run 0,1 2 "$D/b"; t2+=($(( $(now) - s )))
  s=$(now); run 0 1 "$D/c" & run 1 1 "$D/d" & wait; ti+=($(( $(now) - s )))
done
python3 - "${t1[*]}" "${t2[*]}" "${ti[*]}" <<'PY'
import sys, statistics as st
t1, t2, ti = ([int(x) / 1e9 for x in a.split()] for a in sys.argv[1:4])
f = lambda v: f"{min(v):.3f} / {st.median(v):.3f} s"
print(f"T1 (1 core)          {f(t1)}")
print(f"T2 (2 cores)         {f(t2)}")
print(f"Tind (2 runs, 2 cores) {f(ti)}")
e = lambda a, b: (min(a) / (2 * min(b)), st.median(a) / (2 * st.median(b)))
print("efficiency T1/(2 T2)       min %.1f %%  median %.1f %%" % tuple(100 * x for x in e(t1, t2)))
c = (min(t1) / min(ti), st.median(t1) / st.median(ti))
print("machine ceiling T1/Tind     min %.1f %%  median %.1f %%" % tuple(100 * x for x in c))
print("of the ceiling              min %.1f %%  median %.1f %%" % tuple(100 * a / b for a, b in zip(e(t1, t2), c)))
PY
