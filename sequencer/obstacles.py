"""Obstacles a footstep planner must step over: what perception reports and what the plan avoids.

An :class:`Obstacle` is a box standing on flat ground, described in the world frame by its
footprint (a rectangle) and its height. The robot's perception (``sim.perception``: a rangefinder
array read at its own rate, never the scene's ground truth) reports the obstacles it has detected
in :attr:`wbmpc.walking.measurement.Measurement.obstacles`; the walking controller hands them to the
footstep planner (footholds outside the footprint) and to the whole-body OCP (swing-foot apex and
clearance above the top).

Frames: world frame, z up. The obstacle's *depth axis* points along ``yaw`` (the direction a robot
walking straight at it crosses it); ``depth`` is its extent along that axis, ``width`` across it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sequencer.planner import _finite_scalar, _finite_vector
from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class Obstacle:
    """A box obstacle on the ground, world frame.

    Attributes:
        center: (x, y) of the footprint's centre [m], shape (2,).
        yaw: direction of the depth axis about z [rad] (0: the box is crossed along world x).
        depth: extent along the depth axis [m], > 0.
        width: extent across the depth axis [m], > 0.
        height: height of the top above the ground [m], > 0.
    """

    center: np.ndarray
    yaw: float
    depth: float
    width: float
    height: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _finite_vector("obstacle center", self.center, 2))
        object.__setattr__(self, "yaw", _finite_scalar("obstacle yaw", self.yaw))
        for name in ("depth", "width", "height"):
            value = _finite_scalar(f"obstacle {name}", getattr(self, name))
            if value <= 0.0:
                raise ParameterError(f"obstacle {name}={value} m must be > 0")
            object.__setattr__(self, name, value)

    @property
    def axes(self) -> np.ndarray:
        """Unit depth axis and width axis as rows, world frame, shape (2, 2)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, s], [-s, c]])

    def footprint_corners(self) -> np.ndarray:
        """The footprint's four corners (x, y) [m], counter-clockwise, shape (4, 2)."""
        along, across = self.axes
        half = 0.5 * np.array([self.depth, self.width])
        signs = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
        return self.center + (signs * half) @ np.array([along, across])

    def local(self, points_xy) -> np.ndarray:
        """``points_xy`` (..., 2) in the obstacle's frame: (along the depth axis, across) from the centre [m]."""
        return (np.asarray(points_xy, dtype=float) - self.center) @ self.axes.T

    def contains(self, points_xy, margin: float = 0.0) -> np.ndarray:
        """True where a point (..., 2) lies in the footprint grown by ``margin`` [m] on every side."""
        local = self.local(points_xy)
        return ((np.abs(local[..., 0]) <= 0.5 * self.depth + margin)
                & (np.abs(local[..., 1]) <= 0.5 * self.width + margin))

    def interval_along(self, origin_xy, heading_yaw: float) -> tuple[float, float]:
        """Distances [m] from ``origin_xy`` along the unit direction of ``heading_yaw`` at which that
        line enters and leaves the footprint, (near, far); (inf, inf) when it misses it."""
        direction = np.array([math.cos(heading_yaw), math.sin(heading_yaw)])
        origin = self.local(origin_xy)
        d = self.axes @ direction
        half = 0.5 * np.array([self.depth, self.width])
        near, far = -math.inf, math.inf
        for k in range(2):
            if abs(d[k]) < 1e-12:
                if abs(origin[k]) > half[k]:
                    return (math.inf, math.inf)
                continue
            t1, t2 = sorted(((-half[k] - origin[k]) / d[k], (half[k] - origin[k]) / d[k]))
            near, far = max(near, t1), min(far, t2)
        if near > far:
            return (math.inf, math.inf)
        return (float(near), float(far))

    def grown(self, margin: float) -> "Obstacle":
        """The same box with its footprint grown by ``margin`` [m] >= 0 on every side (height kept)."""
        margin = _finite_scalar("margin", margin)
        if margin < 0.0:
            raise ParameterError(f"margin={margin} m must be >= 0")
        return Obstacle(self.center, self.yaw, self.depth + 2.0 * margin, self.width + 2.0 * margin, self.height)
