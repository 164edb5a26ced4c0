"""Reference postures: placing a configuration so that its feet touch the floor z = 0."""

from __future__ import annotations

import numpy as np
import pinocchio as pin


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
