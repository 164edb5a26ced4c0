"""The ALIP planner behind the FootstepPlanner interface: plan structure, eq. 16, the CoM reference is the
ALIP prediction, the measured state, push recovery on the ALIP itself, the G1 preset against the robot."""

import math

import numpy as np
import pytest
from robot_extras import needs_h1_extra

from sequencer import FootstepPlanner, ReducedState, StanceState, VelocityCommand, contact_schedule
from sequencer.alip.nlp import AlipSolverError
from sequencer.alip.params import AlipParams
from sequencer.alip.planner import AlipFootstepPlanner, desired_orbit
from sequencer.alip.s2s import B_D, heading_change_entries
from wbmpc.errors import ParameterError, SolverError

PARAMS = AlipParams.preset("g1")


def rot(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array(((c, -s), (s, c)))


def standing(yaw=0.0):
    stance = StanceState("left", [0.03, 0.11], yaw, 0.0)
    com = np.array([0.03, 0.0, PARAMS.com_height])
    com[:2] = stance.position + rot(yaw) @ np.array([0.0, -0.11])
    return stance, ReducedState(com, np.zeros(3), com[:2], np.zeros(3))


def test_interface_and_plan_structure():
    planner = AlipFootstepPlanner(PARAMS)
    assert isinstance(planner, FootstepPlanner)
    assert planner.omega == pytest.approx(math.sqrt(9.81 / 0.64)) and planner.com_height == 0.64
    stance, measured = standing(yaw=0.3)
    command = VelocityCommand(0.3, 0.05, 0.4)
    planner.check_command(command)
    plan = planner.plan(0.1, stance, measured, command)
    solution = planner.last_solution
    K = PARAMS.steps
    assert plan.steps[-1].touchdown_time >= 0.1 + PARAMS.horizon and len(plan.steps) > K
    assert [s.foot for s in plan.steps[:4]] == ["right", "left", "right", "left"]
    # eq. 16 with ψ_{k+1} = ψ_k + r T_k, touchdowns t_start + ΣT
    yaw, position = stance.yaw, stance.position
    for k in range(K):
        position = position + rot(yaw) @ solution.steps[k]
        yaw += command.yaw_rate * solution.periods[k]
        assert np.allclose(plan.steps[k].position, position) and plan.steps[k].yaw == pytest.approx(yaw)
        assert plan.steps[k].touchdown_time == pytest.approx(np.sum(solution.periods[:k + 1]))
    contact_schedule(plan, t0=0.1, dt=0.02, n_nodes=50, rounding="nearest")


def test_com_reference_is_the_alip_prediction():
    planner = AlipFootstepPlanner(PARAMS)
    stance = StanceState("right", [0.0, -0.11], 0.2, 0.0)
    com = np.array([0.02, -0.02, 0.64])
    measured = ReducedState(com, np.array([0.2, 0.15, 0.0]), com[:2], np.array([-3.0, 6.0, 0.0]))
    command = VelocityCommand(0.2, 0.0, 0.3)
    plan = planner.plan(0.12, stance, measured, command)
    solution, instance, model = planner.last_solution, planner.last_instance, planner.model
    assert np.any(np.abs(solution.torques[0]) > 0.1)  # the ankle torque is used: the CoP shift matters
    # integrate the ALIP through the optimised steps and compare with the plan's CoM reference (world frame)
    x, yaw, origin, start, t_local = instance.x0, stance.yaw, stance.position, 0.0, instance.t_curr
    for k in range(PARAMS.steps):
        for fraction in (0.3, 0.7, 1.0):
            tau_time = start + fraction * (solution.periods[k] - (instance.t_curr if k == 0 else 0.0))
            dt = tau_time - start
            xk = model.flow(x, solution.torques[k], dt)
            world = origin + rot(yaw) @ xk[[0, 2]]
            t_abs = 0.12 + tau_time - (0.0 if k else 0.0)
            assert np.allclose(plan.com_reference(t_abs - 1e-12, com[:2])[:2], world, atol=1e-9)
        x = model.flow(x, solution.torques[k], solution.periods[k] - (t_local if k == 0 else 0.0))
        origin = origin + rot(yaw) @ solution.steps[k]
        x = np.array(heading_change_entries(command.yaw_rate * solution.periods[k])) @ (x + B_D @ solution.steps[k])
        yaw += command.yaw_rate * solution.periods[k]
        start += solution.periods[k] - (t_local if k == 0 else 0.0)


def test_measured_state_fallback_is_eqs_14_15():
    planner = AlipFootstepPlanner(PARAMS)
    stance = StanceState("left", [0.0, 0.1], 0.0, 0.0)
    com, v = np.array([0.05, -0.01, 0.64]), np.array([0.3, -0.1, 0.02])
    m, z = PARAMS.mass, PARAMS.com_height
    x = planner.measured_state(stance, ReducedState(com, v, com[:2]))
    p = com[:2] - stance.position
    assert np.allclose(x, [p[0], m * (z * v[0] - p[0] * v[2]), p[1], m * (p[1] * v[2] - z * v[1])])
    L = np.array([1.0, 2.0, 0.0])
    assert np.allclose(planner.measured_state(stance, ReducedState(com, v, com[:2], L)), [p[0], 2.0, p[1], 1.0])


def test_push_recovery_on_the_alip():
    """Receding horizon on the ALIP itself (re-plan every 10 ms): after a push the state returns to the orbit."""
    planner = AlipFootstepPlanner(PARAMS)
    model = planner.model
    command = VelocityCommand(0.0, 0.0, 0.0)
    stance, t, t_start, dt = "left", 0.0, 0.0, 0.01
    x = np.array([0.0, 0.0, -0.11, 0.0])
    pushed, impacts = False, []
    for _ in range(400):
        if not pushed and t >= 1.0:
            x = x + np.array([0.0, 8.0, 0.0, -4.0])  # 8 and 4 kg m^2/s: 0.38 and 0.19 m/s
            pushed = True
        origin = np.zeros(2)
        com = np.array([x[0], x[2], model.com_height])
        plan = planner.plan(t, StanceState(stance, origin, 0.0, t_start),
                            ReducedState(com, np.zeros(3), com[:2], np.array([x[3], x[1], 0.0])), command)
        solution = planner.last_solution
        remaining = solution.periods[0] - (t - t_start)
        if remaining <= dt + 1e-12:  # touchdown within this tick
            x = model.flow(x, solution.torques[0], remaining)
            impacts.append((stance, t + remaining, x.copy()))
            x = x + B_D @ solution.steps[0]
            x = model.flow(x, (0.0, 0.0), dt - remaining)
            stance, t_start = plan.steps[0].foot, t + remaining
        else:
            x = model.flow(x, solution.torques[0], dt)
        t += dt
    orbit = desired_orbit(PARAMS, command)
    after = [(foot, time, state) for foot, time, state in impacts if time > 1.0]
    first_error = np.abs(after[0][2] - orbit[after[0][0]])
    last_foot, _, last = after[-1]
    error = np.abs(last - orbit[last_foot])
    assert first_error[1] > 2.0  # the push moved the state off the orbit
    assert error[0] < 0.005 and error[2] < 0.005 and error[1] < 0.3 and error[3] < 0.3, error


@pytest.mark.parametrize("stance_foot, command", [("left", VelocityCommand()), ("right", VelocityCommand(0.3, 0.1, 0.0))])
def test_a_start_from_standing_plans_from_the_orbit_at_the_stance_start(stance_foot, command):
    planner = AlipFootstepPlanner(PARAMS)
    model = planner.model
    start = planner.stance_start_state(stance_foot, command)
    # the post-impact state of the orbit: flowing it over T_des (τ = 0) reaches this stance's pre-impact state
    assert np.allclose(model.flow(start, (0.0, 0.0), PARAMS.t_des), desired_orbit(PARAMS, command)[stance_foot],
                       atol=1e-9)
    # in place the stance starts with the CoM half a nominal width inside the stance foot, moving towards it
    if command == VelocityCommand():
        side = 1.0 if stance_foot == "left" else -1.0
        assert start[2] == pytest.approx(-side * PARAMS.width_offset / 2, abs=0.02) and start[0] == 0.0
        assert side * -start[3] > 0  # L_x = -m z v_y: v_y towards the stance foot
    stance = StanceState(stance_foot, [0.0, 0.11 if stance_foot == "left" else -0.11], 0.0, 0.6)
    at_rest = ReducedState([0.0, 0.0, PARAMS.com_height], np.zeros(3), np.zeros(2), np.zeros(3))
    plan = planner.plan(0.2, stance, at_rest, command)  # 0.4 s before the stance begins
    assert plan.t0 == 0.6 and planner.last_instance.t_curr == 0.0
    assert np.array_equal(planner.last_instance.x0, start)  # not the measured state (CoM between the feet, at rest)
    assert plan.steps[0].touchdown_time >= 0.6 + PARAMS.t_min
    schedule = contact_schedule(plan, t0=0.2, dt=0.02, n_nodes=40, rounding="nearest")
    assert schedule.in_contact[schedule.times < 0.6 - 1e-9].all()  # both feet down until the stance begins


def test_bad_input_and_failures():
    planner = AlipFootstepPlanner(PARAMS)
    stance, measured = standing()
    with pytest.raises(ParameterError, match="v_x=1.0 m/s"):
        planner.check_command(VelocityCommand(1.0, 0.0, 0.0))
    with pytest.raises(ParameterError, match="v_y="):
        planner.plan(0.0, stance, measured, VelocityCommand(0.0, 0.5, 0.0))
    with pytest.raises(ParameterError, match="t=nan s must be finite"):
        planner.plan(math.nan, stance, measured, VelocityCommand())
    with pytest.raises(ParameterError, match="solver="):
        AlipFootstepPlanner(PARAMS, solver="snopt")
    with pytest.raises(ParameterError, match="com="):
        ReducedState([0.0, np.nan, 0.6], np.zeros(3), np.zeros(2))
    far = ReducedState([0.3, 0.0, 0.64], [1.5, 0.0, 0.0], [0.3, 0.0], [0.0, 40.0, 0.0])
    with pytest.raises(AlipSolverError) as info:
        planner.plan(0.45, StanceState("left", [0.0, 0.1], 0.0, 0.0), far, VelocityCommand())
    assert isinstance(info.value, SolverError)


@pytest.mark.parametrize("robot_name", ["g1", pytest.param("h1", marks=needs_h1_extra)])
def test_alip_preset_matches_the_robot(robot_name):
    robots = pytest.importorskip("robots.registry")
    pin = pytest.importorskip("pinocchio")
    params = AlipParams.preset(robot_name)
    robot = robots.load_robot(robot_name)
    model = robot.pinocchio_model
    assert params.mass == pytest.approx(pin.computeTotalMass(model), abs=0.01)
    com = pin.centerOfMass(model, model.createData(), robot.q_reference)
    feet = robot.foot_positions_reference()
    stance = feet["left"][1] - feet["right"][1]
    assert params.width_min < stance < params.width_max
    if robot_name == "g1":  # a CoM lowered below the reference's, for the reach of 0.30 m steps
        assert params.com_height <= com[2] and com[2] - params.com_height < 0.05
    else:  # the reference's CoM height and stance
        assert params.com_height == pytest.approx(com[2], abs=0.005)
        assert params.width_offset == pytest.approx(stance, abs=0.001)
