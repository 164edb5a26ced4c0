"""RecedingHorizonMPC(restart_after_failures=): after consecutive failed updates the next one starts cold."""

from __future__ import annotations

import numpy as np
import pytest
from wbmpc_fixtures import alternating_schedule, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.mpc import RecedingHorizonMPC
from wbmpc.walking import WalkingControllerConfig, WalkingMPC, WalkingOCPConfig

T, NX, NU = 4, 2, 1
COLD_U = 7.0  # the quasi-static guess's control


class _State:
    nx = ndx = NX

    def check_state(self, name, x):
        x = np.asarray(x, dtype=float)
        if x.shape != (NX,) or not np.all(np.isfinite(x)):
            raise ParameterError(f"{name} is not a finite ({NX},) state")
        return x


class _Problem:
    """The few members RecedingHorizonMPC reads (no running models: horizon_end="repeat")."""

    T, nx, ndx, nu = T, NX, NX, NU
    state = _State()

    def set_x0(self, x):
        self.x0 = x


class _Solver:
    """Fails every warm-started solve while ``broken`` (as the H1's shifted plans do after a failed update);
    a cold guess (controls COLD_U) succeeds and repairs it. Records each solve's (cold, maxiter, deadline)."""

    reg_max = 1e9

    def __init__(self):
        self.broken = False
        self.calls = []
        self.log, self.preg, self.deadline_hit = [], 0.0, False

    def solve(self, init_xs, init_us, maxiter=100, is_feasible=False, deadline=None):
        cold = bool(np.all(init_us == COLD_U))
        self.calls.append((cold, maxiter, deadline))
        self.log = [None] * maxiter
        if cold:
            self.broken = False
        ok = not self.broken
        self.xs = np.array(init_xs, dtype=float)
        self.us = np.array(init_us, dtype=float) + (1.0 if ok else np.nan)  # a plan differs from a guess
        self.K = np.zeros((T, NU, NX))
        self.cost = 1.0 if ok else np.nan
        return ok


def _mpc(restart, **kwargs):
    solver = _Solver()
    mpc = RecedingHorizonMPC(_Problem(), 0.01, initial_controls=lambda x: np.full(NU, COLD_U), solver=solver,
                             max_iterations=1, cold_start_iterations=5, restart_after_failures=restart, **kwargs)
    return mpc, solver


def _run(mpc, solver, n, break_at=1):
    solutions = []
    for i in range(n):
        if i == break_at:
            solver.broken = True
        solutions.append(mpc.update(0.01 * i, np.array([0.01 * i, 0.0])))
    return solutions


def test_without_restart_the_warm_starts_keep_failing():
    mpc, solver = _mpc(None)
    solutions = _run(mpc, solver, 8)
    assert solutions[0].ok and [s.ok for s in solutions[1:]] == [False] * 7
    assert not any(s.restart for s in solutions)
    assert [cold for cold, _, _ in solver.calls] == [True] + [False] * 7


@pytest.mark.parametrize("after", [1, 3])
def test_restart_after_the_given_count_of_failures(after):
    mpc, solver = _mpc(after, time_budget=0.5)
    solutions = _run(mpc, solver, 8)
    # update 0 cold and good; updates 1..after fail warm; update after + 1 restarts cold and succeeds
    assert [s.ok for s in solutions[1:after + 1]] == [False] * after
    restart = solutions[after + 1]
    assert restart.ok and restart.restart and restart.status in ("converged", "max_iter")
    cold, maxiter, deadline = solver.calls[after + 1]
    assert cold and maxiter == 5 and deadline is None  # cold_start_iterations, no time budget
    assert all(s.ok and not s.restart for s in solutions[after + 2:])
    assert mpc.last_good is solutions[-1] and mpc.failures == 0


def test_a_failed_restart_keeps_the_last_good_plan_and_counts_again():
    mpc, solver = _mpc(2)
    good = mpc.update(0.0, np.zeros(NX))
    # the measured state is not finite: the update fails before any guess, whatever the guess would be
    bad = np.array([np.nan, 0.0])
    solutions = [mpc.update(0.01 * i, bad) for i in range(1, 7)]
    assert [s.ok for s in solutions] == [False] * 6
    assert [s.restart for s in solutions] == [False, False, True, False, True, False]
    for i, s in enumerate(solutions, start=1):  # each failure reports the last good plan, shifted to t
        assert s.t == pytest.approx(0.01 * i) and np.array_equal(s.us, good.us) and s.cost == good.cost
    assert mpc.last_good is good
    recovered = mpc.update(0.07, np.zeros(NX))  # two failures since the failed restart: restart
    assert recovered.ok and recovered.restart and solver.calls[-1][0]


def test_no_restart_before_a_first_good_update():
    mpc, solver = _mpc(1)
    first = [mpc.update(0.01 * i, np.array([np.nan, 0.0])) for i in range(3)]
    assert not any(s.ok or s.restart for s in first)  # the first update is cold anyway: nothing to restart
    assert mpc.update(0.03, np.zeros(NX)).ok and solver.calls == [(True, 5, None)]


@pytest.mark.parametrize("value", [-1, 1.5, True, "2"])
def test_bad_values_are_refused(value):
    with pytest.raises(ParameterError, match="restart_after_failures="):
        _mpc(value)
    with pytest.raises(ParameterError, match="mpc_restart_after_failures="):
        WalkingControllerConfig(mpc_restart_after_failures=value)


@pytest.mark.parametrize("value", [None, 0])
def test_none_and_zero_mean_never(value):
    mpc, solver = _mpc(value)
    assert not any(s.restart for s in _run(mpc, solver, 6))


def test_walking_mpc_recovers_bolt_by_a_restart():
    """The real OCP: an update whose problem update raises fails, the next one restarts cold and succeeds."""
    bolt = load_robot("bolt")
    n, dt = 40, 0.01
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=n, dt=dt, max_iterations=1, cold_start_iterations=3,
                     restart_after_failures=1)
    x0 = standing_state(bolt)
    com = np.array([0.0, 0.0, 0.3])
    first = mpc.update(0.0, x0, alternating_schedule(0.0, dt, n), com)
    assert first.ok and not first.restart
    failed = mpc.update(dt, first.xs[1], alternating_schedule(dt, dt, n), np.array([np.nan, 0.0]))  # bad reference
    assert not failed.ok and not failed.restart and np.array_equal(failed.us, first.us[[*range(1, n), n - 1]])
    restarted = mpc.update(2 * dt, first.xs[2], alternating_schedule(2 * dt, dt, n), com)
    assert restarted.ok and restarted.restart and restarted.iterations <= 3
    assert mpc.last_good is restarted
    assert mpc.update(3 * dt, restarted.xs[1], alternating_schedule(3 * dt, dt, n), com).restart is False
