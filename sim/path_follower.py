"""A pure-pursuit path follower for a walking robot: measured planar pose -> velocity command.

Each call of :meth:`PathFollower.command` with the measured base pose (x [m], y [m], yaw [rad],
world frame), v_w = ``speed * speed_scale`` [m/s] the walking speed (``speed_scale`` a start ramp):

1. **progress**: the closest point of the path within a window around the previous progress
   (:meth:`sim.paths.PlanarPath.project_near`; ``look_ahead`` behind, twice ahead), an unwrapped
   arc length ``s`` [m] capped at the path's end ``end = laps * length``;
2. **corners** (a robot that turns): each vertex of the path where the heading turns by Δ [rad]
   has a corner speed v_c = ω · r, ω [rad/s] the robot's largest yaw rate that way (its command
   range) and r [m] the radius of the arc tangent to both sides that cuts the vertex by
   ``corner_deviation``, r = corner_deviation · cos(Δ/2) / (1 - cos(Δ/2)) (v_c = 0 for a U-turn;
   no limit without a command range). The progress speed is v = min(v_w, v_c + corner_rate ·
   max(0, d - v_c / heading_gain)) over the vertices, d [m] the arc length to the next one ahead
   and from the last one passed: the robot slows down toward a corner exponentially in time (rate
   ``corner_rate`` [1/s], a deceleration the walk can follow), to v_c at v_c / heading_gain before
   the vertex, where the heading's preview (step 3) reaches it and the turn begins
   (``corner_rate`` < ``heading_gain`` keeps the preview from reaching it sooner); it speeds up
   again at the same rate after the vertex, so that the heading has come round before it walks
   on at full speed. On the G1 (0.3 rad/s) a 90° corner with corner_deviation 0.05 m gives
   v_c = 0.036 m/s, and cos(90°) = 0 in step 3 makes it turn in place there; the circle's
   vertices (0.5°) ask for no slowdown (its curvature is step 3's);
3. **heading**: ``yaw_rate = heading_gain * wrap(heading(s + v / heading_gain) - yaw)``: the
   tangent heading a little ahead, by as much as the lag a proportional law has on a path of
   constant curvature (on a circle of radius R it turns at v / R with no steady heading
   error). The progress speed v is multiplied by max(0, cos(heading error)): at a corner the
   robot turns first and walks on as its heading comes round, instead of walking sideways until
   it has turned; and, when that yaw rate is beyond the robot's range, by the share of it the
   robot can turn (limit / |yaw_rate|): a robot that cannot turn as fast as the path asks walks it
   slower instead of falling behind in heading (the G1, limited to 0.3 rad/s, lagged the 1 m circle
   by 0.2 rad while its speed overshot after the start);
4. **translation**: the world velocity v · t + (v_w / look_ahead) · (p_s - p), its norm capped at
   v_w, t the path's unit tangent and p_s its point at ``s``, p the robot's position [m]. At full
   progress speed (v = v_w) that is pure pursuit toward the point ``look_ahead`` ahead of p_s along
   t (on the path the robot walks along its tangent: no offset on a circle, where aiming at a
   point of the path itself cuts inside by R (1 - cos(look_ahead / R)), 4.5 cm for 0.3 m on 1 m;
   off the path it comes back at the angle atan(distance / look_ahead)); when steps 2-3 slow the
   progress down (a corner, a turn in place) the robot still comes back to the path at the rate
   v_w / look_ahead [1/s] (the G1 drifted 0.16 m off a corner of the square during a 5 s turn in
   place while the return, scaled with the progress speed, was off). Within ``look_ahead`` of the
   end, the end point replaces p_s and v = 0: the robot walks toward it, slowing down with the
   distance to it, to 0 there;
5. **frame and range**: the world velocity rotated into the heading frame (yaw), then
   :func:`fit_command` keeps it within the robot's command range: (v_x, v_y) scaled down together
   (the direction of travel kept, slower), the yaw rate clipped.

A robot that cannot turn (yaw-rate range [0, 0], Bolt) keeps its heading (steps 2 and 3 are
skipped, v = v_w) and walks the path sideways and backwards where it must, as fast as its v_x and
v_y ranges allow.
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
        corner_deviation: how far a turn at the robot's yaw-rate limit may cut a vertex [m], > 0
            (sets the corner speed, step 2).
        corner_rate: rate of the slowdown toward a corner and of the speed-up after it [1/s], in
            (0, heading_gain): slower than the heading law, so that the turn begins at the vertex.

    Attributes:
        progress: unwrapped arc length of the closest point of the path [m] at the last call.
        turns: whether the follower steers the heading (False when the yaw-rate range is [0, 0]).
        corner_arc_lengths, corner_speeds: arc length [m] and corner speed v_c [m/s] of the
            vertices where the robot must walk slower than ``speed`` (shape (k,); none on the
            circle, the square's four corners; none when it does not turn).
    """

    def __init__(self, path: PlanarPath, speed: float, look_ahead: float, heading_gain: float, laps: float = 1.0,
                 command_range: CommandRanges | None = None, corner_deviation: float = 0.05,
                 corner_rate: float = 0.5) -> None:
        for name, value in (("speed", speed), ("look_ahead", look_ahead), ("heading_gain", heading_gain), ("laps", laps),
                            ("corner_deviation", corner_deviation)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name}={value} must be a finite number > 0")
        if not 0.0 < corner_rate < heading_gain:
            raise ParameterError(f"corner_rate={corner_rate} 1/s must be in (0, heading_gain={heading_gain}) 1/s")
        self.path, self.speed, self.look_ahead, self.heading_gain = path, float(speed), float(look_ahead), float(heading_gain)
        self.corner_rate = float(corner_rate)
        self.end = float(laps) * path.length  # [m], arc length where the robot stops
        self.command_range = command_range
        self.turns = command_range is None or tuple(command_range["yaw_rate"]) != (0.0, 0.0)  # aims its heading
        self.corner_arc_lengths, self.corner_speeds = self._corner_speeds(float(corner_deviation))
        self.progress = 0.0

    def _corner_speeds(self, corner_deviation: float) -> tuple[np.ndarray, np.ndarray]:
        """(arc lengths [m], corner speeds v_c [m/s]) of the vertices where v_c < speed (step 2)."""
        if not self.turns or self.command_range is None:
            return np.zeros(0), np.zeros(0)
        turn = self.path.vertex_turns
        low, high = self.command_range["yaw_rate"]
        yaw_rate_limit = np.where(turn > 0.0, high, -low)  # [rad/s], the robot's fastest turn that way
        cos_half = np.cos(0.5 * np.abs(turn))
        cuts = cos_half < 1.0  # a straight vertex (turn 0) asks for no limit
        radius = np.full(len(turn), np.inf)  # [m], of the arc that cuts the vertex by corner_deviation
        radius[cuts] = corner_deviation * cos_half[cuts] / (1.0 - cos_half[cuts])
        corner_speed = np.where(cuts, yaw_rate_limit * radius, np.inf)
        slower = corner_speed < self.speed
        return self.path.vertex_arc_lengths[slower], corner_speed[slower]

    def progress_speed(self, s: float, walking_speed: float) -> float:
        """The progress speed v [m/s] at unwrapped arc length ``s`` [m] (step 2), at most ``walking_speed``
        [m/s]: from each corner's next passage ahead (before the end) and its last one behind (after the start)."""
        length = self.path.length
        ahead = (self.corner_arc_lengths - s) % length  # [m]
        behind = (s - self.corner_arc_lengths) % length  # [m]
        distance = np.concatenate([ahead[s + ahead < self.end], behind[s - behind >= 0.0]])
        corner_speed = np.concatenate([self.corner_speeds[s + ahead < self.end], self.corner_speeds[s - behind >= 0.0]])
        speed = corner_speed + self.corner_rate * np.maximum(0.0, distance - corner_speed / self.heading_gain)
        return float(np.min(speed, initial=walking_speed))

    def command(self, pose, speed_scale: float = 1.0) -> tuple[float, float, float]:
        """(v_x [m/s], v_y [m/s], yaw_rate [rad/s]), heading frame, for the measured ``pose`` (x, y, yaw)
        [m, m, rad], world frame; ``speed_scale`` in [0, 1] multiplies the speed (a start ramp)."""
        x, y, yaw = (float(value) for value in pose)
        s, _ = self.path.project_near((x, y), self.progress, self.look_ahead, 2.0 * self.look_ahead)
        self.progress = s = min(s, self.end)
        position = np.array((x, y))
        walking_speed = self.speed * float(np.clip(speed_scale, 0.0, 1.0))
        speed = self.progress_speed(s, walking_speed)
        yaw_rate = 0.0
        if self.turns:
            heading = float(self.path.heading_at(min(s + speed / self.heading_gain, self.end)))
            heading_error = float(wrap_angle(heading - yaw))
            yaw_rate = self.heading_gain * heading_error
            speed *= max(0.0, math.cos(heading_error))
            if self.command_range is not None:
                low, high = self.command_range["yaw_rate"]
                limit = high if yaw_rate > 0.0 else -low
                if abs(yaw_rate) > limit > 0.0:
                    speed *= limit / abs(yaw_rate)
        if s + self.look_ahead < self.end:
            heading_here = float(self.path.heading_at(s))
            reference = self.path.point_at(s)
            velocity_world = speed * np.array((math.cos(heading_here), math.sin(heading_here)))
        else:  # the end point is within the look-ahead: walk toward it and stop on it
            reference = self.path.point_at(self.end)
            velocity_world = np.zeros(2)
        velocity_world = velocity_world + (walking_speed / self.look_ahead) * (reference - position)
        norm = float(np.hypot(*velocity_world))
        if norm > walking_speed:
            velocity_world *= walking_speed / norm
        v_x, v_y = rotate_xy(velocity_world, -yaw)  # world -> heading frame
        return fit_command(v_x, v_y, yaw_rate, self.command_range)
