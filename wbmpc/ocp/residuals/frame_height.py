"""Frame height residual r = z_frame_world − z_reference (1,) [m]: swing-foot height (eq. 18)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualFrameHeight:
    """r(x) = oMf.translation[2] − z_reference, Rx = [(oRf J_local[:3])[2], 0].

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        height_reference: reference height z* [m] in the world frame; mutable (``reference``).
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, frame_id: int, height_reference: float, nu: int):
        self.state = state
        self.frame_id = int(frame_id)
        self.reference = float(height_reference)
        self.nr = 1
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        data.r[0] = placement.translation[2] - self.reference

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        np.matmul(pdata.oMf[self.frame_id].rotation[2], J_local[:3], out=data.Rx[0, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
