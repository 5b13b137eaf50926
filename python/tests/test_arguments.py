"""Whole-number arguments (seeds, thread counts, sizes, ids): a negative, too large,
fractional, boolean or non-numeric value is an InputError (exit code 2) naming the argument
and its range, raised before anything runs or is written; NumPy integers are ints."""

from __future__ import annotations

import numpy as np
import pytest

import gripopt
import gripopt.dask
from conftest import BOTTLE

# values no whole-number argument takes, and what the message says of each
BAD = [
    (-1, "-1"),
    (2**64, str(2**64)),
    (True, "True: .*, not a bool"),
    (2.0, r"2\.0: .*, not a float"),
    ("3", "'3': .*, not a str"),
]


def raises_naming(name: str, shown: str, rule: str):
    """An InputError whose message starts `name = value: must be an int from <rule>`."""
    value, _, why = shown.partition(": ")
    return pytest.raises(gripopt.InputError, match=rf"^{name} = {value}: must be an int from {rule}.*{why}")


@pytest.mark.parametrize("value, shown", BAD)
def test_sample_n_and_seed(problem, value, shown):
    with raises_naming("n", shown, "0 to"):
        problem.bounds.sample(value, seed=1)
    with raises_naming("seed", shown, "0 to 18446744073709551615") as e:
        problem.bounds.sample(3, seed=value)
    assert e.value.exit_code == 2 and e.value.field == "seed"


def test_sample_larger_than_memory_is_a_memory_error(problem):
    """An n within the argument's range whose designs cannot be allocated (48 PB) raises
    MemoryError naming n, instead of aborting the interpreter."""
    with pytest.raises(MemoryError, match=r"^n = 1000000000000000: 4\.800e16 bytes"):
        problem.bounds.sample(10**15, seed=1)
    assert len(problem.bounds.sample(2, seed=1)) == 2


@pytest.mark.parametrize("value, shown", [*BAD, (0, "0"), (1025, "1025")])
def test_evaluate_threads(problem, value, shown):
    with raises_naming("threads", shown, "1 to 1024"):
        problem.evaluate(problem.nominal, static_only=True, threads=value)


@pytest.mark.parametrize("value, shown", [*BAD, (2**63, str(2**63))])
def test_evaluate_first_id(problem, value, shown):
    with raises_naming("first_id", shown, "0 to 9223372036854775807"):
        problem.evaluate(problem.nominal, static_only=True, first_id=value)


def test_the_last_id_of_a_batch_fits_int64(problem):
    two = [problem.nominal, problem.nominal]
    last = 2**63 - 1
    assert problem.evaluate(two[:1], static_only=True, first_id=last)["id"].tolist() == [last]
    with pytest.raises(gripopt.InputError, match="first_id = 9223372036854775807: the last of 2 designs"):
        problem.evaluate(two, static_only=True, first_id=last)


@pytest.mark.parametrize("name", ["pop", "generations", "seed", "threads"])
@pytest.mark.parametrize("value, shown", BAD)
def test_optimise_arguments_fail_before_the_run_folder_is_made(tmp_path, name, value, shown):
    out = tmp_path / "run"
    with raises_naming(name, shown, "1 to" if name == "threads" else "0 to"):
        gripopt.optimise(BOTTLE, out, **{"pop": 8, "generations": 1, name: value})
    assert not out.exists()


@pytest.mark.parametrize("name", ["generations", "threads"])
@pytest.mark.parametrize("value, shown", BAD)
def test_resume_arguments(tmp_path, name, value, shown):
    with raises_naming(name, shown, "1 to" if name == "threads" else "0 to"):
        gripopt.resume(tmp_path, **{name: value})


def test_design_ids_beyond_u64(cli_run):
    run = gripopt.Run(cli_run)
    for ask in (run.design, run.replay):
        with raises_naming("id", str(2**64), "0 to"):
            ask(2**64)
    for ask in (run._folder.design, run._folder.replay):  # the native module itself
        with raises_naming("id", "-1", "0 to"):
            ask(-1)


def test_numpy_integers_are_ints(problem):
    a = problem.bounds.sample(np.int64(3), seed=np.uint64(4))
    assert a.equals(problem.bounds.sample(3, seed=4))
    rows = problem.evaluate(a, static_only=True, threads=np.int32(1), first_id=np.int64(7))
    assert rows["id"].tolist() == [7, 8, 9]


@pytest.mark.parametrize("value", [0, -1, 2.0, True, "8"])
def test_dask_chunk_size(problem, value):
    with pytest.raises(gripopt.InputError, match=r"^chunk_size = .*: must be an int of at least 1"):
        gripopt.dask.evaluate(None, problem, problem.nominal, chunk_size=value)


def test_dask_checks_threads_and_first_id_before_sending_work(problem):
    # no client is used: the check comes first
    with raises_naming("threads", "-1", "1 to 1024"):
        gripopt.dask.evaluate(None, problem, problem.nominal, threads=-1)
    with raises_naming("first_id", "True: .*, not a bool", "0 to"):
        gripopt.dask.evaluate(None, problem, problem.nominal, first_id=True)
