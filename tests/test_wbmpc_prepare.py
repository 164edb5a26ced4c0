"""WalkingMPC.prepare: derivatives computed ahead give the same updates, to the last bit."""

from __future__ import annotations

import time

import numpy as np
import pytest
from wbmpc_fixtures import alternating_schedule, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.walking import WalkingMPC, WalkingOCPConfig

N_NODES, DT = 40, 0.01
COM_REF = np.array([0.3, 0.0, 0.3])


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


# terms reading the contact forces: their forces and derivatives are prepared too
FORCE_TERMS = WalkingOCPConfig(contact_force_weight=1e-2, friction_cone_weight=10.0)


def _pair(bolt, horizon_end, config=None):
    config = WalkingOCPConfig() if config is None else config
    make = lambda: WalkingMPC(bolt, config, n_nodes=N_NODES, dt=DT, max_iterations=1,  # noqa: E731
                              cold_start_iterations=10, horizon_end=horizon_end)
    return make(), make()


def _assert_same(a, b):
    assert a.ok == b.ok and a.status == b.status
    np.testing.assert_array_equal(a.us, b.us)
    np.testing.assert_array_equal(a.xs, b.xs)
    np.testing.assert_array_equal(a.K, b.K)


@pytest.mark.parametrize("horizon_end,config", [("repeat", None), ("rollout", None), ("rollout", FORCE_TERMS)])
def test_prepared_updates_equal_plain_ones(bolt, horizon_end, config):
    """Ticks one node apart, a re-timed schedule (every touchdown one node later), a skipped tick
    and a failed update: each update is bit-identical with and without preparation, and the
    preparation is used where the guess and the contact sets match, not elsewhere."""
    plain, prepared = _pair(bolt, horizon_end, config)
    assert prepared.ocp.evaluation == "batched"
    assert prepared.prepare() == 0  # no solution yet
    x = standing_state(bolt)
    # (time [s], start of the gait [s] (0.01: re-timed), measured state is NaN)
    ticks = [(0.00, 0.0, False), (0.01, 0.0, False), (0.02, 0.0, False), (0.03, 0.01, False),
             (0.05, 0.01, False), (0.06, 0.01, True), (0.07, 0.01, False), (0.08, 0.01, False)]
    used = []
    for t, t_start, failed in ticks:
        schedule = alternating_schedule(t, DT, N_NODES, t_start=t_start)
        measured = np.full_like(x, np.nan) if failed else x
        a = plain.update(t, measured, schedule, COM_REF)
        b = prepared.update(t, measured, schedule, COM_REF)
        _assert_same(a, b)
        assert a.ok != failed
        used.append(prepared.problem.prepared_used)
        assert prepared.prepare() == N_NODES - 1
        if not failed:
            x = a.xs[1].copy()
            x[prepared.ocp.state.nq:] += 0.01  # a measured state off the prediction
    # normal ticks: every prepared node but the entering one (its contact set may have changed)
    assert used[1] >= N_NODES - 2 and used[2] >= N_NODES - 2
    assert used[3] < used[2]  # re-timed: the nodes whose contact set changed are recomputed
    # two nodes later, and after a failure (the guess comes from an older solution), no node
    # matches but, with the repeated horizon end, the last one (the same state and control)
    assert used[4] <= (horizon_end == "repeat")
    assert used[6] <= (horizon_end == "repeat")
    assert used[7] >= N_NODES - 2


def test_a_prepare_deadline_prepares_fewer_nodes_and_the_update_computes_the_rest(bolt):
    plain, prepared = _pair(bolt, "rollout")
    x = standing_state(bolt)
    for i, t in enumerate((0.0, 0.01, 0.02)):
        schedule = alternating_schedule(t, DT, N_NODES)
        a = plain.update(t, x, schedule, COM_REF)
        b = prepared.update(t, x, schedule, COM_REF)
        _assert_same(a, b)
        if i == 1:
            assert prepared.problem.prepared_used == 0  # the deadline had passed: nothing prepared
        deadline = time.perf_counter() - 1.0 if i == 0 else None
        assert prepared.prepare(deadline=deadline) == (0 if i == 0 else N_NODES - 1)
        x = a.xs[1]
    with pytest.raises(ParameterError, match="deadline=nan must be a finite"):
        prepared.prepare(deadline=float("nan"))


def test_several_iterations_and_node_wise_evaluation(bolt):
    """With 3 iterations per update the preparation serves the first one only (same results);
    a problem evaluated node by node has nothing to prepare."""
    make = lambda: WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT, max_iterations=3,  # noqa: E731
                              cold_start_iterations=10)
    plain, prepared = make(), make()
    nodes = WalkingMPC(bolt, WalkingOCPConfig(evaluation="nodes"), n_nodes=N_NODES, dt=DT, cold_start_iterations=10)
    first_iteration_used = []  # prepared nodes taken by each update's first calcDiff
    prepared.solver.callbacks.append(
        lambda solver: first_iteration_used.append(solver.problem.prepared_used) if len(solver.log) == 1 else None)
    x = standing_state(bolt)
    for t in (0.0, 0.01, 0.02):
        schedule = alternating_schedule(t, DT, N_NODES)
        a = plain.update(t, x, schedule, COM_REF)
        b = prepared.update(t, x, schedule, COM_REF)
        _assert_same(a, b)
        assert b.iterations > 1
        prepared.prepare()
        assert nodes.update(t, x, schedule, COM_REF).ok and nodes.prepare() == 0
        x = a.xs[1]
    assert first_iteration_used[0] == 0 and min(first_iteration_used[1:]) >= N_NODES - 2
    assert prepared.problem.prepared_used == 0  # later iterations compute every node


def test_prepare_dynamics_rejects_bad_shapes(bolt):
    mpc = WalkingMPC(bolt, n_nodes=10, dt=DT)
    nx, nu = mpc.ocp.state.nx, mpc.ocp.nu
    with pytest.raises(ParameterError, match=r"prepare_dynamics: xs \(9, 25\)"):
        mpc.problem.prepare_dynamics(np.zeros((9, nx)), np.zeros((10, nu)), [None] * 10)
