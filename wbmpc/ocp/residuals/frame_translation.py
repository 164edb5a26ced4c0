"""Frame translation residual r = p_frame_world − p_reference_world (3,) [m] (foothold tracking)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.kernels.residuals import frame_jacobian_rows_many, frame_rows_many, subtract_rows
from wbmpc.ocp.residuals.base import (
    BatchedResidual,
    DataCollector,
    HorizonData,
    ResidualData,
    dense_jacobian_pattern,
)
from wbmpc.ocp.state import StateMultibody

_XYZ = np.array([0, 1, 2], dtype=np.int64)


class ResidualFrameTranslation(BatchedResidual):
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
        self.batch_frames = (self.frame_id,)
        self._reference = np.asarray(reference_world, dtype=float).reshape(3).copy()
        self.nr = 3
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        subtract_rows(placement.translation, self._reference, data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        np.matmul(pdata.oMf[self.frame_id].rotation, J_local[:3], out=data.Rx[:, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return dense_jacobian_pattern(3, self.state.nv)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        frame_rows_many(horizon.frame_position[:, horizon.frame_slot[self.frame_id]], _XYZ, references, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        frame_jacobian_rows_many(horizon.frame_jacobian[:, horizon.frame_slot[self.frame_id]], _XYZ, mask, values)
