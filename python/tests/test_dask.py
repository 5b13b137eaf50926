"""gripopt.dask: a large batch evaluated on a Dask LocalCluster (separate worker
processes) equals the local evaluation bit for bit; a pymoo run through the cluster
equals the local run."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pandas.testing as pdt
import pytest

pytest.importorskip("dask.distributed")
from dask.distributed import Client, LocalCluster  # noqa: E402

import gripopt  # noqa: E402
import gripopt.dask  # noqa: E402


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as c:
            yield c


def test_a_batch_on_the_cluster_equals_the_local_evaluation(client, problem):
    static = problem.bounds.sample(20_000, seed=11)
    near = pd.DataFrame(problem.nominal.to_numpy() * (1 + 0.1 * (np.random.default_rng(3).random((40, 6)) - 0.5)), columns=list(gripopt.DESIGN_NAMES))
    for designs, static_only, chunk in [(static, True, 3000), (near, False, 7)]:
        there = gripopt.dask.evaluate(client, problem, designs, static_only=static_only, chunk_size=chunk)
        here = problem.evaluate(designs, static_only=static_only)
        pdt.assert_frame_equal(there, here, check_exact=True)
        assert there.attrs == here.attrs
    assert here["sim_steps"].notna().any()  # the second batch simulated grasps


def test_pymoo_through_the_cluster_equals_the_local_run(client, problem):
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.optimize import minimize

    from gripopt.pymoo import GripperProblem

    def run(**kw):
        return minimize(GripperProblem(problem, **kw), NSGA2(pop_size=12), ("n_gen", 3), seed=4, verbose=False)

    there, here = run(client=client, chunk_size=5, threads=1), run()
    assert np.array_equal(there.pop.get("X"), here.pop.get("X"))
    assert np.array_equal(there.pop.get("F"), here.pop.get("F"))


def test_pymoo_passes_its_thread_count_to_the_cluster(client, problem):
    """GripperProblem(threads=...) reaches the Dask tasks: a thread count out of range is an
    InputError with a client too (it used to be dropped there)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.optimize import minimize

    from gripopt.pymoo import GripperProblem

    with pytest.raises(gripopt.InputError, match="^threads = 0: must be an int from 1"):
        minimize(GripperProblem(problem, threads=0, client=client), NSGA2(pop_size=4), ("n_gen", 1), seed=1)
