"""Activation functions a(r) turning a residual r (nr,) into a scalar cost (Crocoddyl's convention).

Every activation here has a diagonal Hessian, so ``data.Arr`` stores only its diagonal (nr,).
All three are instances of one row-wise form, a = ½ Σ_i w_i e_i² with the dead-zone error
e_i = min(r_i − lb_i, 0) + max(r_i − ub_i, 0) (quadratics: lb = ub = 0); ``row_parameters()``
returns (w, lb, ub) so a cost sum can evaluate all its terms in one compiled pass. That form is
written once, :func:`wbmpc.ocp.kernels.costs.dead_zone`; calc and calcDiff here call it too.

- :class:`ActivationQuad`: a = ½‖r‖².
- :class:`ActivationWeightedQuad`: a = ½ rᵀ diag(w) r.
- :class:`ActivationQuadraticBarrier`: a = ½‖min(r − lb, 0)‖² + ½‖max(r − ub, 0)‖² (zero inside
  the bounds; the paper's eq. (22) control-bound barrier).
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.costs import dead_zone_rows


class ActivationData:
    """Buffers of one activation: a_value (scalar), Ar (nr,), Arr (nr,) diagonal of the Hessian."""

    def __init__(self, nr: int):
        self.a_value = 0.0
        self.Ar = np.zeros(nr)
        self.Arr = np.zeros(nr)


class _RowwiseDeadZone:
    """a(r) = ½ Σ_i w_i e_i², e_i = min(r_i − lb_i, 0) + max(r_i − ub_i, 0) (row parameters w, lb, ub)."""

    def __init__(self, w: np.ndarray, lb: np.ndarray, ub: np.ndarray):
        self._w, self._lb, self._ub = w, lb, ub
        self.nr = w.size

    def calc(self, data: ActivationData, r: np.ndarray) -> None:
        data.a_value = dead_zone_rows(np.asarray(r, dtype=float), self._w, self._lb, self._ub, data.Ar, data.Arr)

    def calcDiff(self, data: ActivationData, r: np.ndarray) -> None:
        dead_zone_rows(np.asarray(r, dtype=float), self._w, self._lb, self._ub, data.Ar, data.Arr)

    def createData(self) -> ActivationData:
        return ActivationData(self.nr)

    def row_parameters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._w.copy(), self._lb.copy(), self._ub.copy()


class ActivationQuad(_RowwiseDeadZone):
    """a(r) = ½‖r‖²."""

    def __init__(self, nr: int):
        super().__init__(np.ones(nr), np.zeros(nr), np.zeros(nr))


class ActivationWeightedQuad(_RowwiseDeadZone):
    """a(r) = ½ rᵀ diag(weights) r, weights (nr,) ≥ 0."""

    def __init__(self, weights: np.ndarray):
        weights = np.asarray(weights, dtype=float).ravel()
        if np.any(weights < 0) or not np.all(np.isfinite(weights)):
            raise ParameterError(f"activation weights={weights} must be finite and >= 0")
        self.weights = weights
        super().__init__(weights, np.zeros(weights.size), np.zeros(weights.size))


class ActivationQuadraticBarrier(_RowwiseDeadZone):
    """a(r) = ½‖min(r − lb, 0)‖² + ½‖max(r − ub, 0)‖²; zero while lb ≤ r ≤ ub.

    Args:
        lower: lower bounds lb (nr,).
        upper: upper bounds ub (nr,), ub ≥ lb.
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray):
        lower = np.asarray(lower, dtype=float).ravel()
        upper = np.asarray(upper, dtype=float).ravel()
        if lower.shape != upper.shape:
            raise ParameterError(f"barrier bounds lower{lower.shape} and upper{upper.shape} must have the same shape")
        if np.any(lower > upper):
            raise ParameterError(f"barrier bounds need lower <= upper, got lower={lower}, upper={upper}")
        self.lower = lower
        self.upper = upper
        super().__init__(np.ones(lower.size), lower, upper)
