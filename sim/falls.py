"""Fall detection and foot-contact sensing from the MuJoCo contact list and the base pose.

A run counts as a fall when the base gets too low, tilts too much, or any part of the robot other
than a foot touches the ground. Ground geoms are those attached to the world body (floor, terrain
boxes, patches); a contact belongs to a foot when its point lies within the foot sphere (radius +
``foot_contact_margin``) of a foot frame, so the test does not depend on geom names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class FallCriteria:
    """Thresholds of fall detection.

    Attributes:
        min_base_height: base height below which the robot has fallen [m] (Bolt stands at 0.34 m).
        max_tilt: largest angle between the base z axis and the world vertical [rad].
        foot_contact_margin: distance beyond the foot radius within which a ground contact is still
            attributed to the foot [m].
        detect_non_foot_contact: treat a ground contact away from the feet as a fall.
    """

    min_base_height: float = 0.18
    max_tilt: float = np.deg2rad(50.0)
    foot_contact_margin: float = 0.01
    detect_non_foot_contact: bool = True

    def __post_init__(self) -> None:
        if not (np.isfinite(self.min_base_height) and self.min_base_height >= 0.0):
            raise ParameterError(f"min_base_height={self.min_base_height} m must be >= 0")
        if not (0.0 < self.max_tilt <= np.pi):
            raise ParameterError(f"max_tilt={self.max_tilt} rad must be in (0, pi]")
        if not self.foot_contact_margin >= 0.0:
            raise ParameterError(f"foot_contact_margin={self.foot_contact_margin} m must be >= 0")


class ContactSensor:
    """Classifies MuJoCo contacts between the robot and the ground.

    Args:
        model: compiled ``mujoco.MjModel``.
        foot_radius: radius of the foot spheres [m].
        margin: see :attr:`FallCriteria.foot_contact_margin`.
    """

    def __init__(self, model, foot_radius: float, margin: float) -> None:
        self.ground_geom = np.asarray(model.geom_bodyid) == 0
        self.ground_geom_list = self.ground_geom.tolist()
        self.reach = float(foot_radius) + float(margin)
        self.model = model

    def classify(self, data, feet_position_world: np.ndarray) -> tuple[np.ndarray, str | None]:
        """Feet touching the ground and the first non-foot ground contact.

        Args:
            data: ``mujoco.MjData`` after a step (contacts computed).
            feet_position_world: shape (n_feet, 3), foot frame positions [m].

        Returns:
            (foot_in_contact (n_feet,) bool, description of a non-foot ground contact or None).
        """
        n_feet = len(feet_position_world)
        in_contact = np.zeros(n_feet, dtype=bool)
        if data.ncon == 0:
            return in_contact, None
        # plain Python over the few contacts: faster than numpy on arrays this small (1 kHz path)
        contacts = data.contact
        ground = self.ground_geom_list
        feet = feet_position_world.tolist()
        reach2 = self.reach * self.reach
        other = None
        for g1, g2, point in zip(contacts.geom1.tolist(), contacts.geom2.tolist(), contacts.pos.tolist()):
            ground1, ground2 = ground[g1], ground[g2]
            if ground1 == ground2:
                continue
            nearest, nearest_d2 = 0, float("inf")
            for f, foot in enumerate(feet):
                d2 = (point[0] - foot[0]) ** 2 + (point[1] - foot[1]) ** 2 + (point[2] - foot[2]) ** 2
                if d2 < nearest_d2:
                    nearest, nearest_d2 = f, d2
            if nearest_d2 <= reach2:
                in_contact[nearest] = True
            elif other is None:
                robot_geom = g2 if ground1 else g1
                body = self.model.body(self.model.geom_bodyid[robot_geom]).name
                other = f"ground contact of body {body!r} at {np.round(point, 3).tolist()} m"
        return in_contact, other


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
