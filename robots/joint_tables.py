"""Per-joint numbers given by joint-name suffix (motor classes, speed ratings)."""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from wbmpc.errors import ParameterError


def values_by_joint_suffix(
    joint_names: Sequence[str], values_by_suffix: Mapping[str, float], quantity: str
) -> np.ndarray:
    """(len(joint_names),) array: for each joint, the value of the first suffix its name ends with.

    Args:
        joint_names: joint names (e.g. ``RobotDescription.actuated_joint_names``).
        values_by_suffix: {name suffix ("knee_joint"): value}; checked in order.
        quantity: what the values are ("armature [kg·m²]"), for the error message.

    Raises:
        ParameterError: a joint name ends with none of the suffixes.
    """
    values = []
    for name in joint_names:
        match = next((value for suffix, value in values_by_suffix.items() if name.endswith(suffix)), None)
        if match is None:
            raise ParameterError(f"joint {name!r} has no {quantity} (known suffixes: {sorted(values_by_suffix)})")
        values.append(float(match))
    return np.array(values)
