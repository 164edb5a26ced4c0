"""Named cost terms: cost = Σ_i weight_i · a_i(r_i(x, u)) (Crocoddyl's CostModelSum).

Each term couples a residual (``wbmpc.residuals``) and an activation (``wbmpc.activations``);
the weight stays outside the residual so logs and plots show every term by name::

    costs = CostModelSum(state, nu)
    costs.add("state_regularization", CostModelResidual(ResidualState(state, x_ref, nu),
              ActivationWeightedQuad(w)), weight=1.0)

Derivatives use the Gauss-Newton approximation: Lx = Rxᵀ Ar, Lxx = Rxᵀ diag(Arr) Rx.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbmpc.activations import ActivationQuad
from wbmpc.errors import ParameterError
from wbmpc.residuals.base import DataCollector
from wbmpc.state import StateMultibody


class CostModelResidual:
    """One cost term a(r(x, u)); the activation defaults to ½‖r‖²."""

    def __init__(self, residual, activation=None):
        self.residual = residual
        self.activation = ActivationQuad(residual.nr) if activation is None else activation
        if self.activation.nr != residual.nr:
            raise ParameterError(
                f"activation dimension {self.activation.nr} does not match the residual dimension {residual.nr}"
            )
        self.nr = residual.nr

    def createData(self) -> "CostDataResidual":
        return CostDataResidual(self)


class CostDataResidual:
    def __init__(self, model: CostModelResidual):
        self.residual = model.residual.createData()
        self.activation = model.activation.createData()
        self.cost = 0.0


@dataclass
class CostItem:
    """A named, weighted term of a :class:`CostModelSum`; ``active`` switches it on and off."""

    name: str
    cost: CostModelResidual
    weight: float
    active: bool = True


class CostModelSum:
    """Sum of named weighted cost terms of a node.

    Args:
        state: the multibody state.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, nu: int):
        self.state = state
        self.nu = nu
        self.costs: dict[str, CostItem] = {}

    def add(self, name: str, cost: CostModelResidual, weight: float, active: bool = True) -> None:
        """Add a term; ``weight`` ≥ 0. Names are unique within a node."""
        if name in self.costs:
            raise ParameterError(f"cost name {name!r} is already used in this node (terms: {list(self.costs)})")
        if not (np.isfinite(weight) and weight >= 0):
            raise ParameterError(f"weight={weight} of cost {name!r} must be finite and >= 0")
        self.costs[name] = CostItem(name, cost, float(weight), active)

    def changeCostStatus(self, name: str, active: bool) -> None:
        if name not in self.costs:
            raise ParameterError(f"unknown cost {name!r} (terms: {list(self.costs)})")
        self.costs[name].active = bool(active)

    def createData(self) -> "CostDataSum":
        return CostDataSum(self)

    def calc(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> float:
        """Fill every active term's residual and activation; returns and stores the total cost."""
        total = 0.0
        for name, item in self.costs.items():
            term = data.terms[name]
            if not item.active:
                term.cost = 0.0
                continue
            item.cost.residual.calc(term.residual, x, u, shared)
            item.cost.activation.calc(term.activation, term.residual.r)
            term.cost = item.weight * term.activation.a_value
            total += term.cost
        data.cost = total
        return total

    def calcDiff(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        """Fill data.Lx (ndx,), Lu (nu,), Lxx, Lxu, Luu (Gauss-Newton). Needs calc first.

        The residual Jacobians of all terms are rows of one matrix R = [Rx Ru] (data.R), so the
        Hessian is a single product Rᵀ diag(w·Arr) R.
        """
        weights_Arr = data.weights_Arr
        weights_Ar = data.weights_Ar
        for name, item in self.costs.items():
            term = data.terms[name]
            rows = data.rows[name]
            if not item.active:
                weights_Arr[rows] = 0.0
                weights_Ar[rows] = 0.0
                data.R[rows] = 0.0
                continue
            rdata = term.residual
            item.cost.residual.calcDiff(rdata, x, u, shared)
            item.cost.activation.calcDiff(term.activation, rdata.r)
            np.multiply(term.activation.Arr, item.weight, out=weights_Arr[rows])
            np.multiply(term.activation.Ar, item.weight, out=weights_Ar[rows])
        R = data.R
        ndx = self.state.ndx
        if u is None or not self.nu:
            Rx = R[:, :ndx]
            np.matmul(Rx.T, weights_Ar, out=data.Lx)
            np.matmul(Rx.T, weights_Arr[:, None] * Rx, out=data.Lxx)
            return
        gradient = R.T @ weights_Ar
        hessian = R.T @ (weights_Arr[:, None] * R)
        data.Lx[:] = gradient[:ndx]
        data.Lu[:] = gradient[ndx:]
        data.Lxx[:] = hessian[:ndx, :ndx]
        data.Lxu[:] = hessian[:ndx, ndx:]
        data.Luu[:] = hessian[ndx:, ndx:]

    def term_costs(self, data: "CostDataSum") -> dict[str, float]:
        """Cost of every term by name (inactive terms report 0)."""
        return {name: term.cost for name, term in data.terms.items()}


class CostDataSum:
    """Buffers of a cost sum; every term's residual Jacobians are row views of ``R`` (nr_total, ndx + nu)."""

    def __init__(self, model: CostModelSum):
        ndx, nu = model.state.ndx, model.nu
        self.terms = {name: item.cost.createData() for name, item in model.costs.items()}
        nr_total = sum(item.cost.nr for item in model.costs.values())
        self.R = np.zeros((nr_total, ndx + nu))
        self.weights_Ar = np.zeros(nr_total)
        self.weights_Arr = np.zeros(nr_total)
        self.rows: dict[str, slice] = {}
        start = 0
        for name, item in model.costs.items():
            rows = slice(start, start + item.cost.nr)
            rdata = self.terms[name].residual
            self.R[rows, :ndx] = rdata.Rx
            self.R[rows, ndx:] = rdata.Ru
            rdata.Rx = self.R[rows, :ndx]
            rdata.Ru = self.R[rows, ndx:]
            self.rows[name] = rows
            start += item.cost.nr
        self.cost = 0.0
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
