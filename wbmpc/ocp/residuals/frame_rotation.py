"""Frame orientation residual r = log3(R_ref^T R_frame) (3,) [rad]: swing-foot orientation (land flat,
with the planned yaw)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.kernels.residuals import (
    frame_rotation_jacobian,
    frame_rotation_jacobian_many,
    frame_rotation_rows,
    frame_rotation_rows_many,
    jacobian_blocks,
)
from wbmpc.ocp.residuals.base import (
    BatchedResidual,
    DataCollector,
    HorizonData,
    ResidualData,
    dense_jacobian_pattern,
)
from wbmpc.ocp.state import StateMultibody


class ResidualFrameRotation(BatchedResidual):
    """r(x) = log3(R_ref^T oRf) (the rotation from the reference to the frame, in the frame's axes),
    Rx = [Jlog3(R_ref^T oRf) J_local[3:], 0], J_local[3:] = oRfᵀ J_world_aligned[3:] the angular
    rows of the frame Jacobian.

    Both evaluations (node-wise and batched) compute the rows with the compiled kernels of
    :mod:`wbmpc.ocp.kernels.residuals`; within 1e-2 rad of a half turn of R_refᵀ oRf they use
    Pinocchio's log3 / Jlog3.

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        reference: reference rotation (3, 3), world frame; mutable through ``reference`` (a (3, 3)
            view of the stored row-major (9,) array: write it in place or assign it).
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, frame_id: int, reference: np.ndarray | None = None, nu: int = 0):
        self.state = state
        self.frame_id = int(frame_id)
        self.batch_frames = (self.frame_id,)
        self.batch_frame_rotations = True
        rotation = np.eye(3) if reference is None else np.array(reference, dtype=float).reshape(3, 3)
        self._reference = rotation.reshape(9).copy()
        self.nr = 3
        self.nu = nu
        self._ok = None  # (N,) scratch of the batched evaluation

    @property
    def reference(self) -> np.ndarray:
        """Reference rotation (3, 3), world frame (a view of the stored reference)."""
        return self._reference.reshape(3, 3)

    @reference.setter
    def reference(self, value) -> None:
        self._reference[:] = np.asarray(value, dtype=float).reshape(9)

    def _pinocchio_error(self, rotation: np.ndarray) -> np.ndarray:
        """R_refᵀ R (3, 3), for Pinocchio's log3 near a half turn."""
        return self.reference.T @ rotation

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        if not frame_rotation_rows(self._reference, placement.rotation, data.r):
            data.r[:] = pin.log3(self._pinocchio_error(placement.rotation))

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        model, pdata, nv = self.state.pinocchio, shared.pinocchio, self.state.nv
        J = pin.getFrameJacobian(model, pdata, self.frame_id, pin.LOCAL_WORLD_ALIGNED)
        rotation = pdata.oMf[self.frame_id].rotation
        if not frame_rotation_jacobian(self._reference, rotation, J[3:], data.Rx[:, :nv]):
            data.Rx[:, :nv] = pin.Jlog3(self._pinocchio_error(rotation)) @ rotation.T @ J[3:]

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    # ----------------------------------------------------------------- batched evaluation
    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return dense_jacobian_pattern(3, self.state.nv)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        rotations = horizon.frame_rotation[:, horizon.frame_slot[self.frame_id]]
        ok = self._scratch(mask.size)
        if not frame_rotation_rows_many(rotations, references, mask, r, ok):
            for k in np.flatnonzero(mask & ~ok):
                r[k] = pin.log3(references[k].reshape(3, 3).T @ rotations[k])

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        slot = horizon.frame_slot[self.frame_id]
        rotations, jacobians = horizon.frame_rotation[:, slot], horizon.frame_jacobian[:, slot]
        ok = self._scratch(mask.size)
        blocks = jacobian_blocks(values, 3)
        if not frame_rotation_jacobian_many(rotations, jacobians, references, mask, blocks, ok):
            for k in np.flatnonzero(mask & ~ok):
                error = references[k].reshape(3, 3).T @ rotations[k]
                blocks[k] = pin.Jlog3(error) @ rotations[k].T @ jacobians[k, 3:]

    def _scratch(self, n_nodes: int) -> np.ndarray:
        if self._ok is None or self._ok.size != n_nodes:
            self._ok = np.ones(n_nodes, dtype=np.bool_)
        return self._ok


def yaw_rotation(yaw: float) -> np.ndarray:
    """Rotation (3, 3) about the world z axis by ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
