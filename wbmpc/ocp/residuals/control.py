"""Control residual r = u − u_ref (nu,): torque regularisation (paper eq. 20) and bounds (eq. 22)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.kernels.residuals import subtract_rows, subtract_rows_many
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualControl(BatchedResidual):
    """r(u) = u − u_ref, Ru = I, Rx = 0. For a node without control (terminal) r = −u_ref.

    ``reference`` (nu,) [N·m] is mutable."""

    def __init__(self, state: StateMultibody, nu: int, u_reference: np.ndarray | None = None):
        self.state = state
        self.nu = nu
        self.nr = nu
        self._reference = np.zeros(nu) if u_reference is None else np.asarray(u_reference, dtype=float).copy()

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        if u is None:
            data.r[:] = -self._reference
        else:
            subtract_rows(u, self._reference, data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        """Ru = I is constant (written by createData)."""

    def createData(self) -> ResidualData:
        data = ResidualData(self.nr, self.state.ndx, self.nu)
        data.Ru[:] = np.eye(self.nu)
        return data

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        rows = np.arange(self.nu, dtype=np.int64)
        return rows, self.state.ndx + rows

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        subtract_rows_many(horizon.us, references, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        values[:] = 1.0
