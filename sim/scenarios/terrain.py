"""``terrain``: cluttered ground (paper, section IV.C): random boxes on the robot's path.

Boxes have sides of 1-5 cm and heights of 5-8 mm, with a mean density of 10 per m², placed
uniformly (random yaw) over a strip ahead of the robot that covers the distance it walks.

These are the paper's sizes, for Bolt. For another robot the box sides, heights and the strip's
width are multiplied by ``scale``: by default the robot's size relative to Bolt's, the ratio of
their base heights at the reference posture (:func:`robot_scale`; G1 2.2), so that a bigger robot
meets obstacles as big for it; the density (per m²) is kept. ``scale=1`` gives the paper's sizes
to any robot.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from sim.scenarios.base import Scenario, _check_range, register

PAPER_ROBOT = "bolt"  # the robot the paper's sizes are for


@functools.cache
def _paper_robot_base_height() -> float:
    from robots import load_robot

    return load_robot(PAPER_ROBOT).base_height_reference


def robot_scale(robot) -> float:
    """Size of ``robot`` (a :class:`robots.description.RobotDescription`) relative to the paper's
    robot: the ratio of their base heights at the reference posture [-] (Bolt 1, G1 2.2)."""
    return robot.base_height_reference / _paper_robot_base_height()


@register("terrain")
@dataclass(frozen=True)
class Terrain(Scenario):
    """Walk at ``speed`` over randomly placed low boxes."""

    default_duration = 20.0

    speed: float = 0.3  # [m/s]
    density: float = 10.0  # [boxes / m²]
    side_min: float = 0.01  # [m]
    side_max: float = 0.05  # [m]
    height_min: float = 0.005  # [m]
    height_max: float = 0.008  # [m]
    x_start: float = 0.25  # [m], start of the cluttered strip (world x)
    length: float = 8.0  # [m], length of the strip along x
    width: float = 0.6  # [m], width of the strip (centred on y = 0)
    friction: float = 1.0  # sliding friction coefficient of the boxes
    scale: float | None = None  # [-], multiplies sides, heights and width; None: robot_scale of the run's robot

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range("density", self.density, 0.0, 1000.0, "1/m²")
        _check_range("side_min", self.side_min, 1e-3, 0.5, "m")
        _check_range("side_max", self.side_max, self.side_min, 0.5, "m")
        _check_range("height_min", self.height_min, 1e-4, 0.2, "m")
        _check_range("height_max", self.height_max, self.height_min, 0.2, "m")
        _check_range("length", self.length, 0.0, 1e3, "m")
        _check_range("width", self.width, 0.0, 100.0, "m")
        _check_range("friction", self.friction, 0.0, 10.0, "")
        if self.scale is not None:
            _check_range("scale", self.scale, 0.1, 10.0, "")
        self._set_size_scale(1.0 if self.scale is None else self.scale)  # the paper's robot until setup

    def _set_size_scale(self, value: float) -> None:
        object.__setattr__(self, "size_scale", float(value))  # the run's, not a parameter

    def setup(self, robot, command_range) -> None:
        if self.scale is None:
            self._set_size_scale(robot_scale(robot))

    def sample_boxes(self, rng: np.random.Generator) -> np.ndarray:
        """Random boxes: rows (x, y, yaw [rad], side_x, side_y, height) [m], shape (n, 6), with the
        sizes and the width times ``size_scale`` (1 before :meth:`setup`; see the module docstring)."""
        k = self.size_scale
        width = k * self.width
        n = int(rng.poisson(self.density * self.length * width))
        x = self.x_start + rng.uniform(0.0, self.length, n)
        y = rng.uniform(-0.5 * width, 0.5 * width, n)
        yaw = rng.uniform(0.0, np.pi, n)
        sides = rng.uniform(k * self.side_min, k * self.side_max, (n, 2))
        height = rng.uniform(k * self.height_min, k * self.height_max, n)
        return np.column_stack([x, y, yaw, sides, height])

    def modify_spec(self, spec, rng: np.random.Generator) -> None:
        from robots.mujoco_model import add_box_geom

        for i, (x, y, yaw, sx, sy, h) in enumerate(self.sample_boxes(rng)):
            add_box_geom(
                spec, f"terrain_box_{i}", np.array([x, y, 0.5 * h]), 0.5 * np.array([sx, sy, h]),
                friction=self.friction, yaw=yaw, rgba=(0.55, 0.45, 0.35, 1.0),
            )
