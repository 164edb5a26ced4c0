"""Reference postures: joint angles by name, and placing a configuration so that its feet touch
the floor z = 0."""

from __future__ import annotations

from typing import Mapping

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError

SIDES = ("left", "right")


def both_sides(angles_by_suffix: Mapping[str, float]) -> dict[str, float]:
    """{joint name: angle [rad]}: each ``suffix: angle`` on the joints "left_<suffix>" and "right_<suffix>".

    Args:
        angles_by_suffix: {joint name without its side prefix ("knee_joint"): angle [rad]}.
    """
    return {f"{side}_{suffix}": float(angle) for suffix, angle in angles_by_suffix.items() for side in SIDES}


def configuration_with_joint_angles(model: pin.Model, joint_angles: Mapping[str, float]) -> np.ndarray:
    """``pin.neutral(model)`` with the named one-dof joints set to the given angles [rad].

    Raises:
        ParameterError: a name is not a joint of ``model`` or not a one-dof joint.
    """
    q = pin.neutral(model)
    for name, angle in joint_angles.items():
        if not model.existJointName(name):
            raise ParameterError(f"joint {name!r} of the posture is not a joint of the model")
        joint = model.joints[model.getJointId(name)]
        if joint.nq != 1:
            raise ParameterError(f"joint {name!r} of the posture has nq={joint.nq}, expected a one-dof joint")
        q[joint.idx_q] = float(angle)
    return q


def standing_on_floor(model: pin.Model, q: np.ndarray, foot_frames: dict[str, str], frame_height: float) -> np.ndarray:
    """Shift ``q``'s base height so the lowest foot frame is at ``frame_height`` above z = 0.

    Args:
        model: Pinocchio model.
        q: (nq,) configuration (not modified).
        foot_frames: {side: frame name}.
        frame_height: wanted height of the foot frames [m] (e.g. the foot sphere radius).

    Returns:
        (nq,) configuration with ``q[2]`` adjusted.
    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    lowest = min(data.oMf[model.getFrameId(frame)].translation[2] for frame in foot_frames.values())
    q_floor = np.array(q, dtype=float)
    q_floor[2] += frame_height - lowest
    return q_floor
