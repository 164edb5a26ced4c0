"""One-step footstep QP: exact solver vs OSQP vs ProxQP, KKT conditions, infeasibility."""

import numpy as np
import pytest
from sequencer_instances import random_problems

from sequencer import InfeasibleStep, SequencerParams, StepProblem, StepQPError
from sequencer.backends import make_backend
from sequencer.step_qp import ExactBackend
from wbmpc.errors import ParameterError, SolverError


def kkt_residuals(problem, solution):
    """Stationarity (eq. 9), primal feasibility, dual feasibility and complementarity residuals."""
    x, u, w = solution.x, solution.u, solution.w
    a1, a2, a3 = problem.alpha
    grad_f = 2 * np.array([a1, a1, a2, a3, a3]) * (
        x - np.concatenate([problem.p0 + problem.step_nominal, [problem.gamma_nominal], problem.b_nominal])
    )
    stationarity = grad_f - problem.inequality_jacobian() @ u + problem.equality_jacobian() @ w
    g = problem.inequalities(x)
    return stationarity, g, problem.equalities(x), u * g


@pytest.mark.parametrize("tight", [False, True])
def test_exact_solution_satisfies_kkt_on_random_instances(tight):
    n_active = 0
    for problem in random_problems(200, seed=1, tight=tight):
        solution = ExactBackend().solve(problem)
        stationarity, g, h, complementarity = kkt_residuals(problem, solution)
        scale = 1.0 + np.max(np.abs(solution.w))
        assert np.max(np.abs(stationarity)) < 1e-9 * scale
        assert np.all(g >= -1e-12) and np.max(np.abs(h)) < 1e-12
        assert np.all(solution.u >= 0) and np.max(np.abs(complementarity)) < 1e-9 * scale
        n_active += int(solution.active.any())
    if tight:
        assert n_active > 50  # the tight family exercises active bounds


@pytest.mark.parametrize("backend", ["osqp", "proxqp"])
def test_iterative_backends_agree_with_the_exact_solver(backend):
    solver = make_backend(backend)  # one warm workspace across all instances
    for problem in random_problems(60, seed=2, tight=True) + random_problems(20, seed=3):
        exact = ExactBackend().solve(problem)
        other = solver.solve(problem)
        assert other.x == pytest.approx(exact.x, abs=1e-6, rel=1e-6)
        assert np.array_equal(other.active, exact.active), (problem.describe(), other.x, exact.x)
        scale = 1.0 + np.max(np.abs(exact.w))
        assert np.max(np.abs(other.w - exact.w)) < 1e-4 * scale
        assert np.max(np.abs(other.u - exact.u)) < 1e-4 * scale


def test_table_i_example_has_no_active_constraint():
    problem = StepProblem.from_params(SequencerParams.table_i(), "left", [-0.12, 0.10], [-0.12, -0.07], 0.229)
    solution = ExactBackend().solve(problem)
    assert not solution.active.any()
    assert solution.step_position[1] < problem.p0[1]  # the right foot steps to the right
    assert 0.229 < solution.duration < 1.0


def test_elapsed_beyond_t_max_raises_infeasible_step_with_data_and_status():
    problem = StepProblem.from_params(SequencerParams.table_i(), "left", [0.0, 0.1], [0.0, 0.0], 1.2)
    for backend in ("exact", "osqp", "proxqp"):
        with pytest.raises(InfeasibleStep, match=r"t=1.2 s exceeds T_max=1.0 s") as info:
            make_backend(backend).solve(problem)
        assert info.value.problem is problem and info.value.status == "primal infeasible"
        assert "dcm_measured=[0.0, 0.0]" in str(info.value)
        assert isinstance(info.value, StepQPError) and isinstance(info.value, SolverError)


def test_unknown_backend_and_bad_problem_data_raise():
    with pytest.raises(ParameterError, match=r"backend='gurobi' is not available \(choose from \['exact', 'osqp', 'proxqp'\]\)"):
        make_backend("gurobi")
    with pytest.raises(ParameterError, match=r"dcm_measured=\[nan, 0.0\] must be finite"):
        StepProblem.from_params(SequencerParams.table_i(), "left", [0, 0], [np.nan, 0.0], 0.1)
    with pytest.raises(ParameterError, match=r"elapsed=-0.1 s .* must be finite and >= 0"):
        StepProblem.from_params(SequencerParams.table_i(), "left", [0, 0], [0, 0], -0.1)
    with pytest.raises(ParameterError, match=r"stance_foot='middle' must be 'left' or 'right'"):
        StepProblem.from_params(SequencerParams.table_i(), "middle", [0, 0], [0, 0], 0.1)
