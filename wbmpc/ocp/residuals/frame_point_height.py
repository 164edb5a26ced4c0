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
from wbmpc.ocp.kernels.residuals import (
    point_height_jacobian_many,
    point_height_jacobian_row,
    point_height_row,
    point_height_rows_many,
)
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.residuals.frame_height import HeightReference
from wbmpc.ocp.state import StateMultibody


class ResidualFramePointHeight(HeightReference, BatchedResidual):
    """r(x) = (oMf.translation + oRf p)[2] − z_reference, Rx = [J_v[2] + w_y J_ω[0] − w_x J_ω[1], 0].

    (J_v, J_ω: the frame's LOCAL_WORLD_ALIGNED Jacobian, w = oRf p: the point's world velocity is
    v + ω × w.) Both evaluations use the same compiled rows (:mod:`wbmpc.ocp.kernels.residuals`);
    the batched one reads the frame's rotation and angular Jacobian rows from the horizon.

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        point_local: the point in the frame, (3,) [m] (zeros: the frame's origin).
        height_reference: reference height z* [m], world frame; mutable (``reference``).
        nu: control dimension.
    """

    batch_frame_rotations = True

    def __init__(self, state: StateMultibody, frame_id: int, point_local, height_reference: float, nu: int):
        point = np.asarray(point_local, dtype=float).reshape(-1)
        if point.shape != (3,):
            raise ParameterError(f"point_local={point_local!r} must be 3 numbers [m]")
        check_finite("point_local", point)
        self.state = state
        self.frame_id = int(frame_id)
        self.batch_frames = (self.frame_id,)
        self.point_local = point
        self._reference = np.array([float(height_reference)])
        self.nr = 1
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        data.r[0] = point_height_row(placement.translation, placement.rotation, self.point_local, self._reference[0])

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        jacobian = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL_WORLD_ALIGNED)
        point_height_jacobian_row(jacobian, pdata.oMf[self.frame_id].rotation, self.point_local,
                                  data.Rx[0, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nv = self.state.nv
        return np.zeros(nv, dtype=np.int64), np.arange(nv, dtype=np.int64)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        slot = horizon.frame_slot[self.frame_id]
        point_height_rows_many(horizon.frame_position[:, slot], horizon.frame_rotation[:, slot], self.point_local,
                               references, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        slot = horizon.frame_slot[self.frame_id]
        point_height_jacobian_many(horizon.frame_jacobian[:, slot], horizon.frame_rotation[:, slot], self.point_local,
                                   mask, values)

    def batch_signature(self) -> tuple:
        return (type(self), self.nr, self.batch_frames, tuple(self.point_local))
