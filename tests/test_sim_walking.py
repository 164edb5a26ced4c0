"""The walking controller in closed loop: a short walk, an injected MPC failure, the prepared MPC,
the time budget, determinism (its parts alone: tests/test_walking_parts.py)."""

from __future__ import annotations

import numpy as np
import pytest

from sim import run_scenario
from wbmpc.errors import ParameterError
from wbmpc.walking import WalkingControllerConfig
from wbmpc.walking.controller import MPC_STATUS_CODES


@pytest.fixture(scope="module")
def short_walk():
    """3 s of walking with two consecutive MPC updates discarded at t = 1.0 and 1.01 s."""
    return run_scenario("walk", duration=3.0, seed=0, mpc_failure_times=(1.0, 1.01), progress=False)


@pytest.mark.slow
def test_short_walk_completes_without_falling(short_walk):
    log = short_walk
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    metrics = log.metrics
    assert metrics["steps"] >= 6
    # command ramped 0 -> 0.33 m/s over 2 s (0.66 m in 3 s, ~0.7 m walked with the LIPM corrections;
    # 1.3 m when the touchdowns hovered and the sequencer ignored the swing drift, docs/closed_loop.md)
    assert 0.3 < metrics["distance_x"] < 1.2
    assert metrics["mpc_failures"] == 2  # only the injected ones
    # the stance foot alternates and the executed footholds move forward
    stance = log.replans["stance_foot"][log.replans["stance_switched"] > 0.5]
    assert np.all(np.diff(stance) != 0)


@pytest.mark.slow
def test_injected_mpc_failure_is_survived_and_logged(short_walk):
    replans = short_walk.replans
    injected = replans["mpc_injected_failure"] > 0.5
    np.testing.assert_allclose(replans["t"][injected], [1.0, 1.01], atol=1e-9)
    assert np.all(replans["mpc_ok"][injected] == 0.0)
    # while the MPC is down the 1 kHz loop follows the last good solution, 10 then 20 ms old
    np.testing.assert_allclose(replans["mpc_reference_age"][injected], [0.01, 0.02], atol=1e-9)
    after = np.flatnonzero(injected)[-1] + 1
    assert replans["mpc_ok"][after] == 1.0 and replans["mpc_reference_age"][after] == 0.0


def test_prepared_mpc_gives_the_same_closed_loop():
    """WalkingMPC.prepare (the default) moves derivative work ahead of the measurement and changes
    nothing else: the same torques to the last bit, through re-timed touchdowns and a failed update."""
    kwargs = dict(duration=1.2, seed=0, mpc_failure_times=(1.0,), progress=False)
    plain = run_scenario("walk", mpc_prepare=False, **kwargs)
    prepared = run_scenario("walk", **kwargs)
    np.testing.assert_array_equal(plain.ticks["tau"], prepared.ticks["tau"])
    used = prepared.replans["mpc_prepared_used"][1:]
    assert np.nanmedian(used) >= 97  # of 99 prepared nodes; re-timed contact switches are recomputed
    assert "mpc_prepared_used" not in plain.replans or np.nanmax(plain.replans["mpc_prepared_used"]) == 0
    assert prepared.metrics["mpc_cycle_time_median"] > prepared.metrics["mpc_tick_time_median"]
    # each update runs its accepted rollout and the rejected line-search trials, all logged
    np.testing.assert_array_equal(plain.replans["mpc_rollouts"], prepared.replans["mpc_rollouts"])
    ok = prepared.replans["mpc_ok"] == 1.0
    assert np.all(prepared.replans["mpc_rollouts"][ok] >= 1)


def test_real_time_factor_is_of_the_loop_without_the_setup(short_walk):
    """The setup (models, buffers, the controller's reset and cold first solve) is timed apart."""
    timing, metrics = short_walk.timing, short_walk.metrics
    assert timing["setup"] > 0 and timing["loop"] > 0
    assert timing["setup"] + timing["loop"] == pytest.approx(timing["total"])
    assert metrics["real_time_factor"] == pytest.approx(3.0 / timing["loop"])
    assert metrics["setup_time"] == timing["setup"]
    # the first replan (the cold solve) is in the setup, the warm updates in the loop (the loop's until session 25)
    ticks = short_walk.replans["mpc_tick_time"]
    assert timing["setup"] > timing["cold_start"] >= ticks[0] > 0
    assert timing["replan"] >= np.sum(ticks[1:])


def test_mpc_time_budget_reaches_the_mpc_and_is_logged():
    """A budget too short for more than one rollout cuts the line search: status "deadline" (code
    4) in the log, and the loop goes on."""
    log = run_scenario("walk", duration=0.3, seed=0, progress=False, mpc_time_budget=1e-6)
    codes = log.replans["mpc_status_code"][1:]  # the cold start has no budget
    assert log.status == "completed" and np.all(log.replans["mpc_ok"] == 1.0)
    assert np.any(codes == MPC_STATUS_CODES["deadline"])
    with pytest.raises(ParameterError, match=r"mpc_time_budget=0 must be None or a number of seconds"):
        WalkingControllerConfig(mpc_time_budget=0)


def test_same_seed_same_walking_log():
    kwargs = dict(duration=0.15, seed=3, noise_q=1e-4, noise_v=1e-3, progress=False)
    a = run_scenario("walk", **kwargs)
    b = run_scenario("walk", **kwargs)
    for key in ("x", "tau", "dcm", "feet"):
        np.testing.assert_array_equal(a.ticks[key], b.ticks[key], err_msg=key)
    np.testing.assert_array_equal(a.replans["mpc_cost"], b.replans["mpc_cost"])


@pytest.mark.slow
def test_bolt_walks_sideways_on_a_lateral_command():
    """v_y = 0.1 m/s (heading frame): Bolt steps to the left, without turning."""
    log = run_scenario("walk", duration=3.0, seed=0, velocity_command=(0.0, 0.1, 0.0), ramp_time=1.0, progress=False)
    assert log.status == "completed", (log.fall_time, log.fall_reason)
    moved = log.ticks["x"][-1, :2] - log.ticks["x"][0, :2]
    assert 0.12 < moved[1] < 0.35 and abs(moved[0]) < 0.08, moved
    assert np.all(log.replans["sequencer_v_y"][log.replans["t"] >= 1.0] == pytest.approx(0.1))


def test_a_command_the_robot_cannot_follow_is_refused_before_the_run():
    with pytest.raises(ParameterError, match=r"yaw_rate=0.2 rad/s for robot 'bolt' must be 0 rad/s \(Bolt's legs"):
        run_scenario("walk", duration=0.1, velocity_command=(0.2, 0.0, 0.2))
    with pytest.raises(ParameterError, match=r"v_x=0.65 m/s for robot 'bolt' must be in \[-0.3, 0.5\] m/s"):
        run_scenario("walk", duration=0.1, speed=0.65)
    with pytest.raises(ParameterError, match=r"and \['lateral_speed'\] both set the command: give one"):
        run_scenario("walk", duration=0.1, velocity_command=(0.0, 0.1, 0.0), lateral_speed=0.3)


def test_a_planner_failing_until_its_last_plan_runs_out_ends_the_run_with_the_reason_and_the_log(monkeypatch):
    """Every replan's step QP fails from t = 1 s on: the controller follows the last good plan while it covers
    the MPC's horizon, then the run ends with the reason, its log up to then kept (Bolt, blind, falls on the
    way: the fall stays the outcome, recorded first)."""
    from sequencer.dcm_planner import DcmFootstepPlanner
    from wbmpc.errors import SolverError

    healthy = DcmFootstepPlanner.plan

    def failing_after_one_second(self, t, *args, **kwargs):
        if t >= 1.0 - 1e-9:
            raise SolverError("footstep QP failed: injected")
        return healthy(self, t, *args, **kwargs)

    monkeypatch.setattr(DcmFootstepPlanner, "plan", failing_after_one_second)
    log = run_scenario("walk", duration=4.0, seed=0, stop_on_fall=False, progress=False)
    assert log.status == "fell" and 1.0 < log.fall_time, (log.status, log.fall_reason, log.error)
    assert log.error.startswith("the footstep planner has failed at every replan since t=1.000 s"), log.error
    assert "SolverError: footstep QP failed: injected" in log.error and "nothing left to follow" in log.error
    replans = log.replans
    after = replans["t"] >= 1.0 - 1e-9
    assert np.all(replans["sequencer_ok"][after] == 0.0) and np.all(replans["sequencer_ok"][~after] == 1.0)
    t_end = replans["t"][-1]
    assert 1.5 < t_end < 4.0 - 0.5 and log.ticks["t"][-1] >= t_end  # the kept plan's steps ran out
