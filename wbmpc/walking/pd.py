"""A posture-holding joint PD (no balance): exercises a closed loop without any planning."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.walking.measurement import Measurement

GRAVITY = 9.81  # [m/s^2]


class JointPDController:
    """Holds the robot's reference posture with a joint PD (no balance: Bolt falls within ~1 s).

    Useful to exercise the runner (logging, fall detection) without any planning.

    Args:
        kp: proportional gain [N·m/rad], > 0.
        kd: derivative gain [N·m·s/rad], >= 0.
        replan_period: period of the (empty) slow update [s].
    """

    def __init__(self, kp: float = 3.0, kd: float = 0.05, replan_period: float = 0.01) -> None:
        if not kp > 0:
            raise ParameterError(f"kp={kp} N·m/rad must be > 0")
        if not kd >= 0:
            raise ParameterError(f"kd={kd} N·m·s/rad must be >= 0")
        self.kp, self.kd, self.replan_period = float(kp), float(kd), float(replan_period)
        self._q_joints_reference = None
        self._nq = 0
        self.omega = float("nan")

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        self._nq = robot.pinocchio_model.nq
        self._q_joints_reference = np.asarray(robot.q_reference)[7:].copy()
        # the DCM the runner logs: LIP frequency at the standing CoM height
        self.omega = math.sqrt(GRAVITY / robot.com_height_reference)

    def set_velocity_command(self, command) -> None:
        """Ignored: the PD holds the posture."""

    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        return {}

    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        q_joints = measurement.x[7 : self._nq]
        v_joints = measurement.x[self._nq + 6 :]
        return self.kp * (self._q_joints_reference - q_joints) - self.kd * v_joints
