"""IPOPT (reference) and the warm-started SQP fast path: one result on 200 random instances, active bounds
included; bad input and solver failures."""

import dataclasses

import numpy as np
import pytest

from sequencer.alip.instances import random_instances
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import AlipInstance, AlipNlp, AlipSolverError
from sequencer.alip.params import AlipParams
from sequencer.alip.sqp_ import SqpSolver
from wbmpc.errors import ParameterError, SolverError

PARAMS = AlipParams.preset("g1")


@pytest.fixture(scope="module")
def solvers():
    nlp = AlipNlp(PARAMS)
    return nlp, IpoptSolver(nlp), SqpSolver(nlp)


def test_200_instances_agree(solvers):
    nlp, ipopt, sqp = solvers
    worst, with_active, kinds = 0.0, 0, set()
    rng = np.random.default_rng(1)
    for instance in random_instances(PARAMS, 200, seed=0):
        reference = ipopt.solve(instance)
        cold = sqp.solve(instance)
        # warm: from the solution of the same instance measured 10 ms earlier (a receding-horizon replan)
        before = dataclasses.replace(instance, x0=instance.x0 + rng.normal(size=4) * [0.002, 0.3, 0.002, 0.3],
                                     t_curr=max(0.0, instance.t_curr - 0.01))
        warm = sqp.solve(instance, sqp.solve(before, cold))
        for fast in (cold, warm):
            worst = max(worst, float(np.max(np.abs(fast.w - reference.w))))
            assert fast.active == reference.active
        with_active += bool(reference.active)
        kinds |= {name.split("_")[0] + ":" + name.split(":")[1] for name in reference.active}
    assert worst <= 1e-6, worst
    assert with_active >= 50
    assert {"T:lower", "T:upper", "tau:lower", "tau:upper", "l:lower", "l:upper"} <= kinds


def test_warm_start_from_own_solution_takes_few_iterations(solvers):
    nlp, ipopt, sqp = solvers
    instance = random_instances(PARAMS, 1, seed=5)[0]
    first = sqp.solve(instance)
    nudged = dataclasses.replace(instance, x0=instance.x0 + [0.002, 0.3, 0.0, 0.0])
    again = sqp.solve(nudged, first)
    assert again.iterations <= 4
    assert np.max(np.abs(again.w - ipopt.solve(nudged).w)) <= 1e-6


def test_fixed_timing_is_respected(solvers):
    params = PARAMS.fixed_timing(0.35)
    nlp = AlipNlp(params)
    instance = random_instances(params, 3, seed=1)[2]
    solution = SqpSolver(nlp).solve(instance)
    assert np.allclose(solution.periods, 0.35)


@pytest.mark.parametrize("changes, match", [
    ({"t_min": 0.6}, "t_min=0.6 s must be <= t_max"),
    ({"length_min": 0.1, "length_max": 0.05}, "length_min"),
    ({"q_x": [1.0, 2.0]}, "q_x"),
    ({"mass": float("inf")}, "mass"),
    ({"steps": 1}, "steps"),
])
def test_bad_parameters(changes, match):
    with pytest.raises(ParameterError, match=match):
        dataclasses.replace(PARAMS, **changes)


def test_bad_instances(solvers):
    nlp, _, _ = solvers
    with pytest.raises(ParameterError, match="x0="):
        AlipInstance([0.0, np.nan, 0.0, 0.0], 0.1, "left")
    with pytest.raises(ParameterError, match="v_x="):
        AlipInstance([0.0] * 4, 0.1, "left", v_x=float("inf"))
    with pytest.raises(ParameterError, match="t_curr"):
        AlipInstance([0.0] * 4, -0.1, "left")
    with pytest.raises(ParameterError, match=r"v_x=2.0 m/s puts the desired step"):  # the step box excludes it
        nlp.parameters(AlipInstance([0.0] * 4, 0.1, "left", v_x=2.0))


def test_infeasible_problem_raises_a_solver_error(solvers):
    nlp, ipopt, sqp = solvers
    push = AlipInstance([0.2, 40.0, -0.1, 0.0], 0.45, "left")  # beyond the state bounds whatever the step
    for solver in (ipopt, sqp):
        with pytest.raises(AlipSolverError) as info:
            solver.solve(push)
        assert isinstance(info.value, SolverError) and info.value.solver == solver.name and info.value.status
