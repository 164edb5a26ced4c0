"""A box across the H1's path and a walking controller told where it is (test-side; the ``obstacle``
scenario and the perception that sees the box are the simulation's, ``sim/scenarios/obstacle.py``).

- scenario ``step_over_box``: a box across the path (centred on the robot's straight line, yaw 0), its near
  edge ``distance`` ahead of the start, ``height`` high, ``depth`` deep, ``width`` wide;
- :class:`KnownObstacleController`: the walking controller whose measurements carry the box as perceived
  (``Measurement.obstacles``), the true one;
- :class:`BoxContacts`: a tick observer recording every contact of the robot with the box and the lowest
  clearance of the sole spheres over its footprint.

Used by ``tests/test_sim_h1_negotiation.py`` and ``docs/scripts/h1_step_over.py``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import mujoco
import numpy as np

from robots.mujoco_model import add_box_geom
from sequencer.obstacles import Obstacle
from sim.scenarios.base import _REGISTRY, Scenario, register
from wbmpc.walking.controller import WalkingController

BOX_GEOM = "step_over_box"


@dataclass(frozen=True)
class StepOverBox(Scenario):
    """Walk at ``speed`` towards a box across the path and step over it."""

    default_duration = 8.0

    speed: float = 0.3  # [m/s]
    ramp_time: float = 1.0  # [s]
    distance: float = 1.0  # [m], world x of the box's near edge (the robot starts at x = 0)
    height: float = 0.1  # [m]
    depth: float = 0.1  # [m], along x
    width: float = 1.2  # [m], across the path

    def obstacle(self) -> Obstacle:
        """The box as an :class:`~sequencer.obstacles.Obstacle` (world frame)."""
        return Obstacle(np.array([self.distance + 0.5 * self.depth, 0.0]), 0.0, self.depth, self.width, self.height)

    def modify_spec(self, spec, rng) -> None:
        add_box_geom(spec, BOX_GEOM, np.array([self.distance + 0.5 * self.depth, 0.0, 0.5 * self.height]),
                     0.5 * np.array([self.depth, self.width, self.height]), rgba=(0.8, 0.3, 0.2, 1.0))


if "step_over_box" not in _REGISTRY:
    register("step_over_box")(StepOverBox)


class KnownObstacleController(WalkingController):
    """The walking controller, its measurements carrying ``obstacles`` (world frame) as perceived."""

    def __init__(self, preset, obstacles, **kwargs) -> None:
        super().__init__(preset, **kwargs)
        self.known_obstacles = tuple(obstacles)

    def replan(self, t, measurement):
        return super().replan(t, dataclasses.replace(measurement, obstacles=self.known_obstacles))


class BoxContacts:
    """Tick observer (``run_scenario(on_tick=...)``): contacts of the robot with the box and clearance.

    Attributes:
        touches: (time [s], body name) of every tick with a robot-box contact (first contact of the tick).
        clearance: lowest height [m] of a sole sphere's bottom above the box's top while its centre is over
            the footprint (inf: none passed over it).
        crossed_time: first time [s] every sole sphere is beyond the box's far edge (None: never).
    """

    def __init__(self, box: StepOverBox) -> None:
        self.box = box
        self.touches: list[tuple[float, str]] = []
        self.clearance = np.inf
        self.crossed_time = None
        self._ids = None

    def __call__(self, model, data) -> None:
        if self._ids is None:
            box_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, BOX_GEOM)
            spheres = [g for g in range(model.ngeom)
                       if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE and model.geom_contype[g]]
            self._ids = (box_id, np.array(spheres))
        box_id, spheres = self._ids
        for g1, g2 in zip(data.contact.geom1[: data.ncon].tolist(), data.contact.geom2[: data.ncon].tolist()):
            if box_id in (g1, g2):
                other = g2 if g1 == box_id else g1
                self.touches.append((float(data.time), model.body(model.geom_bodyid[other]).name))
                break
        positions = data.geom_xpos[spheres]
        near, far = self.box.distance, self.box.distance + self.box.depth
        over = (positions[:, 0] >= near) & (positions[:, 0] <= far) & (np.abs(positions[:, 1]) <= 0.5 * self.box.width)
        if over.any():
            bottom = positions[over, 2] - model.geom_size[spheres[over], 0]
            self.clearance = min(self.clearance, float(bottom.min()) - self.box.height)
        if self.crossed_time is None and np.all(positions[:, 0] > far):
            self.crossed_time = float(data.time)
