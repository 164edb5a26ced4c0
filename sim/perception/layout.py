"""The rangefinder array's geometry in the base frame: ray directions and the sites that carry them.

A MuJoCo rangefinder measures along the positive z axis of its site. Each ray of
:class:`wbmpc.walking.perception_config.PerceptionConfig` gets a site on the robot's base body at
``mount_position`` whose z axis is the ray's direction (base frame: x forward, y left, z up).
"""

from __future__ import annotations

import numpy as np


def ray_directions_base(pitch_yaw_deg) -> np.ndarray:
    """Unit ray directions, base frame, shape (n, 3), of (pitch [deg] down from the horizontal,
    yaw [deg] to the left of x) pairs: (cos p cos y, cos p sin y, -sin p)."""
    angles = np.deg2rad(np.asarray(pitch_yaw_deg, dtype=float).reshape(-1, 2))
    pitch, yaw = angles[:, 0], angles[:, 1]
    return np.column_stack([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), -np.sin(pitch)])


def quaternion_z_to(direction) -> np.ndarray:
    """(w, x, y, z) quaternion (MuJoCo's order) of the shortest rotation taking +z to the unit
    ``direction`` (3,): the orientation of a site whose z axis is ``direction``."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    axis = np.cross([0.0, 0.0, 1.0], d)
    s, c = float(np.linalg.norm(axis)), float(d[2])
    if s < 1e-12:  # along +z or -z
        return np.array([1.0, 0.0, 0.0, 0.0]) if c > 0 else np.array([0.0, 1.0, 0.0, 0.0])
    angle = np.arctan2(s, c)
    return np.concatenate([[np.cos(0.5 * angle)], np.sin(0.5 * angle) * axis / s])
