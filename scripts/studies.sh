#!/usr/bin/env bash
# The thesis's chapter-4 parameter studies (figs 4.1-4.18) rerun with `gripopt sweep`.
# Usage: scripts/studies.sh [STUDY...]   (no argument = all; e.g. scripts/studies.sh fig4_16)
# Writes results/studies/<study>/ (git-ignored): sweep.csv, SVG plots, boundaries.csv.
# `make studies` runs all; `make figures` also copies the plots cited in
# docs/thesis-comparison.md to docs/figures/; `make thesis-checks` runs the studies of rows 8,
# 12-14, 22, 24 and 25, prints the figures those rows quote and draws row 14's α map
# (scripts/thesis_checks.py). Base: problems/bottle-1l.toml, the thesis's
# nominal design (§4.1.2) and, where the thesis holds it fixed, l_hand = 0.230 m.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${GRIPOPT:-target/release/gripopt}
P=${PROBLEM:-problems/bottle-1l.toml}
R=results/studies
sw() { local name=$1; shift; echo "== $name"; "$B" sweep "$P" "$@" --out "$R/$name"; }
# l11 = LO:HI:N with ψ free (its own --vary psi_deg): `--vary l11` applies the ψ rule, so these
# studies vary p = l11/l21 at the base design's l21 (0.0494 m) instead; sweep.csv's l11 column
# holds the l11 values, the maps' axis is p.
L21=$("$B" evaluate "$P" --static-only --json | sed -n 's/^ *"l21": *\([^,]*\),*$/\1/p')
[ -n "$L21" ] || { echo "studies.sh: no l21 in \`$B evaluate $P --json\`" >&2; exit 2; }
l11_as_p() { awk -v lo="$1" -v hi="$2" -v n="$3" -v l21="$L21" 'BEGIN { printf "p=%.15g:%.15g:%d", lo / l21, hi / l21, n }'; }

fig4_1()  { sw fig4_1  --stage kinematics --vary "$(l11_as_p 0.01 0.08 15)" --vary r=0.2:1.2:11 --vary psi_deg=90:160:8 --color min_margin_deg; }
fig4_2()  { sw fig4_2  --stage kinematics --vary p=0.2:1.6:15 --vary r=0.2:1.2:11 --vary l21=0.03:0.07:5 --psi-rule --hold-l-hand --color min_margin_deg; }
fig4_4()  { sw fig4_4  --stage kinematics --vary b=0.04:0.08:9 --vary l21=0.03:0.07:9 --vary l_hand=0.20:0.40:5 --psi-rule; }
fig4_5()  { sw fig4_5  --stage static --vary "$(l11_as_p 0.01 0.04 7)" --vary r=0.2:1.0:9 --vary psi_deg=100:160:7 --color max_offset; }
fig4_6()  { sw fig4_6  --stage static --vary p=0.2:1.4:7 --vary r=0.2:1.0:9 --vary l21=0.03:0.07:5 --psi-rule --hold-l-hand --color max_offset; }
fig4_7()  { sw fig4_7  --stage static --vary b=0.045:0.08:8 --vary l21=0.03:0.07:9 --vary l_hand=0.20:0.30:3 --psi-rule --color max_offset; }
fig4_8()  { sw fig4_8  --stage static --vary "$(l11_as_p 0.01 0.04 13)" --vary psi_deg=100:160:13 --color alpha --color mean_force --color alpha_0 --color mean_force_0; }
fig4_8r() { sw fig4_8r --stage static --vary r=0.30:0.66:10 --y mean_force_mu+mean_force_0 --y alpha_mu+alpha_0 --y fmu_1+fmu_2 --y tau_s0; }
# row 14: α over (l11, ψ), 1 mm x 1°, l11 up to 60 mm (scripts/thesis_checks.py draws the ψ rule on it)
fig4_8a() { sw fig4_8a --stage static --vary "$(l11_as_p 0.010 0.060 51)" --vary psi_deg=100:150:51 --color alpha_mu --color alpha_0; }
# rows 13-14: α and F̃ along the ψ rule
fig4_8l() { sw fig4_8l --stage static --vary l11=0.010:0.060:51 --y alpha_mu+alpha_0 --y mean_force_mu+mean_force_0; }
fig4_9()  { sw fig4_9  --stage static --vary p=0.2:1.4:7 --vary r=0.2:1.0:9 --vary l21=0.03:0.07:5 --psi-rule --hold-l-hand --color alpha --color mean_force; }
fig4_9l() { sw fig4_9l --stage static --vary l21=0.030:0.060:31 --hold-l-hand --y alpha_mu+alpha_0 --y mean_force_mu+mean_force_0; }
fig4_10() { sw fig4_10 --stage static --vary b=0.045:0.08:8 --vary l21=0.03:0.07:9 --vary l_hand=0.20:0.30:3 --psi-rule --color alpha --color mean_force; }
fig4_11() { mkdir -p "$R/fig4_11"; echo "== fig4_11"; "$B" simulate "$P" --force --csv "$R/fig4_11/trajectory.csv" --plot "$R/fig4_11/grasp.svg" --json > "$R/fig4_11/simulate.json"; }
fig4_13() { sw fig4_13 --stage dynamic --vary l11=0.010:0.080:15 --bisect l11; }
# row 22: E_cyl along the ψ rule in 0.5 mm steps (its peak)
fig4_13e() { sw fig4_13e --stage dynamic --vary l11=0.010:0.064:109 --y e_cyl+e_lim --y v_impact --y m_finger; }
# fig 4.13 at the torque that puts gripopt's nominal at the thesis's impact margin (0.5 N·m x 0.338/0.9)
fig4_13s() { sw fig4_13s --stage dynamic --vary l11=0.010:0.080:29 --vary tau=0.188:0.188:1 --bisect l11; }
fig4_14() { sw fig4_14 --stage dynamic --vary b=0.045:0.08:4 --vary l21=0.03:0.07:5 --vary l_hand=0.20:0.40:5 --psi-rule --color t_stab --color e_cyl; }
fig4_16() { sw fig4_16 --stage dynamic --vary tau=0.05:1.5:30 --bisect tau; }
fig4_17() { sw fig4_17 --stage dynamic --vary density=100:2000:20 --bisect density; }
fig4_18() { sw fig4_18 --stage dynamic --vary grasp_height=0.005:0.195:20 --bisect grasp_height; }
# the impact-energy differences (docs/thesis-comparison.md): onset velocity and effective finger mass against the torque
fig4_16e() { sw fig4_16e --stage dynamic --vary tau=0.05:1.5:30 --y v_impact --y m_finger; }

ALL="fig4_1 fig4_2 fig4_4 fig4_5 fig4_6 fig4_7 fig4_8 fig4_8r fig4_8a fig4_8l fig4_9 fig4_9l fig4_10 fig4_11 fig4_13 fig4_13e fig4_13s fig4_14 fig4_16 fig4_16e fig4_17 fig4_18"
for s in ${@:-$ALL}; do "$s"; done
