"""A robust run's tables read with plain pandas: the per-object measured columns (P(stay),
its interval, the displacement, the objectives) are float64 even where every value is whole
(`0.0`, not `0`), the counts whole numbers; the single-object tables as before."""

from __future__ import annotations

import io

import pandas as pd

from conftest import REPO


def test_robust_probability_columns_read_as_float(cli, tmp_path):
    out = tmp_path / "run"
    kitchen = REPO / "problems" / "kitchen.toml"
    cli("optimise", kitchen, "--out", out, "--pop", 8, "--generations", 1, "--seed", 1, "--record", "none")
    text = (out / "population.csv").read_text()
    rows = pd.read_csv(io.StringIO(text), comment="#")
    p_cols = [c for c in rows.columns if c.rsplit(".", 1)[-1] in ("p_stay", "p_stay_lo", "p_stay_hi")]
    assert len(p_cols) == 3 * 4, list(rows.columns)
    # the designs whose scenarios ran (the others' robust cells are empty)
    ran = rows[rows[p_cols[0]].notna()]
    assert len(ran) >= 1 and (ran[p_cols] == 0).any(axis=None), ran[p_cols]
    # a table of those designs alone (as a user filtering the file's lines would have it):
    # a column whose every value is 0 still reads as float64
    lines = [l for l in text.splitlines() if not l.startswith("#")]
    keep = [lines[0]] + [lines[1 + i] for i in ran.index]
    alone = pd.read_csv(io.StringIO("\n".join(keep)))
    zero = [c for c in p_cols if (alone[c] == 0).all()]
    assert zero, alone[p_cols]
    for c in p_cols + [c for c in alone.columns if c.endswith(".max_displacement")]:
        assert alone[c].dtype == "float64", (c, alone[c].dtype, list(alone[c]))
    for c in ["scenarios_run", "scenarios_saved"] + [c for c in alone.columns if c.endswith((".stays", ".scenarios"))]:
        assert alone[c].dtype == "int64", (c, alone[c].dtype)
    assert alone["id"].equals(ran["id"].reset_index(drop=True))
