#!/usr/bin/env python3
"""The figures of docs/thesis-comparison.md's rows 8, 12-14, 22, 24 and 25, and row 14's map.

Reads the studies' sweep.csv and boundaries.csv (scripts/studies.sh fig4_5 fig4_8a fig4_8l
fig4_8r fig4_13e fig4_16 fig4_16e fig4_17, under results/studies/) and prints, row by row,
the numbers the table quotes. Row 14's map of alpha^mu and alpha^0 over (l11, psi) with the
thesis's psi rule (eq. 4.15) drawn on it is written to DIR/fig4_8a_alpha_psi_rule.svg
(--figures DIR; default results/studies/fig4_8a). Rows 24-25's density factor is computed
here from MODEL.md's definitions (§4 object mass and inertia, §9.1 impact energy), not from
gripopt's code, and checked against the E_cyl and E_lim gripopt reports at every density the
fig4_17 study simulated. Usage (`make thesis-checks` runs the studies first):

    .venv/bin/python scripts/thesis_checks.py [--figures DIR]
"""
import argparse
import math
import os
import sys
import tomllib

import numpy as np
import pandas as pd

R = "results/studies"
PROBLEM = "problems/bottle-1l.toml"


def sweep(study):
    path = f"{R}/{study}/sweep.csv"
    if not os.path.exists(path):
        sys.exit(f"{path} is missing: run scripts/studies.sh {study} first")
    return pd.read_csv(path, comment="#")


def boundaries(study):
    return pd.read_csv(f"{R}/{study}/boundaries.csv", comment="#")


def rule_psi(l11, l21):
    """Thesis eq. 4.15: psi = 140 - 25.6 p, p = l11/l21 (degrees)."""
    return 140.0 - 25.6 * l11 / l21


def row8():
    d = sweep("fig4_5")
    d["mo"] = d.max_offset * 1e3
    print("row 8 (fig4_5): max_offset [mm] against l11 = 10..40 mm in each (r, psi) slice with form closure")
    print("  ('none': stage 1-2 pass but no form closure; '-': discarded at stage 1-2)")
    for (r, psi), g in d.groupby([d.r.round(3), d.psi_deg.round(2)]):
        if not (g.mo >= 0).any():
            continue
        cells = ["-" if v != "pass" else ("none" if math.isnan(m) else f"{m:g}") for v, m in zip(g.verdict, g.mo)]
        changes = "changes with l11" if len(set(cells) - {"-"}) > 1 else "constant"
        print(f"  r {r:.1f} psi {psi:.0f}: {' '.join(cells)}   ({changes})")
    by_l11 = d.groupby(d.l11.round(4)).mo.max()
    print("  best over (r, psi) per l11:", ", ".join(f"{l * 1e3:.0f} mm {m:g}" for l, m in by_l11.items()))


def row12():
    d = sweep("fig4_8r").sort_values("r")
    a, b = d.iloc[0], d.iloc[-1]
    i0 = d.alpha_0.idxmin()
    print(f"row 12 (fig4_8r): r {a.r:.2f} -> {b.r:.2f}")
    print(f"  mean force f^mu {a.mean_force_mu:.3f} -> {b.mean_force_mu:.3f} N "
          f"({100 * (b.mean_force_mu / a.mean_force_mu - 1):+.1f} %); f^0 {a.mean_force_0:.3f} -> {b.mean_force_0:.3f} N")
    print(f"  f^mu_1 {a.fmu_1:.2f} -> {b.fmu_1:.2f} N, f^mu_2 {a.fmu_2:.2f} -> {b.fmu_2:.2f} N, "
          f"tau_s0 {a.tau_s0:.3f} -> {b.tau_s0:.3f} N·m")
    print(f"  alpha^mu {a.alpha_mu:.3f} -> {b.alpha_mu:.3f} (/{a.alpha_mu / b.alpha_mu:.1f}); "
          f"alpha^0 {a.alpha_0:.2f} -> {d.alpha_0[i0]:.4f} (r {d.r[i0]:.2f}) -> {b.alpha_0:.2f}")


def iso_alpha_slope(m, key, l11_mm, psi, half_l=2.0, half_psi=2.5):
    """d psi / d l11 [deg/mm] of the iso-`key` line at (l11_mm, psi): a local quadratic
    least-squares fit over the computed grid points within the window (the map's points
    next to the rule are often discarded, so centred differences are not available)."""
    w = m[m[key].notna() & ((m.l11_mm - l11_mm).abs() <= half_l + 1e-9) & ((m.psi_deg - psi).abs() <= half_psi + 1e-9)]
    if len(w) < 8:
        return float("nan")
    x, y = w.l11_mm - l11_mm, w.psi_deg - psi
    basis = np.c_[np.ones(len(w)), x, y, x * x, y * y, x * y]
    c = np.linalg.lstsq(basis, w[key].values, rcond=None)[0]
    return -c[1] / c[2]


def row14(figures):
    m = sweep("fig4_8a")
    m["l11_mm"] = (m.l11 * 1e3).round(9)
    l21 = m.l21.iloc[0]
    rule_slope = -25.6 / (l21 * 1e3)
    print(f"row 14 (fig4_8a, fig4_8l): alpha over (l11, psi), l21 = {l21} m; the rule's slope {rule_slope:.3f} deg/mm")
    for key in ("alpha_mu", "alpha_0"):
        grid = m.pivot(index="psi_deg", columns="l11_mm", values=key)
        steps = np.diff(grid.values, axis=1)
        rising = int(np.nansum(steps > 0))
        print(f"  {key}: {int(np.sum(~np.isnan(steps)))} steps of 1 mm in l11 at fixed psi, {rising} rising; "
              f"range {m[key].min():.3f}..{m[key].max():.3f}")
        for psi in (110.0, 120.0, 130.0, 140.0):
            row = grid.loc[psi].dropna()
            print(f"    psi {psi:.0f}: {row.iloc[0]:.3f} at {row.index[0]:.0f} mm -> {row.iloc[-1]:.3f} at {row.index[-1]:.0f} mm")
        slopes = [(l, iso_alpha_slope(m, key, l, rule_psi(l * 1e-3, l21))) for l in np.arange(10.0, 60.01, 5.0)]
        print("    iso-alpha slope on the rule [deg/mm]: " + ", ".join(f"{l:.0f} mm {s:.2f}" for l, s in slopes))
    edge = m[m.verdict == "pass"].groupby("l11_mm").psi_deg.max()
    gap = edge - rule_psi(edge.index.values * 1e-3, l21)
    print("  highest non-discarded psi minus the rule's [deg]: "
          + ", ".join(f"{l:.0f} mm {g:+.1f}" for l, g in gap.items() if l % 6 == 0 or l == 27)
          + f"; from 27 mm on at most {gap[gap.index >= 27].abs().max():.2f} deg (the grid step is 1 deg)")
    r = sweep("fig4_8l")
    r = r[r.verdict == "pass"]
    top = r.alpha_mu.idxmax()
    pick = r[(r.l11 * 1e3).round(6).isin([10.0, 30.0, 60.0])]
    print("  along the rule: alpha^mu " + ", ".join(f"{a:.3f} ({l * 1e3:.0f} mm)" for l, a in zip(pick.l11, pick.alpha_mu))
          + f"; max {r.alpha_mu[top]:.3f} at {r.l11[top] * 1e3:.0f} mm; alpha^0 {r.alpha_0.min():.3f}..{r.alpha_0.max():.3f}")
    print(f"  row 13, along the rule: F^mu {r.mean_force_mu.min():.3f}..{r.mean_force_mu.max():.3f} N, "
          f"F^0 {r.mean_force_0.min():.2f}..{r.mean_force_0.max():.2f} N")
    draw_alpha_map(m, l21, figures)


def draw_alpha_map(m, l21, figures):
    import matplotlib

    matplotlib.use("svg")
    import matplotlib.pyplot as plt

    matplotlib.rcParams["svg.hashsalt"] = "gripopt-fig4_8a"
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), sharey=True)
    rule_l = np.linspace(m.l11_mm.min(), m.l11_mm.max(), 50)
    for ax, key, name in zip(axes, ("alpha_mu", "alpha_0"), (r"$\alpha^\mu$ (from $f^\mu$, the default)", r"$\alpha^0$ (from $f^0$)")):
        grid = m.pivot(index="psi_deg", columns="l11_mm", values=key)
        x, y, z = grid.columns.values, grid.index.values, grid.values
        ax.set_facecolor("#d9d9d9")
        mesh = ax.pcolormesh(x, y, z, shading="nearest", cmap="viridis", vmin=0.0, vmax=2.0, rasterized=True)
        lines = ax.contour(x, y, z, levels=np.arange(0.1, 2.01, 0.1), colors="white", linewidths=0.6)
        ax.clabel(lines, lines.levels[1::2], fontsize=7, fmt="%.1f")
        ax.plot(rule_l, rule_psi(rule_l * 1e-3, l21), color="#00008b", lw=2.2,
                label=f"ψ rule, eq. 4.15: ψ = 140° − 25.6 l11/l21")
        ax.plot([l21 * 0.4e3], [rule_psi(l21 * 0.4, l21)], "o", color="red", label="nominal design (p = 0.4)")
        ax.set_xlabel("l11 [mm]")
        ax.set_title(name)
        ax.legend(loc="upper right", fontsize=8)
        fig.colorbar(mesh, ax=ax, label=key + " (colours clipped at 2)")
    axes[0].set_ylabel("ψ [deg]")
    fig.suptitle(f"fig 4.8: α over (l11, ψ) at r = {m.r.iloc[0]:g}, l21 = {l21 * 1e3:g} mm; white: iso-α lines (0.1 apart)\n"
                 "grey: discarded at stage 1 (singular_closing below, singular_open / mode_change above)", fontsize=10)
    fig.tight_layout()
    os.makedirs(figures, exist_ok=True)
    out = os.path.join(figures, "fig4_8a_alpha_psi_rule.svg")
    fig.savefig(out, dpi=150, metadata={"Date": None})
    print(f"  wrote {out}")


def row22():
    d = sweep("fig4_13e")
    ok = d[d.e_cyl.notna()]
    top = ok.e_cyl.idxmax()
    gap = d[d.verdict == "singular_open"].l11
    last = ok.iloc[-1]
    tau = tomllib.load(open(PROBLEM, "rb"))["hand"]["tau"]
    print(f"row 22 (fig4_13e): E_cyl along the psi rule at tau = {tau} N·m, l11 in 0.5 mm steps")
    before = ok[ok.l11 < gap.min()].iloc[-1]
    print(f"  {ok.e_cyl.iloc[0] * 1e3:.2f} mJ at {ok.l11.iloc[0] * 1e3:.1f} mm, rising to {before.e_cyl * 1e3:.2f} mJ at "
          f"{before.l11 * 1e3:.1f} mm (monotone: {bool(ok[ok.l11 < gap.min()].e_cyl.is_monotonic_increasing)}); singular_open "
          f"{gap.min() * 1e3:.1f}..{gap.max() * 1e3:.1f} mm; peak {d.e_cyl[top] * 1e3:.3f} mJ at "
          f"{d.l11[top] * 1e3:.1f} mm; {last.e_cyl * 1e3:.3f} mJ at {last.l11 * 1e3:.1f} mm (last computed)")
    print(f"  at tau = 0.188 N·m (E_cyl ∝ tau): peak {d.e_cyl[top] * 1e3 * 0.188 / tau:.2f} mJ, "
          f"{last.e_cyl * 1e3 * 0.188 / tau:.2f} mJ at {last.l11 * 1e3:.1f} mm")


def impact_ratio(c, rho, m_finger, v):
    """E_cyl / min(E_lim,trans, E_lim,rot) of MODEL.md §9.1 at object density rho, from the
    finger's effective mass and onset velocity (neither depends on the object in the centred
    scene). Returns (ratio, E_cyl, E_lim)."""
    rad, length, h = c["radius"], c["length"], c["grasp_height"]
    m_c = rho * math.pi * rad**2 * length
    j_c = m_c * (3 * rad**2 + length**2) / 12
    k_c = abs(length / 2 - h)
    m_rot = j_c / k_c**2
    m_cyl = m_c * m_rot / (m_c + m_rot)
    m_tot = m_finger * m_cyl / (m_finger + m_cyl)
    p = (1 + c["restitution"]) * m_tot * v
    e_cyl = p**2 / (2 * m_cyl)
    theta = min(math.radians(c["theta_max_deg"]), math.atan(2 * rad / length))
    e_trans = c["mu_g"] * m_c * c["g"] * c["dx_max"]
    e_rot = m_c * c["g"] * ((length / 2) * (math.cos(theta) - 1) + rad * math.sin(theta))
    e_lim = min(e_trans, e_rot)
    return e_cyl / e_lim, e_cyl, e_lim, m_cyl


def rows24_25():
    t = tomllib.load(open(PROBLEM, "rb"))
    c = {**t["object"], **t["environment"], **t["criteria"], "restitution": t["contact"]["restitution"]}
    d = sweep("fig4_17")
    sim = d[d.e_cyl.notna()]
    m_f, v = sim.m_finger.iloc[0], sim.v_impact.iloc[0]
    worst = max(max(abs(impact_ratio(c, r.density, m_f, v)[i] / e - 1) for i, e in ((1, r.e_cyl), (2, r.e_lim)))
                for r in sim.itertuples())
    print(f"rows 24-25 (fig4_16, fig4_16e, fig4_17): MODEL.md §4/§9.1 recomputed here; it matches gripopt's "
          f"E_cyl and E_lim at the {len(sim)} simulated densities to {worst:.1e} (relative)")
    print(f"  m_finger {m_f * 1e3:.2f} g and v_impact {v:.4f} m/s are the same at every density: "
          f"{sim.m_finger.nunique() == 1 and sim.v_impact.nunique() == 1}")
    b = boundaries("fig4_17")
    rho_star = b[(b.verdict_lo == "impact") & (b.verdict_hi == "pass")][["lo", "hi"]].mean(axis=1).iloc[0]
    at_star, at_730 = impact_ratio(c, rho_star, m_f, v)[0], impact_ratio(c, 730.0, m_f, v)[0]
    print(f"  impact boundary rho* = {rho_star:.1f} kg/m³ (E_cyl/E_lim there {at_star:.6f}); "
          f"at 730 kg/m³ E_cyl/E_lim = {at_730:.4f}")
    m_cyl = {rho: impact_ratio(c, rho, m_f, v)[3] for rho in (730.0, 1000.0, rho_star)}
    print("  m_cyl " + ", ".join(f"{m:.4f} kg at {rho:.1f} kg/m³" for rho, m in m_cyl.items()))
    lo, hi = sim.iloc[0], sim.iloc[-1]
    static = b[(b.verdict_lo == "static_force") & (b.verdict_hi == "impact")][["lo", "hi"]].mean(axis=1)
    print(f"  E_lim/rho {(sim.e_lim / sim.density).min():.4e}..{(sim.e_lim / sim.density).max():.4e} J·m³/kg; "
          f"E_cyl·rho {lo.e_cyl * lo.density:.3f} -> {hi.e_cyl * hi.density:.3f} J·kg/m³ for rho {lo.density:g} -> {hi.density:g}; "
          f"static-force boundary {static.iloc[0]:.1f} kg/m³")
    print(f"  density factor (gripopt's E_cyl/E_lim at 730 over the thesis's, 1 at its limit): {at_730 / at_star:.3f}; "
          f"the shortcut (rho*/730)² = {(rho_star / 730) ** 2:.3f} ignores that m_tot depends on rho")
    e = sweep("fig4_16e")
    e = e[e.v_impact.notna()]
    vt = e.v_impact**2 / e.tau
    print(f"  E_cyl ∝ tau: v_impact²/tau {vt.min():.4f}..{vt.max():.4f} m²s⁻²/(N·m), "
          f"m_finger {e.m_finger.min() * 1e3:.3f}..{e.m_finger.max() * 1e3:.3f} g over tau {e.tau.min():.2f}..{e.tau.max():.2f}")
    bt = boundaries("fig4_16")
    tau_star = bt[(bt.verdict_lo == "pass") & (bt.verdict_hi == "impact")][["lo", "hi"]].mean(axis=1).iloc[0]
    nominal = sweep("fig4_16e")
    n = nominal[(nominal.tau - 0.5).abs() < 1e-9]
    tau_ratio = 0.9 / tau_star
    print(f"  torque factor (gripopt's E_cyl/E_lim at 0.9 N·m, the thesis's limit): 0.9/{tau_star:.4f} = {tau_ratio:.3f}"
          + (f" (= 1.8 × {n.e_cyl.iloc[0] / n.e_lim.iloc[0]:.4f} at 0.5 N·m)" if len(n) and n.e_cyl.notna().all() else ""))
    print(f"  torque factor / density factor = {tau_ratio / (at_730 / at_star):.4f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", default=f"{R}/fig4_8a", help="folder for row 14's map (default: %(default)s)")
    args = ap.parse_args()
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    row8()
    row12()
    row14(args.figures)
    row22()
    rows24_25()


if __name__ == "__main__":
    main()
