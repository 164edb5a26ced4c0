"""Frame translation residual r = p_frame_world − p_reference_world (3,) [m] (foothold tracking)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualFrameTranslation:
    """r(x) = oMf.translation − reference (world frame), Rx = [oRf J_local[:3], 0].

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        reference_world: reference position (3,) [m], world frame; mutable through ``reference``.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, frame_id: int, reference_world: np.ndarray, nu: int):
        self.state = state
        self.frame_id = int(frame_id)
        self.reference = np.asarray(reference_world, dtype=float).reshape(3).copy()
        self.nr = 3
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        np.subtract(placement.translation, self.reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        np.matmul(pdata.oMf[self.frame_id].rotation, J_local[:3], out=data.Rx[:, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
