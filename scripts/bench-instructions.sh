#!/usr/bin/env bash
# Instruction counts of the simulator (valgrind's callgrind: deterministic, so repeatable on
# a noisy machine; see docs/benchmarks.md "Simulator speed (issue 23)"):
#   * the nominal centred grasp and the nominal free scene to t_obs: one
#     `gripopt simulate PROBLEM --scene free --json`, which runs both (the centred grasp in
#     diagnostic mode without recording, as stage 3 runs it); each is the inclusive count of
#     its simulation function (CENTRED_FN, FREE_FN), so parsing and stages 0-2 are left out;
#   * a one-thread `gripopt optimise PROBLEM --pop 128 --generations 10 --seed 1` with recording
#     on: the whole process, every thread.
# Usage: scripts/bench-instructions.sh   (`make bench-instructions`; BIN, PROBLEM, POP,
# GENERATIONS, AUTO_RTOL override; SKIP_OPTIMISE=1 leaves the optimisation out.) Writes its callgrind
# files to target/bench-instructions/.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-target/release/gripopt}
PROBLEM=${PROBLEM:-problems/bottle-1l.toml}
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

valgrind --tool=callgrind --callgrind-out-file="$OUT/simulate-free.cg" "$BIN" simulate "$PROBLEM" --scene free --json \
    > "$OUT/simulate-free.json" 2> "$OUT/simulate-free.log"
centred=$(inclusive "$OUT/simulate-free.cg" "$CENTRED_FN")
free=$(inclusive "$OUT/simulate-free.cg" "$FREE_FN")
printf '%-58s %14s\n' "instructions (callgrind, $BIN)" "count"
printf '%-58s %14s\n' "nominal centred grasp ($CENTRED_FN)" "$(mega "$centred")"
printf '%-58s %14s\n' "nominal free scene to t_obs ($FREE_FN)" "$(mega "$free")"
# the same with the stiffness-switching method at the tolerances where it is at least as
# accurate as RADAU5 at the default 1e-6 / 1e-9 over the work-precision ensemble
# (docs/benchmarks.md, "Stiffness switching"): a copy of the problem whose [solver] says
# method = "auto", rtol = AUTO_RTOL, atol = 1e-3 AUTO_RTOL
auto_problem="$OUT/problem-auto.toml"
awk -v rtol="$AUTO_RTOL" '
    /^\[/ { solver = ($0 ~ /^\[solver\]/) }
    solver && /^(rtol|atol|method) *=/ { next }
    { print }
    /^\[solver\]/ { printf "method = \"auto\"\nrtol = %s\natol = %g\n", rtol, rtol * 1e-3 }' "$PROBLEM" > "$auto_problem"
valgrind --tool=callgrind --callgrind-out-file="$OUT/simulate-free-auto.cg" "$BIN" simulate "$auto_problem" --scene free \
    --json > "$OUT/simulate-free-auto.json" 2> "$OUT/simulate-free-auto.log"
printf '%-58s %14s\n' "  method auto, rtol $AUTO_RTOL: nominal centred grasp" "$(mega "$(inclusive "$OUT/simulate-free-auto.cg" "$CENTRED_FN")")"
printf '%-58s %14s\n' "  method auto, rtol $AUTO_RTOL: nominal free scene" "$(mega "$(inclusive "$OUT/simulate-free-auto.cg" "$FREE_FN")")"
if [ "${SKIP_OPTIMISE:-0}" != 1 ]; then
    run=$(mktemp -d)
    valgrind --tool=callgrind --callgrind-out-file="$OUT/optimise.cg" "$BIN" optimise "$PROBLEM" --out "$run/run" \
        --pop "$POP" --generations "$GENERATIONS" --seed 1 --threads 1 > "$OUT/optimise.log" 2>&1
    rm -rf "$run"
    printf '%-58s %14s\n' "optimise --pop $POP --generations $GENERATIONS, one thread (whole process)" "$(mega "$(total "$OUT/optimise.cg")")"
fi
