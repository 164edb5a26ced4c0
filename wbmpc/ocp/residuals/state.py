"""State residual r = x ⊖ x_ref (ndx,): posture and velocity regularisation (paper eq. 21)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.kernels.residuals import state_difference_many, state_jacobian_many
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualState(BatchedResidual):
    """r(x) = x ⊖ x_ref, Rx = ∂(x ⊖ x_ref)/∂x, Ru = 0.

    Args:
        state: the multibody state.
        x_reference: reference state (nx,), Pinocchio convention; mutable through ``reference``.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, x_reference: np.ndarray, nu: int):
        self.state = state
        self._reference = state.check_state("x_reference", x_reference).copy()
        self.nr = state.ndx
        self.nu = nu
        self._jacobian = None  # (nv, nv) scratch of the batched evaluation
        self._ok = None

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        self.state.diff(self._reference, x, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        nq, nv = self.state.nq, self.state.nv
        self.state.Jdiff_second_q(self._reference[:nq], x[:nq], out=data.Rx[:nv, :nv])

    def createData(self) -> ResidualData:
        data = ResidualData(self.nr, self.state.ndx, self.nu)
        nv = self.state.nv
        data.Rx[nv:, nv:] = np.eye(nv)  # constant block, written once
        return data

    # ----------------------------------------------------------------- batched evaluation
    def _base_dimension(self) -> int:
        """Rows/columns of Rx's configuration block that are not identity (6 for a free flyer)."""
        return 6 if self.state._compiled_difference else self.state.nv

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nb, ndx = self._base_dimension(), self.state.ndx
        rows = [i for i in range(nb) for _ in range(nb)] + list(range(nb, ndx))
        cols = [j for _ in range(nb) for j in range(nb)] + list(range(nb, ndx))
        return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        state = self.state
        ok = self._scratch(mask.size)[1]
        if not (state._compiled_difference and state_difference_many(references, horizon.xs, state.nq, mask, r, ok)):
            for k in np.flatnonzero(mask & ~ok if state._compiled_difference else mask):
                state.diff(references[k], horizon.xs[k], out=r[k])

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        state = self.state
        nq, nb = state.nq, self._base_dimension()
        J, ok = self._scratch(mask.size)
        if state._compiled_difference and state_jacobian_many(references, horizon.xs, nq, mask, nb, J, values, ok):
            return
        for k in np.flatnonzero(mask & ~ok if state._compiled_difference else mask):
            state.Jdiff_second_q(references[k, :nq], horizon.xs[k, :nq], out=J)
            values[k, :nb * nb] = J[:nb, :nb].ravel()
            values[k, nb * nb:] = 1.0

    def _scratch(self, n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
        if self._ok is None or self._ok.size != n_nodes:
            nv = self.state.nv
            self._jacobian = np.zeros((nv, nv))
            self._ok = np.ones(n_nodes, dtype=np.bool_)
        return self._jacobian, self._ok
