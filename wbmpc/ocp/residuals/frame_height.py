"""Frame height residual r = z_frame_world − z_reference (1,) [m]: swing-foot height (eq. 18)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.kernels.residuals import frame_jacobian_rows_many, frame_rows_many, subtract_rows
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.state import StateMultibody

_Z = np.array([2], dtype=np.int64)


class HeightReference:
    """A residual's mutable reference height z* [m], world frame (``reference``), kept in ``_reference`` (1,)."""

    _reference: np.ndarray

    @property
    def reference(self) -> float:
        """Reference height z* [m], world frame."""
        return float(self._reference[0])

    @reference.setter
    def reference(self, value: float) -> None:
        self._reference[0] = value


class ResidualFrameHeight(HeightReference, BatchedResidual):
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
        self.batch_frames = (self.frame_id,)
        self._reference = np.array([float(height_reference)])
        self.nr = 1
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        subtract_rows(placement.translation[2:], self._reference, data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        np.matmul(pdata.oMf[self.frame_id].rotation[2], J_local[:3], out=data.Rx[0, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nv = self.state.nv
        return np.zeros(nv, dtype=np.int64), np.arange(nv, dtype=np.int64)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        frame_rows_many(horizon.frame_position[:, horizon.frame_slot[self.frame_id]], _Z, references, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        frame_jacobian_rows_many(horizon.frame_jacobian[:, horizon.frame_slot[self.frame_id]], _Z, mask, values)
