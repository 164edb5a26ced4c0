"""Real-time deadlines: SolverFDDP.solve(deadline=...) and WalkingMPC(time_budget=...)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from wbmpc_fixtures import alternating_schedule, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.walking import WalkingMPC, WalkingOCPConfig
from wbmpc.walking.ocp import WalkingOCP, quasi_static_controls

N_NODES, DT = 30, 0.01


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


def _solver(bolt) -> tuple[SolverFDDP, np.ndarray, np.ndarray]:
    ocp = WalkingOCP(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT)
    x0 = standing_state(bolt)
    ocp.update(x0, alternating_schedule(0.0, DT, N_NODES), np.array([0.1, 0.0, 0.3]))
    xs = np.repeat(x0[None], N_NODES + 1, axis=0)
    us = np.repeat(quasi_static_controls(ocp, x0)[None], N_NODES, axis=0)
    return SolverFDDP(ocp.problem), xs, us


def _warm_guess(bolt):
    """N = 100 after a cold MPC update, the shifted solution: its full step is accepted."""
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=100, dt=DT, max_iterations=1, cold_start_iterations=30)
    x0 = standing_state(bolt)
    com_ref = np.array([0.3, 0.0, 0.3])
    first = mpc.update(0.0, x0, alternating_schedule(0.0, DT, 100), com_ref)
    mpc.ocp.update(first.xs[1], alternating_schedule(DT, DT, 100), com_ref + [0.0033, 0.0, 0.0])
    xs, us, _ = mpc.warm_start(DT, first.xs[1])
    return mpc.problem, xs, us


@pytest.mark.parametrize("guess", ["cold", "warm"])
def test_a_passed_deadline_runs_the_first_trial_only(bolt, guess):
    """Deadline already passed: one backward pass and the full-step trial, then stop. The gains
    are those of the backward pass at the returned iterate: the next one when the full step was
    accepted (the MPC's warm start), the guess when it was rejected (the cold quasi-static one)."""
    if guess == "cold":
        cut, xs, us = _solver(bolt)
        reference = _solver(bolt)[0]
    else:
        problem, xs, us = _warm_guess(bolt)
        cut, reference = SolverFDDP(problem), SolverFDDP(problem)
    assert not cut.solve(xs, us, maxiter=10, deadline=time.perf_counter())
    assert cut.deadline_hit and len(cut.log) == 1
    K = cut.K.copy()
    reference.solve(xs, us, maxiter=1)
    np.testing.assert_array_equal(K, reference.K)
    assert (reference.log[0].step_length == 1.0) == (guess == "warm")
    if guess == "warm":  # the full step was accepted: the same iterate
        np.testing.assert_array_equal(cut.xs, reference.xs)
        np.testing.assert_array_equal(cut.us, reference.us)
        assert cut.log[0].step_length == 1.0
    else:  # rejected, and no time for α = ½: the guess is kept, logged with step 0
        np.testing.assert_array_equal(cut.us, us)
        assert cut.log[0].step_length == 0.0


def test_a_distant_deadline_changes_nothing(bolt):
    free, xs, us = _solver(bolt)
    free.solve(xs, us, maxiter=6)
    timed, _, _ = _solver(bolt)
    timed.solve(xs, us, maxiter=6, deadline=time.perf_counter() + 600.0)
    assert not timed.deadline_hit and len(timed.log) == len(free.log)
    np.testing.assert_array_equal(timed.us, free.us)
    np.testing.assert_array_equal(timed.K, free.K)


def test_deadline_must_be_finite(bolt):
    solver, xs, us = _solver(bolt)
    with pytest.raises(ParameterError, match="deadline=nan"):
        solver.solve(xs, us, maxiter=1, deadline=float("nan"))


def test_mpc_time_budget_cuts_the_update_short_and_reports_it(bolt):
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT, max_iterations=3, time_budget=1e-6)
    x0 = standing_state(bolt)
    com_ref = np.array([0.1, 0.0, 0.3])
    first = mpc.update(0.0, x0, alternating_schedule(0.0, DT, N_NODES), com_ref)
    assert first.ok and first.status in ("converged", "max_iter")  # the cold start has no budget
    second = mpc.update(DT, first.xs[1], alternating_schedule(DT, DT, N_NODES), com_ref)
    assert second.ok and second.status == "deadline" and second.iterations == 1
    assert np.all(np.isfinite(second.K)) and np.all(np.isfinite(second.us))


@pytest.mark.parametrize("budget", [0.0, -0.01, float("inf"), "9 ms", True])
def test_time_budget_is_checked(bolt, budget):
    with pytest.raises(ParameterError, match="time_budget="):
        WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT, time_budget=budget)
