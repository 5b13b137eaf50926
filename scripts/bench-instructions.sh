#!/usr/bin/env bash
# Instruction counts of the simulator (valgrind's callgrind: deterministic, so repeatable on
# a noisy machine; see docs/benchmarks.md "Simulator speed (issue 23)"):
#   * the nominal centred grasp and the nominal free scene to t_obs: one
#     `gripopt simulate PROBLEM --scene free --json`, which runs both (the centred grasp in
#     diagnostic mode without recording, as stage 3 runs it); each is the inclusive count of
#     its simulation function (CENTRED_FN, FREE_FN), so parsing and stages 0-2 are left out;
#   * the same two with RADAU5 (a copy of PROBLEM naming `method = "radau5"`: the default before
#     session 38) and with `method = "auto"` at AUTO_RTOL;
#   * the kitchen front design of issue 40: `gripopt evaluate KITCHEN --design KITCHEN_DESIGN
#     --json` (32 scenarios, centred grasp and free scene each), the whole process, and the
#     same with RADAU5;
#   * a one-thread `gripopt optimise PROBLEM --pop 128 --generations 10 --seed 1` with recording
#     on: the whole process, every thread;
#   * the accuracy rule's table (not an instruction count): `gripopt bench accuracy
#     --candidates radau5:1e-6,default` (docs/benchmarks.md, "The accuracy rule"), its
#     reference cached in target/bench-instructions/accuracy (computing it takes minutes).
# Usage: scripts/bench-instructions.sh   (`make bench-instructions`; BIN, PROBLEM, KITCHEN, POP,
# GENERATIONS, AUTO_RTOL override; SKIP_OPTIMISE=1 leaves the optimisation out, SKIP_ACCURACY=1
# the accuracy table.) Writes its callgrind files to target/bench-instructions/.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-target/release/gripopt}
PROBLEM=${PROBLEM:-problems/bottle-1l.toml}
KITCHEN=${KITCHEN:-problems/kitchen.toml}
KITCHEN_DESIGN=l21=0.04304807948252374,b=0.06871978187729287,t22=0.03375918412304188,r=0.2601664030440584,p=0.25261005423197275,psi_deg=135.766034896994
POP=${POP:-128}
GENERATIONS=${GENERATIONS:-10}
AUTO_RTOL=${AUTO_RTOL:-1e-7}
CENTRED_FN=${CENTRED_FN:-gripopt::sim::scene::centred::run}
FREE_FN=${FREE_FN:-gripopt::sim::scene::free::run}
OUT=target/bench-instructions
for tool in valgrind callgrind_annotate; do
    command -v "$tool" > /dev/null || { echo "bench-instructions: $tool not found (make bench-instructions installs valgrind)" >&2; exit 2; }
done
mkdir -p "$OUT"

# the inclusive count of function $2 in callgrind file $1 (its symbol line, not the inlined
# copies); awk reads to the end (an early exit would fail the pipe under pipefail)
inclusive() {
    callgrind_annotate --inclusive=yes "$1" 2> /dev/null | awk -v fn="$2" '
        !found && index($0, ":" fn " [") { gsub(",", "", $1); print $1; found = 1 }'
}
total() {
    callgrind_annotate "$1" 2> /dev/null | awk '!found && /PROGRAM TOTALS/ { gsub(",", "", $1); print $1; found = 1 }'
}
mega() { awk -v n="$1" 'BEGIN { if (n == "") print "?"; else printf "%.2f M", n / 1e6 }'; }

# a copy of problem $1 whose [solver] names method $2 (and, when given, rtol $3 and atol 1e-3·$3)
with_method() {
    awk -v m="$2" -v rtol="${3:-}" '
        /^\[/ { solver = ($0 ~ /^\[solver\]/) }
        solver && /^method *=/ { next }
        solver && rtol != "" && /^(rtol|atol) *=/ { next }
        { print }
        /^\[solver\]/ { printf "method = \"%s\"\n", m; if (rtol != "") printf "rtol = %s\natol = %g\n", rtol, rtol * 1e-3 }' "$1"
}
# callgrind of `BIN simulate $2 --scene free --json` into $OUT/$1.cg; prints its two counts
# under the label $3
simulate_counts() {
    valgrind --tool=callgrind --callgrind-out-file="$OUT/$1.cg" "$BIN" simulate "$2" --scene free --json \
        > "$OUT/$1.json" 2> "$OUT/$1.log"
    printf '%-66s %12s\n' "$3nominal centred grasp" "$(mega "$(inclusive "$OUT/$1.cg" "$CENTRED_FN")")"
    printf '%-66s %12s\n' "$3nominal free scene to t_obs" "$(mega "$(inclusive "$OUT/$1.cg" "$FREE_FN")")"
}
printf '%-66s %12s\n' "instructions (callgrind, $BIN)" "count"
simulate_counts simulate-free "$PROBLEM" "default solver: "
with_method "$PROBLEM" radau5 > "$OUT/problem-radau5.toml"
simulate_counts simulate-free-radau5 "$OUT/problem-radau5.toml" "  RADAU5 (the default before session 38): "
# the stiffness-switching method named, at the tolerances where it is at least as accurate as
# RADAU5 at the default 1e-6 / 1e-9 over the work-precision ensemble (docs/benchmarks.md,
# "Stiffness switching")
with_method "$PROBLEM" auto "$AUTO_RTOL" > "$OUT/problem-auto.toml"
simulate_counts simulate-free-auto "$OUT/problem-auto.toml" "  method auto, rtol $AUTO_RTOL: "
# the kitchen front design: 32 scenarios, the whole process
kitchen_counts() {
    valgrind --tool=callgrind --callgrind-out-file="$OUT/$1.cg" "$BIN" evaluate "$2" --design "$KITCHEN_DESIGN" \
        --json > "$OUT/$1.json" 2> "$OUT/$1.log"
    printf '%-66s %12s\n' "$3" "$(mega "$(total "$OUT/$1.cg")")"
}
kitchen_counts kitchen "$KITCHEN" "kitchen front design, 32 scenarios (whole process)"
with_method "$KITCHEN" radau5 > "$OUT/kitchen-radau5.toml"
kitchen_counts kitchen-radau5 "$OUT/kitchen-radau5.toml" "  the same with RADAU5 as given"
if [ "${SKIP_OPTIMISE:-0}" != 1 ]; then
    run=$(mktemp -d)
    valgrind --tool=callgrind --callgrind-out-file="$OUT/optimise.cg" "$BIN" optimise "$PROBLEM" --out "$run/run" \
        --pop "$POP" --generations "$GENERATIONS" --seed 1 --threads 1 > "$OUT/optimise.log" 2>&1
    rm -rf "$run"
    printf '%-66s %12s\n' "optimise --pop $POP --generations $GENERATIONS, one thread (whole process)" "$(mega "$(total "$OUT/optimise.cg")")"
fi
if [ "${SKIP_ACCURACY:-0}" != 1 ]; then
    echo "accuracy rule (gripopt bench accuracy --candidates radau5:1e-6,default; $OUT/accuracy/accuracy.csv):"
    "$BIN" bench accuracy --candidates radau5:1e-6,default --out "$OUT/accuracy" > "$OUT/accuracy.txt" 2> "$OUT/accuracy.log"
    grep -v '0 differ$' "$OUT/accuracy.txt" | grep -v '0.00e0  p90 0.00e0  max 0.00e0' || true
fi
