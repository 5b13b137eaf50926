#!/usr/bin/env bash
# Copy the plots cited in docs/thesis-comparison.md from results/studies/ to docs/figures/
# (row 14's α map is drawn there by `make thesis-checks`).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p docs/figures
for f in fig4_1/slices_verdict fig4_2/slices_verdict fig4_4/slices_verdict fig4_5/slices_max_offset \
         fig4_6/slices_max_offset fig4_7/slices_max_offset fig4_8/map_alpha fig4_8/map_mean_force \
         fig4_8r/line_mean_force_mu_mean_force_0 fig4_9l/line_alpha_mu_alpha_0 fig4_9l/line_mean_force_mu_mean_force_0 \
         fig4_10/slices_mean_force fig4_10/slices_alpha fig4_13/line_e_cyl_e_lim fig4_13s/line_e_cyl_e_lim fig4_13s/line_t_stab \
         fig4_14/slices_verdict fig4_14/slices_t_stab fig4_16/line_e_cyl_e_lim fig4_16/line_t_stab fig4_17/line_e_cyl_e_lim \
         fig4_18/line_e_cyl_e_lim fig4_11/grasp fig4_8r/line_fmu_1_fmu_2 fig4_8r/line_tau_s0 fig4_8r/line_alpha_mu_alpha_0 \
         fig4_13e/line_e_cyl_e_lim; do
  cp "results/studies/$f.svg" "docs/figures/$(echo "$f" | tr / _).svg"
done
echo "copied to docs/figures/"
