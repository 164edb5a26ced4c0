"""State residual r = x ⊖ x_ref (ndx,): posture and velocity regularisation (paper eq. 21)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualState:
    """r(x) = x ⊖ x_ref, Rx = ∂(x ⊖ x_ref)/∂x, Ru = 0.

    Args:
        state: the multibody state.
        x_reference: reference state (nx,), Pinocchio convention.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, x_reference: np.ndarray, nu: int):
        self.state = state
        self.reference = state.check_state("x_reference", x_reference).copy()
        self.nr = state.ndx
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        self.state.diff(self.reference, x, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        nq, nv = self.state.nq, self.state.nv
        self.state.Jdiff_second_q(self.reference[:nq], x[:nq], out=data.Rx[:nv, :nv])

    def createData(self) -> ResidualData:
        data = ResidualData(self.nr, self.state.ndx, self.nu)
        nv = self.state.nv
        data.Rx[nv:, nv:] = np.eye(nv)  # constant block, written once
        return data
