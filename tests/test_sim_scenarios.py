"""Scenario registry, terrain and patch generation, stance tracking and metric definitions."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robots import load_robot
from robots.mujoco_model import build_mujoco_spec
from sim.log import RunLog
from sim.metrics import compute_metrics, running_average
from sim.scenarios import available_scenarios, make_scenario, scenario_parameters
from wbmpc.errors import ParameterError
from wbmpc.walking.stance import StanceTracker


def test_registry_has_the_paper_scenarios():
    assert {"walk", "push", "terrain", "transition", "slip"} <= set(available_scenarios())
    assert scenario_parameters("push")["force"] == 6.3
    assert scenario_parameters("walk")["speed"] == 0.33
    with pytest.raises(ParameterError, match=r"has no parameter \['forse'\]"):
        make_scenario("push", forse=3.0)
    with pytest.raises(ParameterError, match="side='middle'"):
        make_scenario("slip", side="middle")
    with pytest.raises(ParameterError, match="speed=5.0 m/s"):
        make_scenario("walk", speed=5.0)


def test_terrain_boxes_follow_the_paper_distribution_and_the_seed():
    terrain = make_scenario("terrain", length=20.0, width=1.0)
    boxes = terrain.sample_boxes(np.random.default_rng(0))
    assert abs(len(boxes) - 200) < 3 * np.sqrt(200)  # Poisson, 10 per m² over 20 m²
    assert np.all((boxes[:, 3:5] >= 0.01) & (boxes[:, 3:5] <= 0.05))
    assert np.all((boxes[:, 5] >= 0.005) & (boxes[:, 5] <= 0.008))
    np.testing.assert_array_equal(boxes, terrain.sample_boxes(np.random.default_rng(0)))
    robot = load_robot("bolt")
    spec = build_mujoco_spec(robot)
    make_scenario("terrain", length=2.0).modify_spec(spec, np.random.default_rng(1))
    model = spec.compile()
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert sum(name.startswith("terrain_box_") for name in names) > 0


def test_slip_patch_friction_is_the_one_used_in_contacts():
    from robots.conventions import pinocchio_to_mujoco_state

    robot = load_robot("bolt")
    spec = build_mujoco_spec(robot)
    left_y = robot.foot_positions(robot.q_reference)["left"][1]  # the standing left foot
    make_scenario("slip", friction=0.05, x_start=-0.2, length=0.4, track_y=left_y).modify_spec(
        spec, np.random.default_rng(0))
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = pinocchio_to_mujoco_state(robot, robot.q_reference, robot.v_reference)
    data.qpos[2] += 0.001  # stand on the 1 mm patch
    mujoco.mj_forward(model, data)
    patch = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "slip_patch")
    left_foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "left_foot")
    on_patch = [c for c in data.contact[: data.ncon] if {c.geom1, c.geom2} == {patch, left_foot}]
    assert len(on_patch) == 1  # the left foot (y > 0) stands on the patch
    assert on_patch[0].friction[0] == pytest.approx(0.05)  # the patch's friction, not the foot's 1.0
    assert robot.mujoco_contact.friction == pytest.approx(1.0)


@pytest.mark.parametrize("side, track_y", [("left", None), ("right", None), ("left", 0.2)])
def test_slip_patch_lies_on_the_chosen_track(side, track_y):
    """By default on the side's foot track of the default walk gait; else centred on track_y."""
    from sim.scenarios.slip import Slip

    spec = build_mujoco_spec(load_robot("bolt"))
    make_scenario("slip", side=side, track_y=track_y).modify_spec(spec, np.random.default_rng(0))
    model = spec.compile()
    patch = model.geom("slip_patch")
    expected = Slip.DEFAULT_TRACKS[side] if track_y is None else track_y
    assert patch.pos[1] == pytest.approx(expected)
    assert 2 * patch.size[1] == pytest.approx(0.07)
    with pytest.raises(ParameterError, match="track_y=nan"):
        make_scenario("slip", track_y=float("nan"))


def test_push_terrain_and_slip_take_the_robots_base_and_size_from_its_description():
    g1, bolt = load_robot("g1"), load_robot("bolt")
    model = build_mujoco_spec(g1).compile()
    push = make_scenario("push", force=721.0)  # the corner of the G1's push map, (600, 400) N
    push.setup(g1, None)
    push.initialize_episode(model, mujoco.MjData(model), np.random.default_rng(0))
    assert model.body(push._body_id).name == "pelvis" == g1.base_body
    with pytest.raises(ParameterError, match=r"^force=1500.0 N must be in \[0.0, 1000.0\] N$"):
        make_scenario("push", force=1500.0)

    scale = g1.base_height_reference / bolt.base_height_reference
    assert 2.0 < scale < 2.5
    terrain = make_scenario("terrain", length=20.0, width=1.0)
    terrain.setup(g1, None)
    assert terrain.size_scale == pytest.approx(scale)
    boxes = terrain.sample_boxes(np.random.default_rng(0))
    assert np.all((boxes[:, 5] >= 0.005 * scale) & (boxes[:, 5] <= 0.008 * scale))
    assert np.all((boxes[:, 3:5] >= 0.01 * scale) & (boxes[:, 3:5] <= 0.05 * scale))
    assert np.abs(boxes[:, 1]).max() <= 0.5 * scale and np.abs(boxes[:, 1]).max() > 0.5  # the strip widened
    terrain.setup(bolt, None)
    assert terrain.size_scale == pytest.approx(1.0)
    paper_sizes = make_scenario("terrain", scale=1.0)
    paper_sizes.setup(g1, None)
    assert paper_sizes.size_scale == 1.0

    slip = make_scenario("slip", side="right")
    slip.setup(g1, None)  # no measured tracks: under the standing foot
    assert slip.tracks["right"] == pytest.approx(g1.foot_positions_reference()["right"][1])
    slip.setup(bolt, None)
    assert slip.tracks == slip.MEASURED_TRACKS["bolt"]


def test_transition_command_changes_at_the_switch_and_walk_ramps():
    scenario = make_scenario("transition")
    assert scenario.velocity_command(4.99) == (0.0, 0.0, 0.0)
    assert scenario.velocity_command(5.0) == (0.3, 0.0, 0.0)
    walk = make_scenario("walk", speed=0.3, ramp_time=2.0, lateral_speed=0.1, yaw_rate=0.2)
    assert walk.velocity_command(0.5) == pytest.approx((0.075, 0.025, 0.05))
    assert walk.velocity_command(2.5) == (0.3, 0.1, 0.2)
    assert walk.commands() == [(0.3, 0.1, 0.2)]


def test_stance_tracker_switches_at_the_planned_touchdown_or_on_contact():
    feet = np.array([[0.0, 0.05, 0.016], [0.1, -0.05, 0.016]])
    tracker = StanceTracker(("left", "right"), detection="plan")
    tracker.reset("left", feet[0, :2], 0.0)
    assert not tracker.update(0.2, "right", 0.3, 0.0, feet, np.array([True, True]))
    assert tracker.update(0.31, "right", 0.3, 0.0, feet, np.array([True, False]))  # contact ignored
    assert tracker.state.foot == "right" and tracker.state.t_start == pytest.approx(0.3)
    np.testing.assert_allclose(tracker.state.position, feet[1, :2])

    contact = StanceTracker(("left", "right"), detection="contact", late_tolerance=0.05)
    contact.reset("left", feet[0, :2], 0.0)
    assert not contact.update(0.1, "right", 0.3, 0.0, feet, np.array([True, True]))  # before half swing
    assert contact.update(0.2, "right", 0.3, 0.0, feet, np.array([True, True]))  # early touchdown
    assert contact.state.foot == "right" and contact.state.t_start == pytest.approx(0.2)
    # late touchdown: wait for the contact past the planned time, then force after the tolerance
    assert not contact.update(0.52, "left", 0.5, 0.2, feet, np.array([False, True]))
    assert contact.update(0.53, "left", 0.5, 0.2, feet, np.array([True, True]))
    assert contact.state.t_start == pytest.approx(0.53)
    # the sequencer re-plans a late touchdown to "now": lateness counts from the first due time
    assert not contact.update(0.81, "right", 0.81, 0.53, feet, np.array([True, False]))
    assert not contact.update(0.85, "right", 0.85, 0.53, feet, np.array([True, False]))
    assert contact.update(0.86, "right", 0.86, 0.53, feet, np.array([True, False]))
    assert contact.state.t_start == pytest.approx(0.86) and contact.due_since is None
    assert contact.n_switches == 3
    with pytest.raises(ParameterError, match="touchdown_detection='vision'"):
        StanceTracker(("left", "right"), detection="vision")


def _synthetic_log(t, velocity_x, command_x, events=None):
    n = len(t)
    velocity = np.zeros((n, 3))
    velocity[:, 0] = velocity_x
    command = np.zeros((n, 3))
    command[:, 0] = command_x
    x = np.zeros((n, 25))
    x[:, 0] = np.cumsum(velocity_x) * (t[1] - t[0])
    log = RunLog("synthetic", "bolt", 0, {"steady_start": 1.0, "events": events or {}, "torque_limit": [2.7] * 6})
    log.status = "completed"
    log.ticks = {
        "t": t, "base_velocity_world": velocity, "velocity_command": command, "x": x,
        "tau": np.full((n, 6), 1.35), "tau_command": np.full((n, 6), 1.35), "dcm": np.zeros((n, 2)),
    }
    log.timing = {"total": 1.0}
    return log


def test_velocity_error_and_rise_time_definitions():
    t = np.arange(0, 10, 0.001)
    # first-order response to a step 0 -> 0.3 m/s at t = 2 s, time constant 1 s, plus an offset
    velocity = np.where(t < 2, 0.0, 0.3 * (1 - np.exp(-(t - 2) / 1.0))) + 0.005
    command = np.where(t < 2, 0.0, 0.3)
    metrics = compute_metrics(_synthetic_log(t, velocity, command, events={"speed_switch": 2.0}))
    # running average (1 s window) of a first-order step reaches 90 % of the step later than the signal
    average = running_average(t, velocity)
    expected = t[np.argmax((t >= 2) & (average >= 0.27))] - 2.0
    assert metrics["rise_time"] == pytest.approx(expected)
    assert 2.3 < metrics["rise_time"] < 3.5
    # steady window starts 1 s after the last command change (t = 3 s): offset 5 mm/s + residual decay
    assert metrics["steady_window"][0] == pytest.approx(3.0)
    residual = np.mean(0.3 * np.exp(-(t[t >= 3] - 2)))
    assert metrics["velocity_error_x"] == pytest.approx(abs(0.005 - residual), abs=1e-4)
    assert metrics["max_torque_ratio"] == pytest.approx(0.5)
    assert metrics["real_time_factor"] == pytest.approx(10.0)


def test_heading_frame_velocity_error_measures_a_walk_that_turns():
    """Walking 0.3 m/s forward while turning at 0.3 rad/s: the world velocity averages towards 0,
    the heading-frame velocity is the command."""
    t = np.arange(0, 12, 0.001)
    yaw = 0.3 * t
    log = _synthetic_log(t, 0.3 * np.cos(yaw), 0.3)
    log.ticks["base_velocity_world"][:, 1] = 0.3 * np.sin(yaw)
    log.ticks["x"][:, 3:7] = np.column_stack([np.zeros_like(t), np.zeros_like(t), np.sin(yaw / 2), np.cos(yaw / 2)])
    log.ticks["velocity_command"][:, 2] = 0.3
    metrics = compute_metrics(log)
    assert metrics["velocity_error_heading_x"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["velocity_error_heading_y"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["mean_yaw_rate"] == pytest.approx(0.3, rel=1e-6)
    assert metrics["velocity_error_x"] > 0.2  # the world-frame figure says nothing of such a walk


def test_max_stance_slide_compares_the_stance_foot_with_its_touchdown_point():
    from sim.metrics import max_stance_slide

    t = np.arange(0.0, 1.0, 0.001)
    feet = np.zeros((len(t), 2, 3))
    feet[:, 1, 0] = 0.1  # right foot still at x = 0.1
    feet[500:, 0, 1] = np.linspace(0.0, 0.05, 500)  # left foot slides 5 cm sideways
    replans = {"t": np.arange(0.0, 1.0, 0.01), "stance_foot": np.zeros(100), "stance_x": np.zeros(100),
               "stance_y": np.zeros(100)}
    # last replan at 0.99 s: the foot has slid 0.05 * 490 / 499 m by then
    assert max_stance_slide(t, feet, replans) == pytest.approx(0.05 * 490 / 499)
    replans["stance_foot"][:] = 1
    replans["stance_x"][:] = 0.1
    assert max_stance_slide(t, feet, replans) == pytest.approx(0.0)
