#!/usr/bin/env bash
# The robust-design study of docs/robust.md (issue 22), step by step into results/robust-study/
# (git-ignored). Usage: scripts/robust_study.sh [STEP...] (no argument = all, in order):
#   robust   `make kitchen`'s run: problems/kitchen.toml, pop 40 x 15 generations, seed 1
#   nominal  the same problem without [robust] (the 1 l bottle, nominal inputs, free scene)
#   survive  the nominal front evaluated robustly: on problems/kitchen.toml (four objects) and
#            on the 1 l bottle alone with the same uncertainty: how many survive
#   price    the robust front's designs at the nominal inputs (price.csv)
#   verify   `gripopt verify` of the robust run: its front on a fresh, larger draw
#   sweeps   the free-scene verdict of the nominal design and of a robust front design
#            against phalanx friction (mu_scale), rod radius (hand.w) and object offset (x_off)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${GRIPOPT:-target/release/gripopt}
R=results/robust-study
T=${THREADS:-}
TH=${T:+--threads $T}
mkdir -p "$R"
sed '/^\[robust\]/,$d' problems/kitchen.toml | sed 's/^name = "kitchen"/name = "kitchen-nominal"/' > "$R/nominal.toml"

robust() { rm -rf "$R/kitchen"; "$B" optimise problems/kitchen.toml --out "$R/kitchen" --pop 40 --generations 15 --seed 1 $TH --record none; }
nominal() { rm -rf "$R/nominal"; "$B" optimise "$R/nominal.toml" --out "$R/nominal" --pop 40 --generations 15 --seed 1 $TH --record none; }
survive_with() { # $1: problem file, $2: output CSV
  echo "id,feasible,failed_stage,cause,scenarios_run,per_object_meets_p_min" > "$2"
  grep -v '^#' "$R/nominal/pareto.csv" | tail -n +2 | cut -d, -f1,8-13 | while IFS=, read -r id l21 b t22 r p psi; do
    "$B" evaluate "$1" --json --design "l21=$l21,b=$b,t22=$t22,r=$r,p=$p,psi_deg=$psi" |
      python3 -c "import json,sys; r=json.load(sys.stdin); rb=r['robust']; print(','.join(map(str,[$id, r['feasible'], r['failed_stage'], r['cause'], rb['scenarios_run'], ' '.join(o['name']+'='+str(o['meets_p_min']) for o in rb['objects'])])))" >> "$2"
  done
  echo "$1: nominal front designs feasible robustly: $(grep -c ',True,' "$2") of $(($(wc -l < "$2") - 1))"
}
survive() {
  # the kitchen problem, and the same uncertainty on the 1 l bottle alone
  python3 -c "
import re,sys
t=open('problems/kitchen.toml').read()
blocks=t.split('[[robust.objects]]')
keep=[b for b in blocks[1:] if 'name = \"bottle-full\"' in b]
rest=blocks[-1][blocks[-1].index('[robust.uncertainty]'):]
keep[0]=keep[0] if '[robust.uncertainty]' not in keep[0] else keep[0][:keep[0].index('[robust.uncertainty]')]
print(blocks[0]+'[[robust.objects]]'+keep[0]+rest, end='')" | sed 's/^name = "kitchen"/name = "kitchen-bottle"/' > "$R/bottle-robust.toml"
  survive_with problems/kitchen.toml "$R/survive.csv"
  survive_with "$R/bottle-robust.toml" "$R/survive-bottle.csv"
}
price() { # the robust front's designs evaluated at the nominal inputs (the 1 l bottle alone)
  echo "id,feasible,max_offset,alpha,mean_force,t_stab" > "$R/price.csv"
  grep -v '^#' "$R/kitchen/pareto.csv" | tail -n +2 | cut -d, -f1,8-13 | while IFS=, read -r id l21 b t22 r p psi; do
    "$B" evaluate "$R/nominal.toml" --json --design "l21=$l21,b=$b,t22=$t22,r=$r,p=$p,psi_deg=$psi" |
      python3 -c "import json,sys; r=json.load(sys.stdin); print(','.join(map(str,[$id, r['feasible'], r['max_offset'], r['alpha'], r['mean_force'], r['t_stab']])))" >> "$R/price.csv"
  done
}
verify() { "$B" verify "$R/kitchen" $TH; }
sweeps() {
  local best
  best=$(grep -v '^#' "$R/kitchen/pareto.csv" | tail -n +2 | sort -t, -k19 -g -r | head -1 | cut -d, -f8-13 | awk -F, '{printf "l21=%s,b=%s,t22=%s,r=%s,p=%s,psi_deg=%s", $1,$2,$3,$4,$5,$6}')
  for who in nominal robust; do
    local d=""; [ "$who" = robust ] && d="--design $best"
    "$B" sweep "$R/nominal.toml" $d --vary mu_scale=0:1.5:31 --bisect mu_scale --y free_scene.object_max_displacement --out "$R/sweep-$who-mu" $TH
    "$B" sweep "$R/nominal.toml" $d --vary hand.w=0.003:0.007:17 --bisect hand.w --y free_scene.object_max_displacement --out "$R/sweep-$who-w" $TH
    "$B" sweep "$R/nominal.toml" $d --vary scene.x_off=0:0.006:25 --bisect scene.x_off --y free_scene.object_max_displacement --out "$R/sweep-$who-xoff" $TH
  done
  echo "robust front design swept: $best"
}
steps=${*:-robust nominal survive price verify sweeps}
for s in $steps; do echo "== $s"; $s; done
