"""A pure-pursuit path follower for a walking robot: measured planar pose -> velocity command.

Each call of :meth:`PathFollower.command` with the measured base pose (x [m], y [m], yaw [rad],
world frame):

1. **progress**: the closest point of the path within a window around the previous progress
   (:meth:`sim.paths.PlanarPath.project_near`; ``look_ahead`` behind, twice ahead), an unwrapped
   arc length ``s`` [m] capped at the path's end ``end = laps * length``;
2. **translation**: toward the look-ahead point, ``look_ahead`` ahead of the closest point along
   the path's tangent there, at ``speed``: on the path the robot walks along its tangent (no
   offset on a circle, where aiming at a point of the path itself cuts inside by
   R (1 - cos(look_ahead / R)), 4.5 cm for 0.3 m on 1 m); off the path it comes back at the
   angle atan(distance / look_ahead). Within ``look_ahead`` of the end it walks toward the end
   point, slowing down with the distance to it, to 0 there;
3. **heading**: ``yaw_rate = heading_gain * wrap(heading(s + v / heading_gain) - yaw)``, v the speed
   (ramped, ``speed * speed_scale``): the
   tangent heading a little ahead, by as much as the lag a proportional law has on a path of
   constant curvature (on a circle of radius R it turns at speed / R with no steady heading
   error). The speed is multiplied by max(0, cos(heading error)): at a corner the robot turns
   first and walks on as its heading comes round, instead of walking sideways until it has turned;
   and, when that yaw rate is beyond the robot's range, by the share of it the robot can turn
   (limit / |yaw_rate|): a robot that cannot turn as fast as the path asks walks it slower instead
   of falling behind in heading (the G1, limited to 0.3 rad/s, lagged the 1 m circle by 0.2 rad
   while its speed overshot after the start);
4. **frame and range**: the world velocity rotated into the heading frame (yaw), then
   :func:`fit_command` keeps it within the robot's command range: (v_x, v_y) scaled down together
   (the direction of travel kept, slower), the yaw rate clipped.

A robot that cannot turn (yaw-rate range [0, 0], Bolt) keeps its heading (step 3 is skipped) and
walks the path sideways and backwards where it must, as fast as its v_x and v_y ranges allow.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from sequencer.planner import rotate_xy
from sim.paths import PlanarPath, wrap_angle
from wbmpc.errors import ParameterError

CommandRanges = Mapping[str, tuple[float, float]]  # {"v_x": (min, max) [m/s], "v_y": ..., "yaw_rate": [rad/s]}


def fit_command(v_x: float, v_y: float, yaw_rate: float, command_range: CommandRanges | None) -> tuple[float, float, float]:
    """The command (v_x [m/s], v_y [m/s], yaw_rate [rad/s]), heading frame, brought into ``command_range``.

    (v_x, v_y) is scaled by the largest factor in [0, 1] that puts both in their ranges (the
    direction of travel is kept; each range must contain 0); the yaw rate is clipped to its own.
    ``command_range`` None: no limits.
    """
    if command_range is None:
        return float(v_x), float(v_y), float(yaw_rate)
    scale = 1.0
    for name, value in (("v_x", v_x), ("v_y", v_y)):
        low, high = command_range[name]
        if not low <= 0.0 <= high:
            raise ParameterError(f"command range {name}=[{low}, {high}] must contain 0 to scale a command into it")
        if value > high:
            scale = min(scale, high / value)
        elif value < low:
            scale = min(scale, low / value)
    low, high = command_range["yaw_rate"]
    return float(scale * v_x), float(scale * v_y), float(np.clip(yaw_rate, low, high))


class PathFollower:
    """Velocity commands that walk a robot along ``path`` (see the module docstring).

    Args:
        path: the path to follow (it starts at arc length 0, where the robot should stand).
        speed: walking speed along the path [m/s], > 0.
        look_ahead: distance along the path to the point the robot walks toward [m], > 0.
        heading_gain: proportional gain of the heading [1/s], > 0.
        laps: how many times to go round [-], > 0; the robot stops at arc length laps * length.
        command_range: the robot's command range (heading frame); None: no limits.

    Attributes:
        progress: unwrapped arc length of the closest point of the path [m] at the last call.
        turns: whether the follower steers the heading (False when the yaw-rate range is [0, 0]).
    """

    def __init__(self, path: PlanarPath, speed: float, look_ahead: float, heading_gain: float, laps: float = 1.0,
                 command_range: CommandRanges | None = None) -> None:
        for name, value in (("speed", speed), ("look_ahead", look_ahead), ("heading_gain", heading_gain), ("laps", laps)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name}={value} must be a finite number > 0")
        self.path, self.speed, self.look_ahead, self.heading_gain = path, float(speed), float(look_ahead), float(heading_gain)
        self.end = float(laps) * path.length  # [m], arc length where the robot stops
        self.command_range = command_range
        self.turns = command_range is None or tuple(command_range["yaw_rate"]) != (0.0, 0.0)  # aims its heading
        self.progress = 0.0

    def command(self, pose, speed_scale: float = 1.0) -> tuple[float, float, float]:
        """(v_x [m/s], v_y [m/s], yaw_rate [rad/s]), heading frame, for the measured ``pose`` (x, y, yaw)
        [m, m, rad], world frame; ``speed_scale`` in [0, 1] multiplies the speed (a start ramp)."""
        x, y, yaw = (float(value) for value in pose)
        s, _ = self.path.project_near((x, y), self.progress, self.look_ahead, 2.0 * self.look_ahead)
        self.progress = s = min(s, self.end)
        position = np.array((x, y))
        speed = walking_speed = self.speed * float(np.clip(speed_scale, 0.0, 1.0))
        if s + self.look_ahead < self.end:
            heading_here = float(self.path.heading_at(s))
            target = self.path.point_at(s) + self.look_ahead * np.array((math.cos(heading_here), math.sin(heading_here)))
        else:  # the end point is within the look-ahead: slow down to stop on it
            target = self.path.point_at(self.end)
            speed *= min(1.0, float(np.hypot(*(target - position))) / self.look_ahead)
        yaw_rate = 0.0
        if self.turns:
            heading = float(self.path.heading_at(min(s + walking_speed / self.heading_gain, self.end)))
            heading_error = float(wrap_angle(heading - yaw))
            yaw_rate = self.heading_gain * heading_error
            speed *= max(0.0, math.cos(heading_error))
            if self.command_range is not None:
                low, high = self.command_range["yaw_rate"]
                limit = high if yaw_rate > 0.0 else -low
                if abs(yaw_rate) > limit > 0.0:
                    speed *= limit / abs(yaw_rate)
        to_target = target - position
        distance = float(np.hypot(*to_target))
        velocity_world = speed * to_target / distance if distance > 0.0 else np.zeros(2)
        v_x, v_y = rotate_xy(velocity_world, -yaw)  # world -> heading frame
        return fit_command(v_x, v_y, yaw_rate, self.command_range)
