"""Fall detection and foot-contact sensing from the MuJoCo contact list and the base pose.

A run counts as a fall when the base gets too low, tilts too much, or any part of the robot other
than a foot touches the ground. Ground geoms are those attached to the world body (floor, terrain
boxes, patches); a contact belongs to a foot when the robot's geom in it is one of that foot's
collision geoms (``robot.mujoco_foot_geoms``: Bolt's sphere, the G1's sole spheres), so every
robot's foot geometry is known, whatever its size.

Obstacles (``sim.scenarios.obstacle``): world geoms whose name starts with ``OBSTACLE_GEOM_PREFIX``
are classified apart (:meth:`ContactSensor.classify_with_obstacles`). A foot on an obstacle is a
foot in contact (``foot_in_contact``: the controller must know a foot that landed on the box bears
weight) *and* an obstacle contact; any other part of the robot touching an obstacle (a shank
against the box's edge) is an obstacle contact, not a fall by itself (the fall detector still
watches the base height, the tilt and the other ground contacts). The runner logs every obstacle
contact per tick (``ticks["obstacle_contact"]``), which the obstacle metrics read (``touched``,
resting on the obstacle at the end).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from robots.mujoco_model import foot_geom_name
from wbmpc.errors import ParameterError

OBSTACLE_GEOM_PREFIX = "obstacle"  # world geoms named so are obstacles (see the module docstring)


@dataclass(frozen=True)
class FallCriteria:
    """Thresholds of fall detection.

    Attributes:
        min_base_height: base height below which the robot has fallen [m] (Bolt stands at 0.34 m).
        max_tilt: largest angle between the base z axis and the world vertical [rad].
        detect_non_foot_contact: treat a ground contact away from the feet as a fall.
    """

    min_base_height: float = 0.18
    max_tilt: float = np.deg2rad(50.0)
    detect_non_foot_contact: bool = True

    def __post_init__(self) -> None:
        if not (np.isfinite(self.min_base_height) and self.min_base_height >= 0.0):
            raise ParameterError(f"min_base_height={self.min_base_height} m must be >= 0")
        if not (0.0 < self.max_tilt <= np.pi):
            raise ParameterError(f"max_tilt={self.max_tilt} rad must be in (0, pi]")


class ContactSensor:
    """Classifies MuJoCo contacts between the robot and the ground.

    Args:
        model: compiled ``mujoco.MjModel`` built by ``robots.mujoco_model.build_mujoco_spec``.
        robot: its ``robots.RobotDescription`` (foot order and foot geoms).
    """

    def __init__(self, model, robot) -> None:
        self.ground_geom_list = (np.asarray(model.geom_bodyid) == 0).tolist()
        self.obstacle_geom_list = [bool(ground) and model.geom(g).name.startswith(OBSTACLE_GEOM_PREFIX)
                                   for g, ground in enumerate(self.ground_geom_list)]
        self.n_feet = len(robot.foot_frames)
        self.foot_of_geom: dict[int, int] = {}
        for index, side in enumerate(robot.foot_frames):
            for k in range(len(robot.mujoco_foot_geoms[side])):
                geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, foot_geom_name(side, k))
                if geom < 0:
                    raise ParameterError(f"the MuJoCo model has no foot geom {foot_geom_name(side, k)!r}")
                self.foot_of_geom[geom] = index
        self.model = model

    def classify(self, data) -> tuple[np.ndarray, str | None]:
        """Feet touching the ground and the first non-foot ground contact.

        Args:
            data: ``mujoco.MjData`` after a step (contacts computed).

        Returns:
            (foot_in_contact (n_feet,) bool, description of a non-foot ground contact or None).
        """
        in_contact, other, _ = self.classify_with_obstacles(data)
        return in_contact, other

    def classify_with_obstacles(self, data) -> tuple[np.ndarray, str | None, np.ndarray]:
        """:meth:`classify` and the robot's contacts with obstacles.

        Returns:
            (foot_in_contact (n_feet,) bool, description of a non-foot ground contact that is not an
            obstacle contact or None, obstacle_contact (n_feet + 1,) bool: each foot on an obstacle,
            then any other part of the robot touching one).
        """
        in_contact = np.zeros(self.n_feet, dtype=bool)
        on_obstacle = np.zeros(self.n_feet + 1, dtype=bool)
        if data.ncon == 0:
            return in_contact, None, on_obstacle
        obstacles = self.obstacle_geom_list
        # plain Python over the few contacts: faster than numpy on arrays this small (1 kHz path)
        contacts = data.contact
        ground = self.ground_geom_list
        feet = self.foot_of_geom
        other = None
        for g1, g2, point in zip(contacts.geom1.tolist(), contacts.geom2.tolist(), contacts.pos.tolist()):
            ground1, ground2 = ground[g1], ground[g2]
            if ground1 == ground2:
                continue
            robot_geom = g2 if ground1 else g1
            foot = feet.get(robot_geom)
            obstacle = obstacles[g1 if ground1 else g2]
            if obstacle:
                on_obstacle[self.n_feet if foot is None else foot] = True
            if foot is not None:
                in_contact[foot] = True
            elif other is None and not obstacle:
                body = self.model.body(self.model.geom_bodyid[robot_geom]).name
                other = f"ground contact of body {body!r} at {np.round(point, 3).tolist()} m"
        return in_contact, other, on_obstacle


def base_tilt(quaternion_xyzw: np.ndarray) -> float:
    """Angle between the base z axis and the world vertical [rad], from a (x, y, z, w) quaternion."""
    x, y = float(quaternion_xyzw[0]), float(quaternion_xyzw[1])
    # z component of the base z axis in the world frame: 1 - 2 (x² + y²); scalar math (1 kHz path)
    return math.acos(min(1.0, max(-1.0, 1.0 - 2.0 * (x * x + y * y))))


def detect_fall(criteria: FallCriteria, q: np.ndarray, non_foot_contact: str | None) -> str | None:
    """Reason of a fall at configuration ``q`` (Pinocchio), or None if the robot is still up."""
    if q[2] < criteria.min_base_height:
        return f"base height {q[2]:.3f} m < min_base_height={criteria.min_base_height} m"
    tilt = base_tilt(q[3:7])
    if tilt > criteria.max_tilt:
        return f"base tilt {np.rad2deg(tilt):.1f} deg > max_tilt={np.rad2deg(criteria.max_tilt):.1f} deg"
    if criteria.detect_non_foot_contact and non_foot_contact is not None:
        return non_foot_contact
    return None
