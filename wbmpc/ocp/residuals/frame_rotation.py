"""Frame orientation residual r = log3(R_ref^T R_frame) (3,) [rad]: swing-foot orientation (land flat,
with the planned yaw)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualFrameRotation:
    """r(x) = log3(R_ref^T oRf) (the rotation from the reference to the frame, in the frame's axes),
    Rx = [Jlog3(R_ref^T oRf) J_local[3:], 0].

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        reference: reference rotation (3, 3), world frame; mutable through ``reference`` (written in place).
        nu: control dimension.
    """

    #: why :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` cannot batch this term
    batch_unsupported = "the compiled horizon kinematics computes frame positions and their Jacobians, not rotations"

    def __init__(self, state: StateMultibody, frame_id: int, reference: np.ndarray | None = None, nu: int = 0):
        self.state = state
        self.frame_id = int(frame_id)
        self.reference = np.eye(3) if reference is None else np.array(reference, dtype=float).reshape(3, 3)
        self.nr = 3
        self.nu = nu
        self._error = np.eye(3)

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        np.matmul(self.reference.T, placement.rotation, out=self._error)
        data.r[:] = pin.log3(self._error)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        np.matmul(self.reference.T, pdata.oMf[self.frame_id].rotation, out=self._error)
        np.matmul(pin.Jlog3(self._error), J_local[3:], out=data.Rx[:, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)


def yaw_rotation(yaw: float) -> np.ndarray:
    """Rotation (3, 3) about the world z axis by ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
