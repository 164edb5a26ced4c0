"""Height of a point fixed on a frame, r = z_world(oMf · p) − z_reference (1,) [m]: obstacle clearance.

With an :class:`~wbmpc.ocp.activations.ActivationQuadraticBarrier` of bounds (0, +inf) it is an
inequality, penalised only below the reference: the walking OCP keeps the swing sole's toe and heel
points and the shank (knee frame) above an obstacle's top plus a margin while the swing passes over
it (:mod:`wbmpc.walking.ocp`, ``{foot}_clearance_*`` terms).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError, check_finite
from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.residuals.frame_height import HeightReference
from wbmpc.ocp.state import StateMultibody


class ResidualFramePointHeight(HeightReference):
    """r(x) = (oMf.translation + oRf p)[2] − z_reference, Rx = [(oRf (J_v − [p]× J_ω))[2], 0].

    (J_v, J_ω: the frame's LOCAL Jacobian; the point's velocity is v + ω × p = (J_v − [p]× J_ω) q̇ in the
    frame, rotated to the world by oRf.)

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        point_local: the point in the frame, (3,) [m] (zeros: the frame's origin).
        height_reference: reference height z* [m], world frame; mutable (``reference``).
        nu: control dimension.
    """

    batch_unsupported = "a point offset from its frame (node-wise evaluation only)"

    def __init__(self, state: StateMultibody, frame_id: int, point_local, height_reference: float, nu: int):
        point = np.asarray(point_local, dtype=float).reshape(-1)
        if point.shape != (3,):
            raise ParameterError(f"point_local={point_local!r} must be 3 numbers [m]")
        check_finite("point_local", point)
        self.state = state
        self.frame_id = int(frame_id)
        self.point_local = point
        self._skew = pin.skew(point)
        self._reference = np.array([float(height_reference)])
        self.nr = 1
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        data.r[0] = placement.translation[2] + placement.rotation[2] @ self.point_local - self._reference[0]

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        J_local = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        point_rows = J_local[:3] - self._skew @ J_local[3:]
        np.matmul(pdata.oMf[self.frame_id].rotation[2], point_rows, out=data.Rx[0, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
