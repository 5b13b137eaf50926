"""Shared fixtures of the Python suite: the repository, the bottle problem, the gripopt
command (the CLI is the independent reference: a separate process over the same library)
and a small run written by it."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any

import pandas as pd
import pytest

import gripopt

REPO = Path(__file__).resolve().parents[2]
BOTTLE = REPO / "problems" / "bottle-1l.toml"


def _gripopt_binary() -> Path:
    """The `gripopt` command: $GRIPOPT (make test sets it), else a built one in target/."""
    given = os.environ.get("GRIPOPT")
    candidates = [Path(given)] if given else []
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    candidates += [target / "release" / "gripopt", target / "debug" / "gripopt"]
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return c.resolve()
    pytest.fail(f"no gripopt binary (looked at {', '.join(map(str, candidates))}); run `cargo build` or set GRIPOPT")


@pytest.fixture(scope="session")
def gripopt_bin() -> Path:
    return _gripopt_binary()


@pytest.fixture(scope="session")
def cli(gripopt_bin: Path):
    """Run the gripopt command; its stdout (fails the test on a non-zero exit)."""

    def run(*args: Any) -> str:
        p = subprocess.run([str(gripopt_bin), *map(str, args)], capture_output=True, text=True, cwd=REPO)
        assert p.returncode == 0, f"gripopt {' '.join(map(str, args))}: {p.stderr}"
        return p.stdout

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    return lambda *args: json.loads(cli(*args))


@pytest.fixture(scope="session")
def problem() -> gripopt.Problem:
    return gripopt.Problem.load(BOTTLE)


#: The small run the suite reads: `gripopt optimise` with these settings (seed 8: seven designs
#: on its front with the default optimiser; with seed 1 its three generations find none).
RUN_SETTINGS = {"pop": 8, "generations": 3, "seed": 8}


@pytest.fixture(scope="session")
def cli_run(cli, tmp_path_factory) -> Path:
    """A run folder written by `gripopt optimise` (the CLI)."""
    out = tmp_path_factory.mktemp("cli-run") / "run"
    s = RUN_SETTINGS
    cli("optimise", BOTTLE, "--out", out, "--pop", s["pop"], "--generations", s["generations"], "--seed", s["seed"])
    return out


def design_arg(row: Any) -> str:
    """A design as `--design` spells it (each value's shortest round-trip text: exact)."""
    return ",".join(f"{n}={float(row[n])!r}" for n in gripopt.DESIGN_NAMES)


def same_float(a: Any, b: Any) -> bool:
    """Equal bit for bit (floats by their hex form; None/NaN as "not computed")."""

    def missing(v: Any) -> bool:
        return v is None or v is pd.NA or (isinstance(v, float) and v != v)

    if missing(a) or missing(b):
        return missing(a) and missing(b)
    if isinstance(a, float) or isinstance(b, float):
        return float(a).hex() == float(b).hex()
    return a == b
