"""Problem.evaluate and Problem.record against `gripopt evaluate --json` (a separate
process), bit for bit, and the forms designs may take."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest

import gripopt
from conftest import design_arg, same_float


def designs(problem: gripopt.Problem) -> pd.DataFrame:
    """Random designs: uniform in the bounds (mostly discarded at stage 1) and near the
    nominal design (mostly simulated), and the nominal itself."""
    rng = np.random.default_rng(2025)
    lo, hi = problem.bounds.lower.to_numpy(), problem.bounds.upper.to_numpy()
    uniform = lo + rng.random((4, 6)) * (hi - lo)
    near = problem.nominal.to_numpy() * (1 + 0.08 * (rng.random((5, 6)) - 0.5))
    x = np.vstack([uniform, near, problem.nominal.to_numpy()])
    return pd.DataFrame(x, columns=list(gripopt.DESIGN_NAMES))


def expected_row(rec: dict, x: pd.Series) -> dict:
    """A population.csv row as docs/outputs.md defines it from the evaluation record."""
    built = rec["failed_stage"] is None or rec["failed_stage"] >= 2
    mo = rec["max_offset"]
    row = {n: float(x[n]) for n in gripopt.DESIGN_NAMES}
    row.update(
        feasible=rec["feasible"],
        failed_stage=rec["failed_stage"],
        violation=rec["violation"],
        reason=rec["reason"],
        l11=rec["l11"] if built else None,
        l12=rec["l12"] if built else None,
        l22=rec["l22"] if built else None,
        l_hand=rec["l_hand"],
        form_closed=None if mo is None else mo >= 0,
        max_offset=mo if mo is not None and mo >= 0 else None,
        alpha=rec["alpha"],
        mean_force=rec["mean_force"],
        t_stab=rec["t_stab"],
        sim_steps=rec["steps"],
        sim_rhs_evals=rec["rhs_evals"],
        force_model=rec["force_model"],
    )
    return row


@pytest.mark.parametrize("static_only", [False, True])
def test_rows_equal_the_cli_json_bit_for_bit(problem, cli_json, static_only):
    d = designs(problem)
    df = problem.evaluate(d, static_only=static_only)
    assert list(df.columns) == [c[0] for c in gripopt.DESIGN_COLUMNS]
    assert list(df["id"]) == list(range(len(d)))
    kinds = set()
    for k, x in d.iterrows():
        args = ["evaluate", "problems/bottle-1l.toml", "--json", "--design", design_arg(x)]
        rec = cli_json(*args, *(["--static-only"] if static_only else []))
        kinds.add(rec["failed_stage"])
        # the record's own design is the one given, exactly
        for n in ["l21", "b", "t22", "r", "p"]:
            assert same_float(rec[n], x[n])
        for col, want in expected_row(rec, x).items():
            got = df.at[k, col]
            assert same_float(got, want), f"design {k}, {col}: {got!r} != {want!r}"
    # the designs reach every kind of verdict they should
    assert 1 in kinds and (None in kinds or 3 in kinds)


def test_the_full_record_equals_the_cli_json(problem, cli_json):
    for _, x in designs(problem).iloc[[4, 9]].iterrows():
        for flag in ([], ["--static-only"]):
            cli = cli_json("evaluate", "problems/bottle-1l.toml", "--json", "--design", design_arg(x), *flag)
            lib = problem.record(x, static_only=bool(flag))
            for r in (cli, lib):
                r.pop("cpu_s", None)  # wall-clock seconds
            assert lib.keys() == cli.keys()
            for key in cli:
                assert same_float(lib[key], cli[key]) or lib[key] == cli[key], key



def test_the_record_of_an_auto_problem_names_its_method(problem, cli_json, tmp_path):
    """`[solver] method = "auto"`: Problem.record, as `gripopt evaluate --json`, says which
    method did the simulation's work (`method`); stages 0-2 and a file naming radau5 have no
    such key (CHANGELOG.md, Hostile pass 33); a file without the key runs the default, auto."""
    path = tmp_path / "auto.toml"
    path.write_text(problem.toml.replace("\n[solver]\n", '\n[solver]\nmethod = "auto"\n', 1))
    auto = gripopt.Problem.load(path)
    for flag in ([], ["--static-only"]):
        cli = cli_json("evaluate", path, "--json", *flag)
        lib = auto.record(static_only=bool(flag))
        for r in (cli, lib):
            r.pop("cpu_s", None)  # wall-clock seconds
        assert lib.keys() == cli.keys()
        assert lib.get("method") == (None if flag else "auto")
        for key in cli:
            assert same_float(lib[key], cli[key]) or lib[key] == cli[key], key
    assert problem.record()["method"] == "auto"
    radau = gripopt.Problem.from_toml(problem.toml.replace("\n[solver]\n", '\n[solver]\nmethod = "radau5"\n', 1))
    assert "method" not in radau.record()

def test_results_do_not_depend_on_threads_or_batching(problem):
    d = problem.bounds.sample(300, seed=7)
    one = problem.evaluate(d, static_only=True, threads=1)
    two = problem.evaluate(d, static_only=True, threads=2)
    pdt.assert_frame_equal(one, two, check_exact=True)
    # in two halves, the second numbered on: the same rows and the same column types
    half = pd.concat(
        [problem.evaluate(d.iloc[:150], static_only=True), problem.evaluate(d.iloc[150:], static_only=True, first_id=150)]
    )
    pdt.assert_frame_equal(half, one, check_exact=True)


def test_column_types_follow_the_row_fields_not_the_values(problem):
    # a batch with no simulated design still has nullable integer sim_steps, etc.
    df = problem.evaluate(problem.bounds.sample(3, seed=1), static_only=True)
    assert df["sim_steps"].isna().all()
    dtypes = {c: str(t) for c, t in df.dtypes.items()}
    assert dtypes["id"] == "int64" and dtypes["feasible"] == "bool"
    assert dtypes["rank"] == dtypes["failed_stage"] == dtypes["sim_steps"] == "Int64"
    assert dtypes["form_closed"] == "boolean"
    assert dtypes["max_offset"] == dtypes["psi_deg"] == "float64"
    assert df["reason"].dtype == df["force_model"].dtype  # text


def test_units_are_attached(problem):
    df = problem.evaluate(problem.nominal)
    u = df.attrs["units"]
    assert u["psi_deg"] == "deg" and u["max_offset"] == "m" and u["mean_force"] == "N" and u["t_stab"] == "s"
    assert "MAXIMISE" in df.attrs["meanings"]["mean_force"]


def test_design_forms(problem):
    nominal = problem.nominal
    ref = problem.evaluate(nominal, static_only=True)
    assert len(ref) == 1
    forms = [
        dict(nominal),
        nominal.to_numpy(),
        list(nominal),
        nominal.to_numpy()[None, :],
        pd.DataFrame([nominal]).assign(extra="ignored"),
    ]
    for f in forms:
        got = problem.evaluate(f, static_only=True)
        pdt.assert_frame_equal(got.reset_index(drop=True), ref, check_exact=True)
    # a DataFrame's index is kept
    framed = pd.DataFrame([nominal, nominal], index=["a", "b"])
    assert list(problem.evaluate(framed, static_only=True).index) == ["a", "b"]
    assert problem.evaluate(np.empty((0, 6))).empty


def test_bad_designs_are_input_errors(problem):
    with pytest.raises(gripopt.InputError, match="missing column.*psi_deg"):
        problem.evaluate(pd.DataFrame({"l21": [0.05]}))
    with pytest.raises(gripopt.InputError, match=r"shape \(2, 5\)"):
        problem.evaluate(np.zeros((2, 5)))
    x = np.tile(problem.nominal.to_numpy(), (3, 1))
    x[2, 1] = np.nan
    with pytest.raises(gripopt.InputError, match="row 2, `b` = NaN is not finite") as e:
        problem.evaluate(x)
    assert e.value.exit_code == 2
    with pytest.raises(gripopt.InputError, match="threads = 0: must be an int from 1 to 1024"):
        problem.evaluate(x[:2], threads=0)


def test_random_designs_are_the_bench_stream(problem):
    a = problem.bounds.sample(50, seed=4)
    pdt.assert_frame_equal(a, problem.bounds.sample(50, seed=4))
    lo, hi = problem.bounds.lower, problem.bounds.upper
    assert ((a >= lo) & (a <= hi)).all().all()
    assert not a.equals(problem.bounds.sample(50, seed=5))


# MODEL.md §3.4 (nominal derived values, "compare at 1e-9 relative") and D22 (the nominal's
# α and F̃ under each force model): numbers of the spec, not of this code.
NOMINAL_SPEC = {"l11": 0.01976, "l12": 0.045419424436, "l22": 0.0090896, "l_hand": 0.230}
NOMINAL_RECORD_SPEC = {
    "q11_0": -44.441240127,  # degrees in the spec, radians in the record
    "q21_0": 45.558759873,
    "q12_0": 106.332636305,
    "q13_0": -146.092636305,
    "theta1": 57.825595319,
    "theta2": 68.174528183,
}
FORCE_MODEL_SPEC = {"mobilised": (0.630876786547, 11.0872485551), "frictionless": (0.134162947086, 8.29512361390)}


def test_the_nominal_design_has_the_specs_values(problem):
    row = problem.evaluate(problem.nominal).iloc[0]
    for col, want in NOMINAL_SPEC.items():
        assert row[col] == pytest.approx(want, rel=1e-9, abs=0), col
    rec = problem.record()
    for key, deg in NOMINAL_RECORD_SPEC.items():
        assert np.degrees(rec[key]) == pytest.approx(deg, rel=1e-9), key
    assert rec["k1"] == pytest.approx(0.018947295321, rel=1e-9)
    assert rec["masses"] == pytest.approx([2.141686543805e-3, 4.922781889786e-3, 5.354216359513e-3, 5.060449800387e-3], rel=1e-9)
    # the force model of the problem file decides alpha and mean_force (from_toml: an edited problem)
    text = problem.toml
    assert 'force_model = "mobilised"' in text
    for model, (alpha, force) in FORCE_MODEL_SPEC.items():
        p = gripopt.Problem.from_toml(text.replace('force_model = "mobilised"', f'force_model = "{model}"'))
        r = p.evaluate(p.nominal, static_only=True).iloc[0]
        assert r["force_model"] == model
        assert (r["alpha"], r["mean_force"]) == (pytest.approx(alpha, rel=1e-9), pytest.approx(force, rel=1e-9))


def test_the_gil_is_released_while_rust_evaluates(problem):
    # Python code in another thread goes on while evaluate runs: were the GIL held through
    # the native call, the sampling loop below would stall for the call's whole duration
    import threading
    import time

    designs = problem.bounds.sample(20_000, seed=3)
    span: dict[str, float] = {}

    def work() -> None:
        span["start"] = time.perf_counter()
        problem.evaluate(designs, static_only=True, threads=1)
        span["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    stamps = []
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())
        time.sleep(0.0005)
    worker.join()
    inside = [t for t in stamps if span["start"] <= t <= span["end"]]
    duration = span["end"] - span["start"]
    assert len(inside) > 2, "no Python progress during the evaluation"
    gaps = np.diff([span["start"], *inside, span["end"]])
    assert gaps.max() < 0.5 * duration, f"Python stalled {gaps.max():.3f} s of a {duration:.3f} s evaluation"
