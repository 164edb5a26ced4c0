"""Waypoint following: path geometry, the pure-pursuit follower (kinematic, no simulation), the path
metrics on synthetic trajectories, the command line's refusal of an unknown path, and one short
closed loop on Bolt."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from sim.metrics import HEADING_CORNER_MARGIN, path_metrics
from sim.path_follower import PathFollower, fit_command
from sim.paths import make_path, wrap_angle
from sim.scenarios import make_scenario
from wbmpc.errors import ParameterError

BOLT_RANGE = {"v_x": (-0.3, 0.5), "v_y": (-0.1, 0.1), "yaw_rate": (0.0, 0.0)}
G1_RANGE = {"v_x": (-0.2, 0.5), "v_y": (-0.15, 0.15), "yaw_rate": (-0.3, 0.3)}


# ---------------------------------------------------------------------- geometry
def test_circle_closest_point_arc_length_and_tangent():
    radius = 1.5
    circle = make_path("circle", radius=radius)
    assert circle.length == pytest.approx(2 * math.pi * radius, rel=1e-5)
    assert len(circle.corners) == 0
    angle = np.array([-0.5 * math.pi + 0.3, 0.2, 2.0, 3.5])  # about the centre (0, radius), from +x
    distance_from_centre = np.array([1.2, 1.7, 1.5, 0.4])
    points = np.column_stack([distance_from_centre * np.cos(angle), radius + distance_from_centre * np.sin(angle)])
    s, distance = circle.project(points)
    np.testing.assert_allclose(distance, np.abs(distance_from_centre - radius), atol=1e-4)
    np.testing.assert_allclose(s, radius * ((angle + 0.5 * math.pi) % (2 * math.pi)), atol=0.01)  # a side: 1.3 cm
    # counter-clockwise: the tangent is the radius' angle plus 90 degrees; the path starts at the origin along +x
    np.testing.assert_allclose(wrap_angle(circle.heading_at(s) - (angle + 0.5 * math.pi)), 0.0, atol=math.pi / 700)
    np.testing.assert_allclose(circle.point_at(0.0), [0.0, 0.0], atol=1e-12)
    assert circle.heading_at(0.0) == pytest.approx(0.0, abs=1e-2)


def test_square_corners_headings_and_windowed_projection_across_the_start():
    square = make_path("square", side=2.0)
    assert square.length == pytest.approx(8.0)
    np.testing.assert_allclose(square.corners, [1.0, 3.0, 5.0, 7.0])
    np.testing.assert_allclose(square.heading_at([0.5, 2.0, 4.0, 6.0, 7.5, 8.5]),
                               [0.0, 0.5 * math.pi, math.pi, -0.5 * math.pi, 0.0, 0.0])
    np.testing.assert_allclose(square.point_at([1.0, 3.0, 9.0]), [[1.0, 0.0], [1.0, 2.0], [1.0, 0.0]])
    s, distance = square.project([[1.2, 1.0], [0.3, 2.1]])
    np.testing.assert_allclose(s, [2.0, 3.7])
    np.testing.assert_allclose(distance, [0.2, 0.1])
    # near the end of a lap, the windowed projection continues past the length instead of wrapping to 0
    assert square.project_near([0.1, -0.02], 7.95, 0.3, 0.6) == pytest.approx((8.1, 0.02))
    assert square.project_near([-0.1, 0.02], 0.0, 0.3, 0.6) == pytest.approx((-0.1, 0.02))
    # a point as close to two parts of the path: the window picks the one near the previous progress
    assert square.project_near([0.0, 1.0], 2.0, 0.3, 0.6) == pytest.approx((2.0, 1.0))  # the right side's
    assert square.project_near([0.0, 1.0], 6.0, 0.3, 0.6) == pytest.approx((6.0, 1.0))  # the left side's


def test_unknown_path_and_bad_sizes_are_refused_with_the_allowed_values():
    with pytest.raises(ParameterError, match=r"^path='triangle' is unknown \(allowed: circle, square\)$"):
        make_path("triangle")
    with pytest.raises(ParameterError, match=r"path='triangle' is unknown \(allowed: circle, square\)"):
        make_scenario("waypoints", path="triangle")
    with pytest.raises(ParameterError, match="radius=-1.0 m"):
        make_path("circle", radius=-1.0)
    with pytest.raises(ParameterError, match="yaw_rate=0.2 must be 0"):
        make_scenario("waypoints", yaw_rate=0.2)


def test_cli_refuses_an_unknown_path_in_one_line_with_exit_code_2(capsys):
    from wbmpc.cli import main

    assert main(["run", "waypoints", "--robot", "bolt", "--path", "triangle"]) == 2
    err = capsys.readouterr().err
    assert err == "wbmpc run: error: path='triangle' is unknown (allowed: circle, square)\n"


# ---------------------------------------------------------------------- follower
def test_fit_command_keeps_the_direction_of_travel_and_clips_the_yaw_rate():
    assert fit_command(0.2, 0.2, 0.5, BOLT_RANGE) == pytest.approx((0.1, 0.1, 0.0))  # v_y limits: both halved
    assert fit_command(-0.6, 0.05, -0.5, G1_RANGE) == pytest.approx((-0.2, 0.05 / 3, -0.3))
    assert fit_command(0.3, 0.1, 0.2, G1_RANGE) == (0.3, 0.1, 0.2)  # within the range: unchanged
    assert fit_command(3.0, 2.0, 1.0, None) == (3.0, 2.0, 1.0)
    with pytest.raises(ParameterError, match="must contain 0"):
        fit_command(0.2, 0.0, 0.0, {"v_x": (0.1, 0.5), "v_y": (-0.1, 0.1), "yaw_rate": (0.0, 0.0)})


def test_follower_walks_ahead_on_the_path_and_steers_back_to_it():
    square = make_path("square")
    follower = PathFollower(square, speed=0.25, look_ahead=0.3, heading_gain=1.0)
    assert follower.command((0.0, 0.0, 0.0)) == pytest.approx((0.25, 0.0, 0.0))
    v_x, v_y, yaw_rate = PathFollower(square, 0.25, 0.3, 1.0).command((0.0, -0.1, 0.0))  # 10 cm right of the path
    assert v_y > 0.05 and v_x > 0.2 and yaw_rate == pytest.approx(0.0)
    # heading 0.2 rad left of the path: turn right; the velocity stays along the path in the world
    v_x, v_y, yaw_rate = PathFollower(square, 0.25, 0.3, 1.0).command((0.0, 0.0, 0.2))
    assert yaw_rate == pytest.approx(-0.2)
    speed = 0.25 * math.cos(0.2)  # slower while turning
    assert (v_x, v_y) == pytest.approx((speed * math.cos(0.2), -speed * math.sin(0.2)))
    # a robot that cannot turn, where the circle heads along +y: sideways at its largest v_y
    circle = make_path("circle")
    bolt = PathFollower(circle, 0.25, 0.3, 1.0, command_range=BOLT_RANGE)
    bolt.progress = 0.5 * math.pi  # at (1, 1)
    v_x, v_y, yaw_rate = bolt.command((1.0, 1.0, 0.0))
    assert v_y == pytest.approx(0.1) and yaw_rate == 0.0 and -0.05 < v_x < 0.0  # turning left, slightly back


def walk_kinematically(follower, duration, dt=0.01, pose=(0.0, 0.0, 0.0), lag=0.0, turn_drift=(0.0, 0.0)):
    """Integrate the follower's commands on a robot that moves as commanded (heading frame), through a
    first-order lag of ``lag`` [s] (0: exactly), drifting by ``turn_drift`` [m/rad] (heading frame) times
    its |yaw rate| (the G1 turning in place at 0.3 rad/s drifted back and right at ~0.05 m/s)."""
    x, y, yaw = pose
    velocity = np.zeros(3)  # the robot's (v_x, v_y, yaw_rate), heading frame
    trajectory = []
    for k in range(int(round(duration / dt))):
        command = follower.command((x, y, yaw), speed_scale=min(1.0, k * dt / 1.0))
        velocity += (1.0 if lag == 0.0 else dt / lag) * (np.array(command) - velocity)
        v_x, v_y = velocity[:2] + abs(velocity[2]) * np.array(turn_drift)
        x += dt * (math.cos(yaw) * v_x - math.sin(yaw) * v_y)
        y += dt * (math.sin(yaw) * v_x + math.cos(yaw) * v_y)
        yaw += dt * velocity[2]
        trajectory.append((x, y, yaw, *command))
    return np.array(trajectory)


def test_follower_goes_round_the_circle_heading_along_it_and_stops_at_the_end():
    circle = make_path("circle")
    follower = PathFollower(circle, speed=0.25, look_ahead=0.3, heading_gain=1.0, command_range=G1_RANGE)
    trajectory = walk_kinematically(follower, duration=35.0)
    metrics = path_metrics(circle, trajectory[:, :2], trajectory[:, 2])
    sagitta = 1.0 - math.cos(0.5 * 0.3)  # [m], of the last look-ahead, walked straight to the end point
    assert metrics["path_deviation_max"] < sagitta + 1e-3
    s, distance = circle.project(trajectory[:, :2])
    assert np.max(distance[s < circle.length - 0.3]) < 2e-3  # along the tangent: no inside offset
    assert metrics["heading_error_max"] < 0.04  # no lag at constant curvature (the preview)
    assert metrics["path_completion"] == pytest.approx(1.0, abs=0.01)
    assert follower.progress == pytest.approx(circle.length, abs=1e-3)
    assert np.abs(trajectory[-1, 3:5]).max() < 0.01  # stopped at the end


def test_follower_turns_the_square_corners_in_place_within_the_yaw_rate_range():
    square = make_path("square")
    follower = PathFollower(square, speed=0.25, look_ahead=0.3, heading_gain=1.0, laps=0.5, command_range=G1_RANGE)
    trajectory = walk_kinematically(follower, duration=40.0)  # two corners, turning at 0.3 rad/s at most
    assert np.all(np.abs(trajectory[:, 5]) <= 0.3 + 1e-12) and np.all(np.abs(trajectory[:, 4]) <= 0.15 + 1e-12)
    metrics = path_metrics(square, trajectory[:, :2], trajectory[:, 2], laps=0.5)
    assert metrics["path_completion"] == pytest.approx(1.0, abs=0.01)
    assert metrics["path_deviation_max"] < 0.005  # stops at each corner, turns there, walks on along the next side
    assert metrics["heading_error_max"] < 0.1  # the turn is over by HEADING_CORNER_MARGIN past a corner


def test_follower_slows_down_toward_a_corner_to_the_speed_its_yaw_rate_turns_within_corner_deviation():
    square = make_path("square")
    follower = PathFollower(square, 0.25, 0.3, 1.0, command_range=G1_RANGE, corner_deviation=0.05, corner_rate=0.5)
    cos_half = math.cos(0.25 * math.pi)  # the square turns by 90 degrees at each corner
    corner_speed = 0.3 * 0.05 * cos_half / (1.0 - cos_half)  # [m/s], 0.036: radius 0.12 m at 0.3 rad/s
    np.testing.assert_allclose(follower.corner_arc_lengths, [1.0, 3.0, 5.0, 7.0])
    np.testing.assert_allclose(follower.corner_speeds, corner_speed)
    for to_corner in (0.8, 0.5, 0.3, 0.1, 0.05):  # on the first side, heading along it
        follower.progress = 1.0 - to_corner
        expected = min(0.25, corner_speed + 0.5 * max(0.0, to_corner - corner_speed / 1.0))
        assert follower.command((1.0 - to_corner, 0.0, 0.0)) == pytest.approx((expected, 0.0, 0.0)), to_corner
    for past_corner in (0.05, 0.1, 0.3, 0.8):  # on the second side, turned: it speeds up again at the same rate
        follower.progress = 1.0 + past_corner
        expected = min(0.25, corner_speed + 0.5 * max(0.0, past_corner - corner_speed / 1.0))
        assert follower.command((1.0, past_corner, 0.5 * math.pi)) == pytest.approx((expected, 0.0, 0.0)), past_corner
    # within corner_speed / heading_gain of the corner the heading's preview is past it: it turns in place
    follower.progress = 0.98
    v_x, v_y, yaw_rate = follower.command((0.98, 0.0, 0.0))
    assert yaw_rate == pytest.approx(0.3) and abs(v_x) < 1e-12 and abs(v_y) < 1e-12
    # a faster-turning robot may take the corner faster; the circle's vertices (0.5 degrees) ask for no slowdown
    faster = PathFollower(square, 0.25, 0.3, 1.0, command_range={**G1_RANGE, "yaw_rate": (-0.6, 0.6)})
    np.testing.assert_allclose(faster.corner_speeds, 2.0 * corner_speed)
    assert len(PathFollower(make_path("circle"), 0.25, 0.3, 1.0, command_range=G1_RANGE).corner_speeds) == 0
    # a robot that cannot turn (Bolt) keeps walking at its speed toward a corner
    bolt = PathFollower(square, 0.25, 0.3, 1.0, command_range=BOLT_RANGE)
    assert len(bolt.corner_speeds) == 0
    bolt.progress = 0.9
    assert bolt.command((0.9, 0.0, 0.0)) == pytest.approx((0.25, 0.0, 0.0))


def test_follower_comes_back_to_the_path_while_it_turns_in_place():
    # 5 cm outside the first side, near the corner, half-way round: it barely progresses (cos of the
    # heading error, the yaw rate saturated), and still comes back at speed / look_ahead x the distance
    square = make_path("square")
    follower = PathFollower(square, 0.25, 0.3, 1.0, command_range=G1_RANGE)
    follower.progress = 0.98
    yaw = 0.5
    v_x, v_y, yaw_rate = follower.command((0.98, -0.05, yaw))
    assert yaw_rate == pytest.approx(0.3)
    world = (math.cos(yaw) * v_x - math.sin(yaw) * v_y, math.sin(yaw) * v_x + math.cos(yaw) * v_y)
    assert world[1] == pytest.approx(0.25 / 0.3 * 0.05)  # toward the side, as fast as at full speed
    assert 0.0 < world[0] < 0.01  # along it, hardly


def test_follower_keeps_a_lagging_drifting_robot_within_the_corner_deviation_on_the_square():
    # a robot that follows its commands 0.5 s late and drifts back and right while it turns, as the G1 does
    square = make_path("square")
    follower = PathFollower(square, speed=0.25, look_ahead=0.3, heading_gain=1.0, laps=0.5, command_range=G1_RANGE)
    trajectory = walk_kinematically(follower, duration=45.0, lag=0.5, turn_drift=(-0.1, -0.1))
    metrics = path_metrics(square, trajectory[:, :2], trajectory[:, 2], laps=0.5)
    assert metrics["path_completion"] == pytest.approx(1.0, abs=0.01)
    assert metrics["path_deviation_max"] < 0.06  # 0.095 m when the return to the path slowed down with the progress


def test_follower_refuses_a_bad_corner_deviation_or_corner_rate_in_one_line():
    square = make_path("square")
    with pytest.raises(ParameterError, match=r"^corner_deviation=0.0 must be a finite number > 0$"):
        PathFollower(square, 0.25, 0.3, 1.0, corner_deviation=0.0)
    with pytest.raises(ParameterError, match=r"^corner_rate=1.0 1/s must be in \(0, heading_gain=1.0\) 1/s$"):
        PathFollower(square, 0.25, 0.3, 1.0, corner_rate=1.0)
    with pytest.raises(ParameterError, match=r"^corner_deviation=2.0 m must be in \[0.001, 1.0\] m$"):
        make_scenario("waypoints", corner_deviation=2.0)
    with pytest.raises(ParameterError, match=r"^corner_rate=-0.1 1/s must be in \(0, heading_gain=2.0\) 1/s$"):
        make_scenario("waypoints", corner_rate=-0.1, heading_gain=2.0)


def test_follower_walks_slower_round_a_curve_tighter_than_its_yaw_rate_allows():
    # 0.25 m/s round 0.5 m asks 0.5 rad/s of a robot limited to 0.3: it walks at ~0.15 m/s and keeps its heading
    tight = make_path("circle", radius=0.5)
    follower = PathFollower(tight, speed=0.25, look_ahead=0.3, heading_gain=1.0, command_range=G1_RANGE)
    trajectory = walk_kinematically(follower, duration=40.0)
    metrics = path_metrics(tight, trajectory[:, :2], trajectory[:, 2])
    assert metrics["path_completion"] == pytest.approx(1.0, abs=0.01)
    assert metrics["heading_error_max"] < 0.1 and metrics["path_deviation_max"] < 0.06
    steady = slice(500, 1500)  # 5-15 s, on the circle
    assert np.all(np.hypot(trajectory[steady, 3], trajectory[steady, 4]) < 0.2)


# ---------------------------------------------------------------------- metrics
def test_path_metrics_measure_offsets_heading_errors_and_progress():
    circle = make_path("circle")
    angle = np.linspace(-0.5 * math.pi, 1.5 * math.pi, 2001)  # one lap about the centre (0, 1)
    offset, heading_offset = 0.05, 0.1
    position = np.column_stack([(1 + offset) * np.cos(angle), 1 + (1 + offset) * np.sin(angle)])
    metrics = path_metrics(circle, position, angle + 0.5 * math.pi + heading_offset)
    assert metrics["path_deviation_max"] == pytest.approx(offset, abs=1e-4)
    assert metrics["path_deviation_mean"] == pytest.approx(offset, abs=1e-4)
    assert metrics["heading_error_max"] == pytest.approx(heading_offset, abs=5e-3)
    assert metrics["path_completion"] == pytest.approx(1.0, abs=1e-3)
    half = path_metrics(circle, position[:1001], angle[:1001] + 0.5 * math.pi, laps=2.0)
    assert half["path_completion"] == pytest.approx(0.25, abs=1e-3)
    assert half["path_progress"] == pytest.approx(math.pi, abs=1e-2)
    assert half["heading_error_max"] < 5e-3


def test_heading_error_leaves_out_the_corners_but_not_the_sides():
    square = make_path("square")
    s = np.linspace(0.0, 4.0, 4001)  # to the middle of the third side
    position = square.point_at(s)
    yaw = np.where(s < 1.0 + 0.8 * HEADING_CORNER_MARGIN, 0.0, 0.5 * math.pi)  # turns late, within the margin
    yaw = np.where(s >= 3.0 + 0.8 * HEADING_CORNER_MARGIN, math.pi, yaw)
    metrics = path_metrics(square, position, yaw)
    assert metrics["heading_error_max"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["path_deviation_max"] == pytest.approx(0.0, abs=1e-9)
    assert metrics["path_completion"] == pytest.approx(0.5)
    late = np.where(s < 1.0 + 1.2 * HEADING_CORNER_MARGIN, 0.0, yaw)  # still turning past the margin: counted
    assert path_metrics(square, position, late)["heading_error_max"] == pytest.approx(0.5 * math.pi)
    # the path starts on a side: a robot a little behind the start counts its progress from there
    behind = path_metrics(square, np.vstack([[[-0.05, 0.0]], position]), np.concatenate([[0.0], yaw]))
    assert behind["path_progress"] == pytest.approx(4.0)


# ---------------------------------------------------------------------- closed loop
@pytest.mark.filterwarnings("ignore::UserWarning")
def test_bolt_starts_along_the_circle_in_closed_loop(tmp_path):
    from matplotlib.image import imread

    from sim.plots import plot_path, save_figures
    from sim.runner import run_scenario

    log = run_scenario("waypoints", robot="bolt", path="circle", duration=3.0, ramp_time=1.0, progress=False)
    assert log.status == "completed", (log.fall_time, log.fall_reason, log.error)
    m = log.metrics
    assert 0.2 < m["path_progress"] < 1.0  # walked along the path, no faster than commanded
    assert m["path_deviation_max"] < 0.08
    command = log.ticks["velocity_command"]
    assert np.all(np.abs(command[:, 1]) <= 0.1 + 1e-9) and np.all(command[:, 2] == 0.0)  # Bolt's range
    assert command[-1, 1] > 0.0  # steering left, round the circle
    from wbmpc.cli.walk import format_metrics

    table = format_metrics({**log.summary(), "paper": {}})
    assert re.search(rf"\n  path deviation max +{m['path_deviation_max']:.3f} m\n", table), table
    assert re.search(rf"\n  path completion +{100 * m['path_completion']:.1f} %\n", table), table
    # the figure gets the path panel: the path, the footholds, the CoM
    ax = plot_path(log)
    assert {"path (circle)", "CoM", "left foot (contact)", "right foot (contact)"} <= set(ax.get_legend_handles_labels()[1])
    assert imread(save_figures(log, tmp_path / "waypoints.png")).shape[0] > 1.5 * 11 * 120  # taller than a walk's
