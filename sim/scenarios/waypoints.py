"""``waypoints``: walk along a closed path (a circle or a square), heading along it (issue 13).

The command comes from the measured base pose through a pure-pursuit follower
(:class:`sim.path_follower.PathFollower`), kept within the controller's command range: a robot
that can turn (G1: +-0.3 rad/s) turns with the path, slowing down toward a corner to the speed
its yaw-rate limit turns within ``corner_deviation`` of it; one that cannot (Bolt: yaw rate 0) keeps
its heading and walks sideways and backwards where the path asks it to, as fast as its v_x and
v_y ranges allow. The paths start at the robot's standing position, along its heading
(:mod:`sim.paths`); the metrics (``path_deviation_*``, ``heading_error_max``, ``path_completion``)
are in :mod:`sim.metrics`.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim.path_follower import PathFollower
from sim.paths import PATHS, path_from_parameters
from sim.scenarios.base import Scenario, _check_range, register
from wbmpc.errors import ParameterError


@register("waypoints")
@dataclass(frozen=True)
class Waypoints(Scenario):
    """Walk ``laps`` times round ``path`` at ``speed`` [m/s] (reached by a ramp over ``ramp_time``),
    then stop at its end (the start, on these closed paths) and step in place."""

    default_duration = 50.0  # [s]: a lap of the circle (6.3 m) or of the square (8 m, its turns slower) at 0.25 m/s

    speed: float = 0.25  # [m/s], along the path
    path: str = "circle"  # one of sim.paths.PATHS
    radius: float = 1.0  # [m], circle
    side: float = 2.0  # [m], square
    laps: float = 1.0  # [-], times round the path
    look_ahead: float = 0.3  # [m], along the path, to the point the robot walks toward
    heading_gain: float = 1.0  # [1/s], yaw rate per heading error
    corner_deviation: float = 0.05  # [m], how far a turn at the yaw-rate limit may cut a corner (the corner speed)
    corner_rate: float = 0.5  # [1/s], of the slowdown toward a corner and the speed-up after it, below heading_gain

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.lateral_speed != 0.0 or self.yaw_rate != 0.0:
            raise ParameterError(f"waypoints: lateral_speed={self.lateral_speed} and yaw_rate={self.yaw_rate} must be 0 "
                                 f"(the path follower sets v_y and the yaw rate; give the speed only)")
        if self.path not in PATHS:  # before the sizes: the name is the likelier mistake
            raise ParameterError(f"path={self.path!r} is unknown (allowed: {', '.join(PATHS)})")
        _check_range("speed", self.speed, 1e-3, 2.0, "m/s")
        _check_range("laps", self.laps, 1e-3, 100.0, "")
        _check_range("look_ahead", self.look_ahead, 0.01, 10.0, "m")
        _check_range("heading_gain", self.heading_gain, 0.01, 100.0, "1/s")
        _check_range("corner_deviation", self.corner_deviation, 1e-3, 1.0, "m")
        self._set_follower(None)

    def _set_follower(self, command_range) -> None:
        follower = PathFollower(path_from_parameters(vars(self)), self.speed, self.look_ahead, self.heading_gain,
                                self.laps, command_range, self.corner_deviation, self.corner_rate)
        object.__setattr__(self, "follower", follower)  # the run's state (progress), not a parameter

    def setup(self, robot, command_range) -> None:
        self._set_follower(command_range)  # a new follower: progress from the start of the path

    def velocity_command(self, t: float, pose=None) -> tuple[float, float, float]:
        """The follower's command for the measured base ``pose`` (x [m], y [m], yaw [rad]), world frame."""
        if pose is None:
            raise ParameterError("waypoints: velocity_command needs the measured pose (x, y, yaw)")
        ramp = 1.0 if self.ramp_time <= 0.0 else min(1.0, t / self.ramp_time)
        return self.follower.command(pose, ramp)

    def commands(self) -> list[tuple[float, float, float]]:
        """The fastest straight command; the follower keeps the others within the controller's range."""
        return [(self.speed, 0.0, 0.0)]
