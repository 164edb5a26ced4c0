"""Control residual r = u − u_ref (nu,): torque regularisation (paper eq. 20) and bounds (eq. 22)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualControl:
    """r(u) = u − u_ref, Ru = I, Rx = 0. For a node without control (terminal) r = −u_ref."""

    def __init__(self, state: StateMultibody, nu: int, u_reference: np.ndarray | None = None):
        self.state = state
        self.nu = nu
        self.nr = nu
        self.reference = np.zeros(nu) if u_reference is None else np.asarray(u_reference, dtype=float).copy()

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        if u is None:
            data.r[:] = -self.reference
        else:
            np.subtract(u, self.reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        """Ru = I is constant (written by createData)."""

    def createData(self) -> ResidualData:
        data = ResidualData(self.nr, self.state.ndx, self.nu)
        data.Ru[:] = np.eye(self.nu)
        return data
