"""Named cost terms: cost = Σ_i weight_i · a_i(r_i(x, u)) (Crocoddyl's CostModelSum).

Each term couples a residual (``wbmpc.ocp.residuals``) and an activation (``wbmpc.ocp.activations``);
the weight stays outside the residual so logs and plots show every term by name::

    costs = CostModelSum(state, nu)
    costs.add("state_regularization", CostModelResidual(ResidualState(state, x_ref, nu),
              ActivationWeightedQuad(w)), weight=1.0)

Derivatives use the Gauss-Newton approximation: Lx = Rxᵀ Ar, Lxx = Rxᵀ diag(Arr) Rx. A node's
terms are evaluated together: their residuals are rows of one vector/Jacobian and every
activation is the row-wise dead-zone quadratic of :mod:`wbmpc.ocp.activations`.
"""

from __future__ import annotations

import math

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.activations import ActivationQuad
from wbmpc.ocp.kernels.costs import cost_rows_derivatives, cost_rows_value, dense_hessian_entries
from wbmpc.ocp.residuals.base import DataCollector
from wbmpc.ocp.state import StateMultibody


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


def _checked_weight(name: str, weight) -> float:
    """``weight`` as a float; ParameterError unless it is finite and >= 0."""
    if not (math.isfinite(weight) and weight >= 0):
        raise ParameterError(f"weight={weight} of cost {name!r} must be finite and >= 0")
    return float(weight)


class CostItem:
    """A named, weighted term of a :class:`CostModelSum`; ``active`` switches it on and off.

    The node-wise cost sum reads ``weight`` and ``active`` at each evaluation. A batched evaluator
    keeps every node's term factors in one array instead: it binds the item to its slot
    (:meth:`bind_scale`) and is told each change of :attr:`scale`, so setting ``weight`` or
    ``active`` is seen by its next evaluation without a sync.
    """

    __slots__ = ("name", "cost", "_weight", "_active", "_scale_owner", "_scale_index")

    def __init__(self, name: str, cost: CostModelResidual, weight: float, active: bool = True):
        self.name = name
        self.cost = cost
        self._weight = _checked_weight(name, weight)
        self._active = bool(active)
        self._scale_owner = None
        self._scale_index = -1

    def __repr__(self) -> str:
        return f"CostItem(name={self.name!r}, weight={self._weight}, active={self._active})"

    @property
    def weight(self) -> float:
        """Weight of the term (>= 0; ParameterError otherwise)."""
        return self._weight

    @weight.setter
    def weight(self, value: float) -> None:
        self._weight = _checked_weight(self.name, value)
        if self._scale_owner is not None:
            self._scale_owner.set_term_scale(self._scale_index, self.scale)

    @property
    def active(self) -> bool:
        return self._active

    @active.setter
    def active(self, value: bool) -> None:
        if value != self._active:  # receding-horizon updates set every node's activity each tick: mostly unchanged
            self._active = bool(value)
            if self._scale_owner is not None:
                self._scale_owner.set_term_scale(self._scale_index, self.scale)

    @property
    def scale(self) -> float:
        """The term's factor at its node: ``weight`` when active, 0 otherwise."""
        return self._weight if self._active else 0.0

    def bind_scale(self, owner, index: int) -> None:
        """From now on call ``owner.set_term_scale(index, scale)`` at each change of :attr:`scale`,
        and once now. A previous, different owner is told by ``owner.detach()`` (it no longer
        sees this item), as :meth:`~wbmpc.ocp.residuals.base.BatchedResidual.bind_reference` does."""
        previous = self._scale_owner
        if previous is not None and previous is not owner:
            previous.detach()
        self._scale_owner = owner
        self._scale_index = int(index)
        owner.set_term_scale(self._scale_index, self.scale)


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
        self.costs[name] = CostItem(name, cost, weight, active)

    def changeCostStatus(self, name: str, active: bool) -> None:
        if name not in self.costs:
            raise ParameterError(f"unknown cost {name!r} (terms: {list(self.costs)})")
        self.costs[name].active = bool(active)

    def createData(self) -> "CostDataSum":
        return CostDataSum(self)

    def calc(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> float:
        """Evaluate every active term; returns and stores the total cost (data.cost)."""
        term_scale = data.term_scale
        for j, item, residual, rdata in data.loop:
            if item.active:
                term_scale[j] = item.weight
                residual.calc(rdata, x, u, shared)
            else:
                term_scale[j] = 0.0
        data.cost = cost_rows_value(data.r, data.row_term, term_scale, data.w, data.lb, data.ub, data.term_cost)
        return data.cost

    def calcDiff(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        """Fill data.Lx (ndx,), Lu (nu,), Lxx, Lxu, Luu (Gauss-Newton). Needs calc first.

        The residual Jacobians of all terms are rows of one matrix R = [Rx Ru] (data.R), so the
        gradient and Hessian come from one compiled pass over the rows.
        """
        for _, item, residual, rdata in data.loop:
            if item.active:
                residual.calcDiff(rdata, x, u, shared)
        cost_rows_derivatives(data.r, data.R_values, data.R_row_start, data.R_cols, data.row_term, data.term_scale,
                              data.w, data.lb, data.ub, data.gradient, data.hessian)

    def reference_gradient(self, data: "CostDataSum", name: str) -> np.ndarray:
        """∂[Lx; Lu]/∂reference, shape (ndx + nu, nr), of the term ``name`` whose residual is
        r = g(x, u) − reference, after calcDiff (continuous cost, not scaled by a node's dt):
        −weight Rᵀ diag(a''(r)), a'' the activation's row curvature (w_i on a quadratic row or outside
        a dead zone, 0 inside it). Zero for an inactive term."""
        item = self.costs[name]
        rows = data.rows[name]
        if not item.active:
            return np.zeros((data.R.shape[1], item.cost.nr))
        r, w, lb, ub = data.r[rows], data.w[rows], data.lb[rows], data.ub[rows]
        curvature = np.where((lb == ub) | (r < lb) | (r > ub), w, 0.0)
        return -item.weight * data.R[rows].T * curvature

    def term_costs(self, data: "CostDataSum") -> dict[str, float]:
        """Cost of every term by name after calc (inactive terms report 0)."""
        return {name: float(data.term_cost[j]) for j, name in enumerate(self.costs)}


class CostDataSum:
    """Buffers of a cost sum; every term's residual Jacobians are row views of ``R`` (nr_total, ndx + nu)."""

    def __init__(self, model: CostModelSum):
        ndx, nu = model.state.ndx, model.nu
        self.terms = {name: item.cost.createData() for name, item in model.costs.items()}
        nr_total = sum(item.cost.nr for item in model.costs.values())
        n_terms = len(model.costs)
        self.r = np.zeros(nr_total)
        self.R = np.zeros((nr_total, ndx + nu))
        self.w = np.zeros(nr_total)
        self.lb = np.zeros(nr_total)
        self.ub = np.zeros(nr_total)
        self.row_term = np.zeros(nr_total, dtype=np.int64)
        self.term_scale = np.zeros(n_terms)
        self.term_cost = np.zeros(n_terms)
        self.rows: dict[str, slice] = {}
        start = 0
        for j, (name, item) in enumerate(model.costs.items()):
            rows = slice(start, start + item.cost.nr)
            rdata = self.terms[name].residual
            self.R[rows, :ndx] = rdata.Rx
            self.R[rows, ndx:] = rdata.Ru
            rdata.r = self.r[rows]
            rdata.Rx = self.R[rows, :ndx]
            rdata.Ru = self.R[rows, ndx:]
            self.w[rows], self.lb[rows], self.ub[rows] = item.cost.activation.row_parameters()
            self.row_term[rows] = j
            self.rows[name] = rows
            start += item.cost.nr
        # (term index, item, residual model, residual data) in order, for the evaluation loops
        self.loop = [(j, item, item.cost.residual, self.terms[name].residual)
                     for j, (name, item) in enumerate(model.costs.items())]
        n = ndx + nu  # R as the dense row pattern of cost_rows_derivatives
        self.R_values = self.R.reshape(-1)
        self.R_row_start = np.arange(0, nr_total * n + 1, n, dtype=np.int64)
        self.R_cols = np.tile(np.arange(n, dtype=np.int64), nr_total)
        self.hessian_entries = dense_hessian_entries(n if nr_total else 0, ndx)  # every entry (R is dense)
        self.gradient = np.zeros(ndx + nu)
        self.hessian = np.zeros((ndx + nu, ndx + nu))
        self.cost = 0.0
        self.Lx = self.gradient[:ndx]
        self.Lu = self.gradient[ndx:]
        self.Lxx = self.hessian[:ndx, :ndx]
        self.Lxu = self.hessian[:ndx, ndx:]
        self.Luu = self.hessian[ndx:, ndx:]
