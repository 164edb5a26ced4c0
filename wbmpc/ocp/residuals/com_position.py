"""Centre-of-mass residual r = c_world − c_reference (3,) [m] (terminal CoM, eqs. 23-24; the running CoM path)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.kernels.residuals import frame_jacobian_rows_many, subtract_rows, subtract_rows_many
from wbmpc.ocp.residuals.base import (
    BatchedResidual,
    DataCollector,
    HorizonData,
    ResidualData,
    dense_jacobian_pattern,
)
from wbmpc.ocp.state import StateMultibody

_XYZ = np.array([0, 1, 2], dtype=np.int64)


class ResidualCoMPosition(BatchedResidual):
    """r(x) = com − reference (world frame), Rx = [Jcom, 0].

    Node-wise it reads Pinocchio's ``com[0]`` and ``Jcom`` (computed by the dynamics' computeAllTerms);
    the batched evaluation reads the centre of mass and its Jacobian of the compiled horizon kinematics
    (``HorizonData.com``, ``com_jacobian``); both subtract the reference by the same compiled rows.

    Args:
        state: the multibody state.
        reference_world: CoM reference (3,) [m]; mutable through ``reference``.
        nu: control dimension.
    """

    batch_com = True

    def __init__(self, state: StateMultibody, reference_world: np.ndarray, nu: int):
        self.state = state
        self._reference = np.asarray(reference_world, dtype=float).reshape(3).copy()
        self.nr = 3
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        subtract_rows(shared.pinocchio.com[0], self._reference, data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        data.Rx[:, : self.state.nv] = shared.pinocchio.Jcom

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return dense_jacobian_pattern(3, self.state.nv)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        subtract_rows_many(horizon.com, references, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        frame_jacobian_rows_many(horizon.com_jacobian, _XYZ, mask, values)
