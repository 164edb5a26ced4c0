"""BLAS threading: scoped by limit_blas_threads, untouched by a solver's constructor."""

from __future__ import annotations

import os

import pytest

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp import blas
from wbmpc.ocp.blas import limit_blas_threads


def _counts() -> list[int]:
    return [int(getter()) for _, _, getter in blas._openblas_libraries() + blas._openmp_libraries()]


@pytest.mark.skipif("OPENBLAS_NUM_THREADS" in os.environ or "OMP_NUM_THREADS" in os.environ,
                    reason="the environment fixes the thread count")
def test_limit_blas_threads_is_scoped():
    import pinocchio  # noqa: F401 - loads an OpenMP runtime (libgomp)

    assert blas._openmp_libraries(), "Pinocchio's OpenMP runtime was not found"
    with limit_blas_threads(2):  # more than one to start from, whatever the machine
        before = _counts()
        with limit_blas_threads(1) as limited:
            assert len(limited) == len(before)
            assert all(count == 1 for count in _counts())
        assert _counts() == before == [2] * len(before)
        with pytest.raises(RuntimeError), limit_blas_threads(1):
            raise RuntimeError("inside")
        assert _counts() == before


@pytest.mark.skipif("OPENBLAS_NUM_THREADS" in os.environ, reason="the environment fixes the thread count")
def test_solver_constructor_leaves_blas_alone():
    from wbmpc.ocp.solvers.fddp import SolverFDDP
    from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig

    ocp = WalkingOCP(load_robot("bolt"), WalkingOCPConfig(), 4, 0.01)
    with limit_blas_threads(2):
        before = _counts()
        SolverFDDP(ocp.problem)
        assert _counts() == before


@pytest.mark.parametrize("n_threads", [0, -1, 1.5, True])
def test_limit_blas_threads_rejects_bad_counts(n_threads):
    with pytest.raises(ParameterError, match=f"n_threads={n_threads!r}"):
        with limit_blas_threads(n_threads):
            pass
