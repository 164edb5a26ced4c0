"""Flat feet: sole frames added to a Pinocchio model and the sole spheres of the MuJoCo model.

Shared by the flat-footed robots (G1, H1): each has a sole frame per foot at a fixed offset from
its ankle link, and a few small collision spheres under each sole in MuJoCo.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError


def add_sole_frames(
    model: pin.Model,
    sole_frames: Mapping[str, str],
    ankle_frames: Mapping[str, str],
    sole_center_in_ankle: np.ndarray,
) -> None:
    """Add one operational frame per foot at the sole centre, parallel to its ankle link frame.

    Args:
        model: Pinocchio model, modified in place.
        sole_frames: {side: name of the new sole frame}.
        ankle_frames: {side: name of the existing ankle link (body) frame}.
        sole_center_in_ankle: (3,) sole centre in the ankle link frame [m] (same for both feet).
    """
    offset = pin.SE3(np.eye(3), np.asarray(sole_center_in_ankle, dtype=float))
    for side, frame_name in sole_frames.items():
        if not model.existFrame(ankle_frames[side]):
            raise ParameterError(f"ankle frame {ankle_frames[side]!r} of the {side} foot is not a frame of the model")
        ankle_id = model.getFrameId(ankle_frames[side])
        ankle = model.frames[ankle_id]
        placement = ankle.placement * offset  # relative to the ankle's parent joint
        model.addFrame(pin.Frame(frame_name, ankle.parentJoint, ankle_id, placement, pin.FrameType.OP_FRAME))


def sole_sphere_geoms(
    ankle_links: Mapping[str, str], sphere_centers_in_ankle: Sequence[Sequence[float]], radius: float
) -> dict[str, tuple[tuple[str, tuple[float, float, float], float], ...]]:
    """``RobotDescription.mujoco_foot_geoms`` of spheres at the same places under both ankle links.

    Args:
        ankle_links: {side: MuJoCo body name of the ankle link}.
        sphere_centers_in_ankle: sphere centres in the ankle link frame, each (3,) [m].
        radius: sphere radius [m].

    Returns:
        {side: ((body, centre, radius), ...)}, in the order of ``sphere_centers_in_ankle``.
    """
    centers = tuple(tuple(float(x) for x in center) for center in sphere_centers_in_ankle)
    return {side: tuple((body, center, float(radius)) for center in centers) for side, body in ankle_links.items()}
