"""WalkingMPC: the predicted motion walks, warm starts shift, failures keep the last good plan."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from wbmpc_fixtures import alternating_schedule, standing_state

from robots import load_robot
from wbmpc.ocp import MPCSolution
from wbmpc.walking import WalkingMPC, WalkingOCPConfig
from wbmpc.walking.ocp import swing_height_reference

N_NODES, DT = 100, 0.01


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


@pytest.fixture(scope="module")
def walking(bolt):
    """A cold solve (30 iterations) of the default Bolt walking OCP, then 3 warm ticks."""
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT, max_iterations=1, cold_start_iterations=30)
    x0 = standing_state(bolt)
    com_ref = np.array([0.3, 0.0, 0.3])
    first = mpc.update(0.0, x0, alternating_schedule(0.0, DT, N_NODES), com_ref)
    ticks = [first]
    for i in range(1, 4):
        t = i * DT
        ticks.append(mpc.update(t, ticks[-1].xs[1], alternating_schedule(t, DT, N_NODES), com_ref + [0.0033 * i, 0, 0]))
    return mpc, ticks


def test_predicted_motion_walks(bolt, walking):
    mpc, ticks = walking
    solution = ticks[0]
    assert solution.ok and solution.status in ("converged", "max_iter")
    model = bolt.pinocchio_model
    data = model.createData()
    config = mpc.config
    ground = bolt.contact_frame_height
    feet = {foot: model.getFrameId(name) for foot, name in bolt.foot_frames.items()}
    heights = {foot: [] for foot in feet}
    coms = []
    for x in solution.xs:
        q = x[: model.nq]
        pin.framesForwardKinematics(model, data, q)
        coms.append(pin.centerOfMass(model, data, q))
        for foot, fid in feet.items():
            heights[foot].append(data.oMf[fid].translation[2] - ground)
    coms = np.array(coms)
    # the first swing (right foot, nodes 0..30) lifts the foot towards the apex H of eq. (19)
    apex = max(heights["right"][:30])
    assert 0.6 * config.swing_apex_height < apex < 1.4 * config.swing_apex_height
    assert max(heights["left"][30:60]) > 0.6 * config.swing_apex_height
    # stance feet stay on the ground
    assert abs(heights["left"][15]) < 5e-3 and abs(heights["right"][45]) < 5e-3
    # the CoM moves forward towards the terminal reference and stays at walking height
    assert coms[-1, 0] - coms[0, 0] > 0.2
    assert np.all(coms[:, 2] > 0.25)
    assert np.all(np.abs(solution.us) < 1.2 * bolt.torque_limit)
    np.testing.assert_allclose(swing_height_reference(0.5, 0.05), 0.05)


def test_update_returns_the_contract(bolt, walking):
    mpc, ticks = walking
    nx, ndx, nu = mpc.ocp.state.nx, mpc.ocp.state.ndx, mpc.ocp.nu
    for i, solution in enumerate(ticks):
        assert isinstance(solution, MPCSolution)
        assert solution.ok, solution.status
        assert solution.t == pytest.approx(i * DT)
        assert solution.xs.shape == (N_NODES + 1, nx)
        assert solution.us.shape == (N_NODES, nu)
        assert solution.K.shape == (N_NODES, nu, ndx)
        np.testing.assert_array_equal(solution.K(1), solution.K[1])
        np.testing.assert_array_equal(solution.u(1), solution.us[1])
        np.testing.assert_array_equal(solution.x(0), solution.xs[0])
    assert [s.iterations for s in ticks[1:]] == [1, 1, 1]
    # warm start: node 0 is the measurement, the rest the previous plan shifted by one node
    xs_init, us_init, cold = mpc.warm_start(4 * DT, ticks[-1].xs[1])
    assert not cold
    np.testing.assert_array_equal(us_init[:-1], ticks[-1].us[1:])
    np.testing.assert_array_equal(xs_init[0], ticks[-1].xs[1])
    np.testing.assert_array_equal(xs_init[1:-1], ticks[-1].xs[2:])


def test_warm_start_extends_the_horizon_end_without_a_gap(bolt):
    """The node entering at the end takes the control of the latest node with its contact set and
    its successor state is the node's dynamics: no gap at the end, also when the contact set of
    the new node differs from its predecessor's (a step starts at the end of the horizon)."""
    n = 40
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=n, dt=DT, max_iterations=1, cold_start_iterations=10,
                     horizon_end="rollout")
    com_ref = np.array([0.3, 0.0, 0.3])
    solution = mpc.update(0.18, standing_state(bolt), alternating_schedule(0.18, DT, n), com_ref)
    switches = 0
    for t in (0.19, 0.20, 0.21, 0.22):  # node n - 1 reaches the touchdown at 0.6 s at t = 0.21
        x = solution.xs[1]
        mpc.ocp.update(x, alternating_schedule(t, DT, n), com_ref)
        xs, us, cold = mpc.warm_start(t, x)
        assert not cold
        models, datas = mpc.problem.running_models, mpc.problem.running_datas
        keys = [m.differential.active_key for m in models]
        models[n - 1].calc(datas[n - 1], xs[n - 1], us[n - 1])
        np.testing.assert_allclose(xs[n], datas[n - 1].xnext, rtol=0, atol=1e-12)
        same = max(i for i in range(n - 1) if keys[i] == keys[n - 1])
        np.testing.assert_array_equal(us[n - 1], us[same])
        switches += keys[n - 1] != keys[n - 2]
        solution = mpc.update(t, x, alternating_schedule(t, DT, n), com_ref)
        assert solution.ok
    assert switches == 1


def test_failures_keep_the_last_good_solution(bolt, walking):
    mpc, ticks = walking
    last = mpc.last_good
    bad_state = np.full(mpc.ocp.state.nx, np.nan)
    failed = mpc.update(last.t + DT, bad_state, alternating_schedule(last.t + DT, DT, N_NODES), np.zeros(3))
    assert not failed.ok and failed.status.startswith("failed: ")
    assert "x_measured" in failed.status
    np.testing.assert_array_equal(failed.us[0], last.us[1])
    assert failed.t == pytest.approx(last.t + DT)
    wrong_grid = mpc.update(last.t + DT, last.xs[1], alternating_schedule(last.t + DT, DT, N_NODES - 5), np.zeros(3))
    assert not wrong_grid.ok and "n_nodes" in wrong_grid.status
    assert mpc.last_good is last


def test_first_update_failure_has_no_plan(bolt):
    mpc = WalkingMPC(bolt, n_nodes=10, dt=DT)
    x0 = standing_state(bolt)
    failed = mpc.update(0.0, x0, alternating_schedule(0.0, DT, 10), np.array([np.nan, 0.0, 0.3]))
    assert not failed.ok and "com_terminal_reference" in failed.status
    assert np.isnan(failed.cost)


def test_an_update_can_run_its_own_number_of_iterations(bolt):
    """``update(max_iterations=)``: that many FDDP iterations for this warm-started update only (th_stop 0: none
    converges early); a bad value is a ParameterError, the update is not run."""
    from wbmpc.errors import ParameterError

    mpc = WalkingMPC(bolt, WalkingOCPConfig(th_stop=0.0), n_nodes=10, dt=DT, max_iterations=1, cold_start_iterations=3)
    x0 = standing_state(bolt)
    schedule, com = alternating_schedule(0.0, DT, 10), np.array([0.0, 0.0, 0.3])
    assert mpc.update(0.0, x0, schedule, com).iterations == 3  # the cold start
    assert mpc.update(0.0, x0, schedule, com, max_iterations=4).iterations == 4
    assert mpc.update(0.0, x0, schedule, com).iterations == 1
    for bad in (0, 1.5, True):
        with pytest.raises(ParameterError, match=f"max_iterations={bad!r} must be None or an integer >= 1"):
            mpc.update(0.0, x0, schedule, com, max_iterations=bad)


def test_constructor_rejects_bad_parameters(bolt):
    from wbmpc.errors import ParameterError

    with pytest.raises(ParameterError, match="max_iterations=0"):
        WalkingMPC(bolt, n_nodes=10, dt=DT, max_iterations=0)
    with pytest.raises(ParameterError, match="dt=-0.01"):
        WalkingMPC(bolt, n_nodes=10, dt=-0.01)
    with pytest.raises(ParameterError, match="horizon_end='zeros' must be one of"):
        WalkingMPC(bolt, n_nodes=10, dt=DT, horizon_end="zeros")


def test_repeat_horizon_end_is_the_plain_shift(bolt, walking):
    """horizon_end="repeat" (the default): the last node's state and control repeated (the usual shift)."""
    mpc, ticks = walking
    assert mpc.receding.horizon_end == "repeat"
    plain = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=N_NODES, dt=DT, horizon_end="repeat")
    plain.last_good = ticks[-1]
    xs, us, _ = plain.warm_start(4 * DT, ticks[-1].xs[1])
    np.testing.assert_array_equal(us[-1], ticks[-1].us[-1])
    np.testing.assert_array_equal(xs[-1], ticks[-1].xs[-1])
    np.testing.assert_array_equal(xs[-2], ticks[-1].xs[-1])
