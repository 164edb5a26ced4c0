"""Activation functions a(r) turning a residual r (nr,) into a scalar cost (Crocoddyl's convention).

Every activation here has a diagonal Hessian, so ``data.Arr`` stores only its diagonal (nr,).
All three are instances of one row-wise form, a = ½ Σ_i w_i e_i² with the dead-zone error
e_i = min(r_i − lb_i, 0) + max(r_i − ub_i, 0) (quadratics: lb = ub = 0); ``row_parameters()``
returns (w, lb, ub) so a cost sum can evaluate all its terms in one compiled pass.

- :class:`ActivationQuad`: a = ½‖r‖².
- :class:`ActivationWeightedQuad`: a = ½ rᵀ diag(w) r.
- :class:`ActivationQuadraticBarrier`: a = ½‖min(r − lb, 0)‖² + ½‖max(r − ub, 0)‖² (zero inside
  the bounds; the paper's eq. (22) control-bound barrier).
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError


class ActivationData:
    """Buffers of one activation: a_value (scalar), Ar (nr,), Arr (nr,) diagonal of the Hessian."""

    def __init__(self, nr: int):
        self.a_value = 0.0
        self.Ar = np.zeros(nr)
        self.Arr = np.zeros(nr)


class ActivationQuad:
    """a(r) = ½‖r‖²."""

    def __init__(self, nr: int):
        self.nr = nr

    def calc(self, data: ActivationData, r: np.ndarray) -> None:
        data.a_value = 0.5 * float(r @ r)

    def calcDiff(self, data: ActivationData, r: np.ndarray) -> None:
        data.Ar[:] = r
        data.Arr[:] = 1.0

    def createData(self) -> ActivationData:
        return ActivationData(self.nr)

    def row_parameters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.ones(self.nr), np.zeros(self.nr), np.zeros(self.nr)


class ActivationWeightedQuad:
    """a(r) = ½ rᵀ diag(weights) r, weights (nr,) ≥ 0."""

    def __init__(self, weights: np.ndarray):
        weights = np.asarray(weights, dtype=float).ravel()
        if np.any(weights < 0) or not np.all(np.isfinite(weights)):
            raise ParameterError(f"activation weights={weights} must be finite and >= 0")
        self.weights = weights
        self.nr = weights.size

    def calc(self, data: ActivationData, r: np.ndarray) -> None:
        data.Ar[:] = self.weights * r
        data.a_value = 0.5 * float(r @ data.Ar)

    def calcDiff(self, data: ActivationData, r: np.ndarray) -> None:
        np.multiply(self.weights, r, out=data.Ar)
        data.Arr[:] = self.weights

    def createData(self) -> ActivationData:
        return ActivationData(self.nr)

    def row_parameters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.weights.copy(), np.zeros(self.nr), np.zeros(self.nr)


class ActivationQuadraticBarrier:
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
        self.nr = lower.size

    def calc(self, data: ActivationData, r: np.ndarray) -> None:
        below = np.minimum(r - self.lower, 0.0)
        above = np.maximum(r - self.upper, 0.0)
        data.a_value = 0.5 * float(below @ below) + 0.5 * float(above @ above)

    def calcDiff(self, data: ActivationData, r: np.ndarray) -> None:
        below = r - self.lower
        above = r - self.upper
        data.Ar[:] = np.minimum(below, 0.0) + np.maximum(above, 0.0)
        data.Arr[:] = (below <= 0.0) | (above >= 0.0)

    def createData(self) -> ActivationData:
        return ActivationData(self.nr)

    def row_parameters(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.ones(self.nr), self.lower.copy(), self.upper.copy()
