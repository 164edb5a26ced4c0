"""The walking controller in closed loop: a short walk, an injected MPC failure, determinism, and the
1 kHz feedback law (eqs. 25-26 with the library's gain convention) on a known reference."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from robots import load_robot
from sim import WalkingController, WalkingControllerConfig, run_scenario
from wbmpc.errors import ParameterError
from wbmpc.walking.controller import MPC_STATUS_CODES, _Reference
from wbmpc.walking.measurement import Measurement


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


@pytest.fixture(scope="module")
def controller_with_known_reference():
    """A walking controller whose MPC solution is replaced by a synthetic one (random xs, us, K)."""
    robot = load_robot("bolt")
    model = robot.pinocchio_model
    rng = np.random.default_rng(0)
    n, nu, ndx = 5, robot.nu, 2 * model.nv
    xs = np.array([np.concatenate([pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)),
                                   rng.normal(size=model.nv)]) for _ in range(n + 1)])
    reference = _Reference(t=0.5, xs=xs, us=rng.normal(size=(n, nu)), K=rng.normal(size=(n, nu, ndx)))
    x0 = np.concatenate([robot.q_reference, np.zeros(model.nv)])

    def make(**options):
        controller = WalkingController(WalkingControllerConfig(n_nodes=n, **options))
        controller.reset(robot, x0, 0.0)
        controller.reference = reference
        return controller

    x_meas = np.concatenate([pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)),
                             rng.normal(size=model.nv)])
    return make, reference, model, Measurement(0.0, x_meas, np.array([True, False]))


def _feedback(model, reference, k, x):
    nq = model.nq
    dx = np.concatenate([pin.difference(model, reference.xs[k][:nq], x[:nq]), x[nq:] - reference.xs[k][nq:]])
    return reference.us[k] + reference.K[k] @ dx


def test_feedback_law_uses_node_one_by_default_and_the_library_gain_sign(controller_with_known_reference):
    make, reference, model, measurement = controller_with_known_reference
    controller = make()
    # 3 ms after the solution: node 1 (paper's delay model)
    tau = controller.compute(0.503, measurement)
    np.testing.assert_allclose(tau, _feedback(model, reference, 1, measurement.x), rtol=1e-12, atol=1e-12)
    # 12 ms after (a failed update in between): node 2 of the same solution
    tau = controller.compute(0.512, measurement)
    np.testing.assert_allclose(tau, _feedback(model, reference, 2, measurement.x), rtol=1e-12, atol=1e-12)


def test_feedback_options_no_delay_no_feedback_interpolation(controller_with_known_reference):
    make, reference, model, measurement = controller_with_known_reference
    tau = make(delay_nodes=0).compute(0.503, measurement)
    np.testing.assert_allclose(tau, _feedback(model, reference, 0, measurement.x), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(make(feedback=False).compute(0.503, measurement), reference.us[1])
    # interpolation at 30 % of the way from node 1 to node 2 (feed-forward part)
    tau = make(feedback=False, interpolate=True).compute(0.503, measurement)
    np.testing.assert_allclose(tau, 0.7 * reference.us[1] + 0.3 * reference.us[2], rtol=1e-9)


def test_computation_delay_applies_a_new_solution_only_after_the_latency(controller_with_known_reference):
    make, reference, model, measurement = controller_with_known_reference
    controller = make(delay_nodes=0, computation_delay=0.01, feedback=False)
    newer = _Reference(t=0.51, xs=reference.xs, us=reference.us + 100.0, K=reference.K)
    controller._pending.append((0.52, newer))
    # at 0.515 s the solution of 0.51 s is still being "computed": node 1 of the 0.5 s one
    np.testing.assert_array_equal(controller.compute(0.515, measurement), reference.us[1])
    # from 0.52 s on the newer one applies, at its node 1 (10 ms after its own t)
    np.testing.assert_array_equal(controller.compute(0.52, measurement), newer.us[1])


def test_a_due_touchdown_not_yet_measured_is_delayed_in_the_schedule():
    from sequencer import FootstepSequencer, SequencerParams
    from wbmpc.walking.controller import TOUCHDOWN_WAIT_NODES, _wait_for_touchdown

    plan = FootstepSequencer(SequencerParams.bolt_walking()).plan(
        t=0.0, stance_foot="left", stance_position=[0.0, 0.05], dcm_measured=[0.0, 0.0], t_stance_start=0.0
    )
    first = plan.steps[0].touchdown_time
    t = first - 0.005  # touchdown due in 5 ms, the foot still in the air
    delayed, delay = _wait_for_touchdown(plan, t, False, 0.01)
    assert delay == pytest.approx(t + TOUCHDOWN_WAIT_NODES * 0.01 - first)
    np.testing.assert_allclose(delayed.touchdown_times, plan.touchdown_times + delay)
    np.testing.assert_array_equal(delayed.positions, plan.positions)
    same, no_delay = _wait_for_touchdown(plan, t, True, 0.01)  # foot already on the ground
    assert same is plan and no_delay == 0.0


def test_speed_integral_acts_on_the_forward_speed_with_anti_windup(controller_with_known_reference):
    make, _, _, _ = controller_with_known_reference
    controller = make(velocity_integral_gain=1.0, velocity_correction_max=0.2)
    controller.set_velocity_command(0.3, 0.0)
    assert controller.sequencer_params.v_x == pytest.approx(0.3)
    for _ in range(1000):  # 10 s standing still while 0.3 m/s forward is asked, drifting sideways
        controller._update_velocity_integral(np.array([0.0, 0.5]))
    assert controller.sequencer_params.v_x == pytest.approx(0.5)  # 0.3 + the 0.2 m/s bound
    assert controller.sequencer_params.v_y == 0.0
    for _ in range(150):  # now too fast: the clamped integral unwinds once the filtered speed passes 0.3
        controller._update_velocity_integral(np.array([0.6, 0.0]))
    assert controller.sequencer_params.v_x < 0.5


def test_lipm_corrections_are_identified_from_undisturbed_steps_only(controller_with_known_reference):
    """Swing drift kappa = DCM gained over the LIPM / step length; offset bias = measured - planned b_T."""
    from types import SimpleNamespace

    make, _, _, _ = controller_with_known_reference
    controller = make(lipm_correction_gain=0.5)
    omega, duration, length, kappa, epsilon = controller.omega, 0.3, 0.1, 0.2, 0.003
    stance, landing = np.array([1.0, 0.05]), np.array([1.0 + length, -0.05])
    planned = np.array([0.017, 0.01])  # the offset the plan aimed at for this touchdown
    # the stance started from b0 and ended epsilon ahead of the plan after the LIPM growth + kappa L
    b0 = ((1.0 - kappa) * length + planned[0] + epsilon) / np.exp(omega * duration)
    plan = SimpleNamespace(steps=(SimpleNamespace(foot="right", dcm_offset=planned),))
    controller._stance_record = (0.0, stance + np.array([b0, 0.0]), stance, True)
    controller.stance.state = dataclasses.replace(controller.stance.state, foot="right", position=landing)
    measured = landing + planned + np.array([epsilon, 0.0])
    assert measured[0] - stance[0] == pytest.approx(b0 * np.exp(omega * duration) + kappa * length)
    controller._update_lipm_corrections(duration, measured, True, plan)
    params = controller.sequencer_params
    assert params.swing_drift == pytest.approx(0.5 * kappa, rel=1e-9)
    assert params.dcm_offset_bias == pytest.approx(0.5 * epsilon, rel=1e-9)
    assert controller.sequencer.params is params  # the sequencer plans with the new model
    # a pushed step (DCM 3 cm off the plan at touchdown) changes nothing, nor does the next one
    controller.stance.state = dataclasses.replace(controller.stance.state, foot="left", position=landing + [0.1, 0.1])
    plan = SimpleNamespace(steps=(SimpleNamespace(foot="left", dcm_offset=np.array([0.02, -0.01])),))
    controller._update_lipm_corrections(0.6, landing + [0.1, 0.1] + [0.05, -0.01], True, plan)
    assert controller.sequencer_params is params
    controller.stance.state = dataclasses.replace(controller.stance.state, foot="right", position=landing + [0.2, 0.0])
    plan = SimpleNamespace(steps=(SimpleNamespace(foot="right", dcm_offset=np.array([0.02, 0.01])),))
    controller._update_lipm_corrections(0.9, landing + [0.2, 0.0] + [0.02, 0.01], True, plan)
    assert controller.sequencer_params is params
    with pytest.raises(ParameterError, match=r"lipm_correction_gain=1.5 must be in \[0, 1\]"):
        WalkingControllerConfig(lipm_correction_gain=1.5)
    with pytest.raises(ParameterError, match=r"mpc_prepare='yes' must be True or False"):
        WalkingControllerConfig(mpc_prepare="yes")
    with pytest.raises(ParameterError, match=r"mpc_horizon_end='last' must be one of \('rollout', 'repeat'\)"):
        WalkingControllerConfig(mpc_horizon_end="last")


def test_a_step_whose_stance_foot_slid_is_not_used_for_the_lipm_corrections(controller_with_known_reference):
    """The swing drift is measured against the touchdown point: a slid stance foot is excluded."""
    from types import SimpleNamespace

    from wbmpc.walking.controller import LIPM_CORRECTION_MAX_SLIDE

    make, _, _, _ = controller_with_known_reference
    stance, landing = np.array([1.0, 0.05]), np.array([1.1, -0.05])
    plan = SimpleNamespace(steps=(SimpleNamespace(foot="right", dcm_offset=np.array([0.017, 0.01])),))
    measured = landing + np.array([0.018, 0.01])  # 1 mm from the plan: an undisturbed touchdown otherwise
    for slide, used in ((2.0 * LIPM_CORRECTION_MAX_SLIDE, False), (0.5 * LIPM_CORRECTION_MAX_SLIDE, True)):
        controller = make(lipm_correction_gain=0.5)
        before = controller.sequencer_params
        controller._stance_record = (0.0, stance + np.array([0.01, 0.0]), stance, True)
        controller.stance.state = dataclasses.replace(controller.stance.state, foot="right", position=landing)
        controller._update_lipm_corrections(0.3, measured, True, plan, ended_slide=slide)
        assert (controller.sequencer_params is not before) == used
        assert len(controller.lipm_correction_steps) == int(used)


def test_the_sequencer_plans_from_a_sliding_stance_foot(controller_with_known_reference):
    make, _, _, _ = controller_with_known_reference
    controller = make(stance_slide_follow=0.02)
    touchdown = controller.stance.state.position.copy()  # left foot in stance since t = 0
    feet = np.zeros((2, 3))
    contact = np.array([True, False])

    def at(offset, in_contact=contact, switched=False):
        feet[0, :2] = touchdown + offset
        slide = controller._measure_stance_slide(feet)
        return controller._update_stance_slide(switched, slide, feet, in_contact)

    at([0.005, 0.01])  # rolling: the touchdown point is kept
    np.testing.assert_array_equal(controller._stance_plan_position, touchdown)
    at([0.01, 0.05])  # a slide: the sequencer plans from the measured foot
    np.testing.assert_allclose(controller._stance_plan_position, touchdown + [0.01, 0.05])
    at([0.01, 0.08], in_contact=np.array([False, False]))  # bouncing off the ground: kept
    np.testing.assert_allclose(controller._stance_plan_position, touchdown + [0.01, 0.05])
    assert controller.stance.state.position == pytest.approx(touchdown)  # the touchdown point itself is kept (metrics)
    # at the next touchdown: the largest slide of the stance that ended, then a fresh stance
    controller.stance.state = dataclasses.replace(controller.stance.state, foot="right", position=np.array([0.2, -0.1]))
    feet[1, :2] = [0.2, -0.1]
    ended = controller._update_stance_slide(True, controller._measure_stance_slide(feet), feet, np.array([True, True]))
    assert ended == pytest.approx(np.hypot(0.01, 0.08))
    np.testing.assert_array_equal(controller._stance_plan_position, [0.2, -0.1])
    assert controller._stance_slide == 0.0
    # off: the touchdown point for the whole stance
    controller = make(stance_slide_follow=None)
    at([0.01, 0.05])
    np.testing.assert_array_equal(controller._stance_plan_position, touchdown)
    with pytest.raises(ParameterError, match=r"stance_slide_follow=-0.01 m must be None or > 0"):
        WalkingControllerConfig(stance_slide_follow=-0.01)
